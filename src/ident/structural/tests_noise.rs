//! Noisy data: honest uncertainties and order selection, over seeded replicates.

use std::f64::consts::PI;

use nalgebra::Matrix3;

use super::tests::{Truth, fit, random_gain, synthesise};
use super::*;
use crate::rng::Rng;

/// Running check of reported against empirical scatter for one scalar parameter.
#[derive(Default)]
struct Scatter {
    errors: Vec<f64>,
    reported: Vec<f64>,
}

impl Scatter {
    fn push(&mut self, estimate: f64, truth: f64, std: f64) {
        self.errors.push(estimate - truth);
        self.reported.push(std);
    }

    /// Empirical std (about the truth) over mean reported std.
    fn ratio(&self) -> f64 {
        let n = self.errors.len() as f64;
        let emp = (self.errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        emp / (self.reported.iter().sum::<f64>() / n)
    }

    /// How many errors lie within 3 reported sigmas.
    fn within_3_sigma(&self) -> usize {
        self.errors
            .iter()
            .zip(&self.reported)
            .filter(|(e, s)| e.abs() <= 3.0 * **s)
            .count()
    }
}

/// Checks every parameter's ratio within 25 % and the 3-sigma coverage over all of them.
fn assert_honest(name: &str, params: &[Scatter]) {
    let mut inside = 0;
    let mut total = 0;
    for (i, p) in params.iter().enumerate() {
        let r = p.ratio();
        eprintln!("{name} parameter {i}: empirical / reported std = {r:.3}");
        assert!((0.75..=1.25).contains(&r), "{name} parameter {i}: ratio {r}");
        inside += p.within_3_sigma();
        total += p.errors.len();
    }
    let coverage = inside as f64 / total as f64;
    eprintln!("{name}: {inside} of {total} within 3 sigma ({coverage:.4})");
    assert!(coverage >= 0.985, "{name}: coverage {coverage}");
}

#[test]
fn order0_uncertainties_are_honest() {
    let mut rng = Rng::new(100);
    let k = random_gain(&mut rng);
    let tau = 0.003_7;
    let truth = Truth::gain_delay(k, tau);
    let mut params: Vec<Scatter> = (0..10).map(|_| Scatter::default()).collect();
    for _ in 0..200 {
        let data = synthesise(&truth, &mut rng, 1.0);
        let fit = fit(&data, OrderChoice::Fixed(0)).expect("fit");
        for e in 0..9 {
            let (i, j) = (e / 3, e % 3);
            params[e].push(fit.k[i][j], k[(i, j)], fit.k_std[i][j]);
        }
        params[9].push(fit.tau_s, tau, fit.tau_std_s);
    }
    assert_honest("order 0", &params);
}

#[test]
fn order1_uncertainties_are_honest() {
    let mut rng = Rng::new(200);
    let k = random_gain(&mut rng);
    let (t, tau) = (0.004, 0.002_9);
    let truth = Truth {
        num: vec![k],
        den: vec![t],
        tau,
    };
    // K's diagonal, one coupling, T and tau.
    let mut params: Vec<Scatter> = (0..5).map(|_| Scatter::default()).collect();
    for _ in 0..120 {
        let data = synthesise(&truth, &mut rng, 1.0);
        let fit = fit(&data, OrderChoice::Fixed(1)).expect("fit");
        for i in 0..3 {
            params[i].push(fit.k[i][i], k[(i, i)], fit.k_std[i][i]);
        }
        params[3].push(fit.denominator[0], t, fit.denominator_std[0]);
        params[4].push(fit.tau_s, tau, fit.tau_std_s);
    }
    assert_honest("order 1", &params);
}

fn auto_fit(truth: &Truth, seed: u64, criterion: InformationCriterion) -> StructuralFit {
    let mut rng = Rng::new(seed);
    let data = synthesise(truth, &mut rng, 1.0);
    let input = ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::Variance(&data.2),
        offset_hz: None,
    };
    let settings = StructuralSettings {
        criterion,
        ..Default::default()
    };
    fit_structure(&input, OrderChoice::Auto, &settings).expect("fit")
}

#[test]
fn bic_chooses_order_0_for_a_gain_and_delay() {
    let mut rng = Rng::new(300);
    let (mut bic_zero, mut aic_zero) = (0, 0);
    for seed in 0..20 {
        let truth = Truth::gain_delay(random_gain(&mut rng), rng.uniform_in(0.002, 0.006));
        let bic = auto_fit(&truth, 1000 + seed, InformationCriterion::Bic);
        let aic = auto_fit(&truth, 1000 + seed, InformationCriterion::Aic);
        assert_eq!(bic.candidates.len(), 5);
        bic_zero += usize::from(bic.order == 0);
        aic_zero += usize::from(aic.order == 0);
        let c = &bic.candidates;
        // From order 2 on the previous fit times a far pole is a start: chi2 cannot rise.
        for n in 2..c.len() {
            assert!(c[n].chi2 <= c[n - 1].chi2 + 1e-9, "seed {seed}: {c:?}");
        }
        eprintln!(
            "seed {seed}: BIC order {}, AIC order {}, chi2 {:.1} {:.1} {:.1}, dof {}",
            bic.order, aic.order, c[0].chi2, c[1].chi2, c[2].chi2, bic.dof
        );
    }
    eprintln!("order 0 chosen: BIC {bic_zero} of 20, AIC {aic_zero} of 20");
    assert!(bic_zero >= 19, "BIC chose order 0 in {bic_zero} of 20 seeds");
    assert!(aic_zero <= bic_zero);
}

#[test]
fn bic_finds_the_sensor_pole() {
    let mut rng = Rng::new(400);
    for t in [0.004, 0.002] {
        for seed in 0..8 {
            let k: Matrix3<f64> = random_gain(&mut rng);
            let tau = rng.uniform_in(0.002, 0.006);
            let truth = Truth {
                num: vec![k],
                den: vec![t],
                tau,
            };
            let fit = auto_fit(&truth, 2000 + seed, InformationCriterion::Bic);
            eprintln!(
                "T {t}: order {}, T {:?}, tau {:.6} (true {tau:.6})",
                fit.order, fit.denominator, fit.tau_s
            );
            assert!(fit.order >= 1, "T = {t}, seed {seed}: order {}", fit.order);
            if fit.order == 1 {
                let rel = (fit.denominator[0] - t).abs() / t;
                assert!(rel < 0.1, "T = {t}: fitted {}", fit.denominator[0]);
            }
        }
    }
}

/// A sensor behind a second-order low-pass above the band (Butterworth, 100 Hz; the band ends at
/// 40 Hz, where it bends the gain by 1.3 %): the order-2 fit's best start is often its mirror, a
/// pair in the right half plane with a longer delay (same magnitude response). The mirror of an
/// unstable best is refined too, so the stable pair is found and chosen, at the filter's natural
/// frequency, the delay within a millisecond. Checked: without that mirror the first seed is
/// fitted at order 4, the filter's pair with a spurious one at 33 Hz (damping 0.001).
#[test]
fn bic_finds_a_second_order_filter_above_the_band() {
    let mut rng = Rng::new(450);
    for seed in 0..8 {
        let fit = assert_filter_pair_found(&mut rng, 2500 + seed);
        // An all-pole filter: its zeros do not lead beyond the self-check's bound (`zeros_lead`
        // stays quiet; measured: seed 4 leads by 2.06 of its deviations, the delay 2.8 long).
        let [lag, std] = fit.zeros_lag_s.expect("order 2 has N_1");
        assert!(
            -lag <= crate::ident::selfcheck::ZEROS_LEAD_DEVIATIONS * std,
            "seed {seed}: zeros lead by {} +- {std} s",
            -lag
        );
    }
}

#[test]
#[ignore = "timing: cargo test --release --lib structural -- --ignored --nocapture"]
fn timing_of_order_0_and_auto() {
    let mut rng = Rng::new(500);
    let truth = Truth {
        num: vec![random_gain(&mut rng)],
        den: vec![0.003],
        tau: 0.004,
    };
    let data = synthesise(&truth, &mut rng, 1.0);
    let time = |order| {
        let start = std::time::Instant::now();
        let reps = 5;
        for _ in 0..reps {
            fit(&data, order).expect("fit");
        }
        start.elapsed().as_secs_f64() / f64::from(reps)
    };
    let (t0, ta) = (time(OrderChoice::Fixed(0)), time(OrderChoice::Auto));
    eprintln!("order 0: {:.2} ms, auto: {:.2} ms", t0 * 1e3, ta * 1e3);
    if !cfg!(debug_assertions) {
        assert!(t0 < 0.010 && ta < 0.100, "order 0 {t0} s, auto {ta} s");
    }
}

/// The same filter on other seeds: on two of sixteen the order-2 fit's best is an unstable pair
/// (one real pole in each half plane, a longer delay) that fits a little better than the true
/// stable pair, whose magnitude its mirror image does not reach. The data do not prefer it
/// significantly (Vuong's test), so the stable pair is the order's fit, and is chosen. Checked:
/// when the unstable best always wins, seed 2602 keeps order 0 with the filter's lag in its delay
/// (2.29 ms long). The order-2 candidate says so: the unstable fit's chi2 (below its own) and the
/// data's preference for it (positive, at most three deviations); where the best fit was stable
/// nothing is said, and never at order 0. A change of order reusing the fitted orders says it too.
#[test]
fn a_stable_pair_is_kept_when_an_unstable_one_fits_no_better() {
    let mut rng = Rng::new(451);
    let mut set_aside = 0;
    for seed in 0..16 {
        let (fit, truth) = filter_pair_fit(&mut rng, 2600 + seed);
        assert_eq!(fit.candidates[0].unstable_set_aside, None, "seed {seed}");
        let second = &fit.candidates[2];
        if let Some(aside) = second.unstable_set_aside {
            set_aside += 1;
            assert!(second.stable, "seed {seed}: {second:?}");
            assert!(aside.chi2 < second.chi2, "seed {seed}: {second:?}");
            assert!(
                aside.vuong_z > 0.0 && aside.vuong_z <= 3.0,
                "seed {seed}: {aside:?}"
            );
            let words = aside.to_string();
            assert!(words.contains("set aside") && words.contains(" 3 "), "{words}");
            let data = synthesise(&truth, &mut Rng::new(2600 + seed), 1.0);
            let input = ResponseEstimate {
                frequency_hz: &data.0,
                response: &data.1,
                weights: Weights::Variance(&data.2),
                offset_hz: None,
            };
            let fixed = OrderChoice::Fixed(2);
            let refit = refit_structure(&input, fixed, &StructuralSettings::default(), &fit);
            let refit = refit.expect("order change");
            assert!(refit.fitted.from_scratch(), "seed {seed}: models reused");
            assert_eq!(refit.candidates[2].unstable_set_aside, Some(aside), "seed {seed}");
        }
    }
    assert_eq!(set_aside, 2, "the two seeds whose best pair is unstable");
}

/// Fits a gain and delay (drawn from `rng`) behind a 100 Hz Butterworth pair on data of `seed`,
/// and asserts order 2, stable, the pair at 100 +- 15 Hz and the delay within a millisecond.
fn assert_filter_pair_found(rng: &mut Rng, seed: u64) -> StructuralFit {
    filter_pair_fit(rng, seed).0
}

/// [`assert_filter_pair_found`], with the truth drawn.
fn filter_pair_fit(rng: &mut Rng, seed: u64) -> (StructuralFit, Truth) {
    let w = 2.0 * PI * 100.0;
    let zeta = std::f64::consts::FRAC_1_SQRT_2;
    let tau = rng.uniform_in(0.002, 0.006);
    let truth = Truth {
        num: vec![random_gain(rng)],
        den: vec![2.0 * zeta / w, 1.0 / (w * w)],
        tau,
    };
    let fit = auto_fit(&truth, seed, InformationCriterion::Bic);
    eprintln!(
        "seed {seed}: order {}, poles {:?}, tau {:.6} +- {:.6} (true {tau:.6})",
        fit.order, fit.poles, fit.tau_s, fit.tau_std_s
    );
    assert_eq!(fit.order, 2, "seed {seed}: {:?}", fit.candidates);
    assert!(fit.stable, "seed {seed}");
    // From order 2 the delay trades with the numerator's first coefficient (`admissible`, rule 4):
    // its stated deviation is not calibrated here (2.8 and 3.6 of them off on two of eight seeds,
    // measured), so only its size is checked.
    assert!((fit.tau_s - tau).abs() < 1e-3, "seed {seed}: tau {}", fit.tau_s);
    let natural_hz = fit.poles[0][0].hypot(fit.poles[0][1]) / (2.0 * PI);
    assert!((natural_hz - 100.0).abs() < 15.0, "seed {seed}: {natural_hz} Hz");
    (fit, truth)
}

/// A response with a real right-half-plane pole at 30 Hz (a lead: what angles behind a filter
/// give): the data prefer the unstable order-1 fit significantly to the best stable one, which
/// must put the lead into a shorter delay, so the order's candidate stays the unstable fit and is
/// rejected for it; the stable fit is not swapped in. Checked: when the stable fit always wins,
/// the first seed's order-1 candidate is stable.
#[test]
fn an_unstable_fit_the_data_prefer_is_not_swapped_for_a_stable_one() {
    let mut rng = Rng::new(452);
    let p = 2.0 * PI * 30.0;
    for seed in 0..4 {
        let truth = Truth {
            num: vec![random_gain(&mut rng)],
            den: vec![-1.0 / p],
            tau: 0.004,
        };
        let fit = auto_fit(&truth, 2700 + seed, InformationCriterion::Bic);
        let first = &fit.candidates[1];
        eprintln!(
            "seed {seed}: order {}, candidates {:?}",
            fit.order, fit.candidates
        );
        assert!(!first.stable, "seed {seed}: {first:?}");
        assert_eq!(first.unstable_set_aside, None, "seed {seed}: kept, not set aside");
        assert_eq!(
            first.rejected,
            Some(admissible::Rejection::Unstable),
            "seed {seed}"
        );
        assert_ne!(fit.order, 1, "seed {seed}");
    }
}

/// Vuong's statistic on known differences: `[1, 2, 3, 4]` has sum 10, sample variance 5/3 and so
/// `z = 10 / sqrt(4 * 5/3) = 3.873`; negated, its sign flips; counted with a correlation of 2,
/// it shrinks by `sqrt(2)`. Equal positive differences are evidence without spread (`+inf`), zeros
/// none; a NaN or a single difference gives 0.
#[test]
fn vuong_z_on_known_differences() {
    let z = rational::vuong_z(&[1.0, 2.0, 3.0, 4.0], 1.0);
    assert!((z - 10.0 / (4.0_f64 * 5.0 / 3.0).sqrt()).abs() < 1e-12, "{z}");
    assert!((rational::vuong_z(&[-1.0, -2.0, -3.0, -4.0], 1.0) + z).abs() < 1e-12);
    assert!((rational::vuong_z(&[1.0, 2.0, 3.0, 4.0], 2.0) - z / 2.0_f64.sqrt()).abs() < 1e-12);
    let up = rational::vuong_z(&[0.5; 5], 1.0);
    assert!(up.is_infinite() && up > 0.0, "{up}");
    let down = rational::vuong_z(&[-0.5; 5], 1.0);
    assert!(down.is_infinite() && down < 0.0, "{down}");
    for none in [&[0.0; 5][..], &[1.0, f64::NAN, 2.0], &[3.0]] {
        let z = rational::vuong_z(none, 1.0);
        assert!(z.abs() < f64::MIN_POSITIVE, "{none:?}: {z}");
    }
}
