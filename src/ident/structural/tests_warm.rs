//! Refitting from a previous fit: exact reuse for an order change, the cold answer for nearby
//! data, and a safe result from a poor start.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::tests::{Truth, band, element_std, random_gain, synthesise};
use super::*;
use crate::rng::Rng;

type Data = (Vec<f64>, Vec<Matrix3<Complex64>>, Vec<Matrix3<f64>>);

fn input(data: &Data) -> ResponseEstimate<'_> {
    ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::Variance(&data.2),
        offset_hz: None,
    }
}

fn cold(data: &Data, order: OrderChoice) -> StructuralFit {
    fit_structure(&input(data), order, &StructuralSettings::default()).expect("cold fit")
}

fn warm(data: &Data, order: OrderChoice, previous: &StructuralFit) -> StructuralFit {
    refit_structure(&input(data), order, &StructuralSettings::default(), previous).expect("refit")
}

/// The fit without its kept models (a refit keeps orders above the one asked for).
fn reported(mut fit: StructuralFit) -> StructuralFit {
    fit.fitted = FittedOrders::default();
    fit
}

/// A sensor with a 3 ms lag and a 2 ms delay.
fn lagged(rng: &mut Rng) -> Truth {
    Truth {
        num: vec![random_gain(rng)],
        den: vec![0.003],
        tau: 0.002,
    }
}

#[test]
fn an_order_change_on_the_same_data_reuses_the_fits_exactly() {
    let mut rng = Rng::new(31);
    let data = synthesise(&lagged(&mut rng), &mut rng, 1.0);
    let auto = cold(&data, OrderChoice::Auto);
    assert_eq!(auto.fitted.len(), MAX_ORDER + 1);
    assert!(auto.fitted.from_scratch());
    for n in 0..=MAX_ORDER {
        let reused = warm(&data, OrderChoice::Fixed(n), &auto);
        assert_eq!(reused.fitted.len(), MAX_ORDER + 1, "every order is kept");
        assert!(reused.fitted.from_scratch());
        assert_eq!(
            reported(reused),
            reported(cold(&data, OrderChoice::Fixed(n))),
            "order {n}"
        );
    }
    // Upwards: the orders above the kept ones are fitted as a cold fit fits them.
    let first = cold(&data, OrderChoice::Fixed(1));
    assert_eq!(first.fitted.len(), 2);
    assert_eq!(warm(&data, OrderChoice::Auto, &first), auto);
    let second = warm(&data, OrderChoice::Fixed(2), &auto);
    assert_eq!(second.fitted.len(), MAX_ORDER + 1);
    assert_eq!(warm(&data, OrderChoice::Auto, &second), auto);
    // Down to order 0 and back: nothing refitted, nothing lost.
    let zero = warm(&data, OrderChoice::Fixed(0), &second);
    assert_eq!(warm(&data, OrderChoice::Auto, &zero), auto);
}

/// How close a refined fit must come to the fit from scratch, in standard deviations: the
/// refinement stops once the predicted gain in chi2 is below 0.01, i.e. about 0.1 standard
/// deviation from the optimum in the worst direction.
const REFINED_WITHIN_STD: f64 = 0.15;

#[test]
fn nearby_data_give_the_cold_answer_on_the_determined_orders() {
    let mut rng = Rng::new(32);
    let truth = lagged(&mut rng);
    let before = synthesise(&truth, &mut rng, 1.0);
    // A retune: the estimate moves by a fraction of its noise (here 30 %).
    let mut after = before.clone();
    for (w, &f) in after.1.iter_mut().zip(&before.0) {
        let sd = 0.3 * element_std(f) / std::f64::consts::SQRT_2;
        *w += Matrix3::from_fn(|_, _| Complex64::new(sd * rng.normal(), sd * rng.normal()));
    }
    let previous = cold(&before, OrderChoice::Auto);
    let refit = warm(&after, OrderChoice::Auto, &previous);
    assert!(!refit.fitted.from_scratch(), "refined from a fit to other data");
    assert!(!warm(&after, OrderChoice::Fixed(1), &refit).fitted.from_scratch());
    let fresh = cold(&after, OrderChoice::Auto);
    assert_eq!(refit.order, fresh.order, "chosen order");
    assert_eq!(refit.order, 1, "the true order");
    for i in 0..3 {
        for j in 0..3 {
            let d = (refit.k[i][j] - fresh.k[i][j]).abs();
            let limit = REFINED_WITHIN_STD * fresh.k_std[i][j];
            assert!(d < limit, "K[{i}][{j}] off by {d:e} (limit {limit:e})");
        }
    }
    let d_tau = (refit.tau_s - fresh.tau_s).abs();
    assert!(
        d_tau < REFINED_WITHIN_STD * fresh.tau_std_s,
        "tau off by {d_tau:e}"
    );
    for (r, f) in refit.candidates.iter().zip(&fresh.candidates) {
        // Far below the criterion's penalty per parameter (ln(18 n_bins) ~ 8.7).
        let tolerance = if r.order <= 1 { 0.05 } else { 0.5 };
        // Above the true order the fits are over-parameterised, their chi2 surface has many
        // optima close together, and which one a search from scratch reaches depends on its
        // starts: there the refinement must not end worse (it may end better, as the previous
        // optimum's neighbourhood holds one the cold starts miss: measured, 6493.3 against 6505.3
        // at order 3 once order 2's fits compared stable and unstable ones).
        let excess = if r.order <= refit.order {
            (r.chi2 - f.chi2).abs()
        } else {
            r.chi2 - f.chi2
        };
        assert!(
            excess <= tolerance,
            "order {}: chi2 {} from the previous fit, {} cold",
            r.order,
            r.chi2,
            f.chi2
        );
    }
}

#[test]
fn a_poor_start_still_gives_nested_fits_and_the_right_gain() {
    let mut rng = Rng::new(33);
    // The previous fit is of another block: a 40 ms delay and no lag.
    let other = Truth::gain_delay(random_gain(&mut rng) * 1.5, 0.040);
    let previous = cold(&synthesise(&other, &mut rng, 1.0), OrderChoice::Auto);
    let truth = lagged(&mut rng);
    let data = synthesise(&truth, &mut rng, 1.0);
    let refit = warm(&data, OrderChoice::Auto, &previous);
    for pair in refit.candidates.windows(2).skip(1) {
        assert!(
            pair[1].chi2 <= pair[0].chi2 * (1.0 + 1e-9),
            "order {} chi2 {} above order {}'s {}",
            pair[1].order,
            pair[1].chi2,
            pair[0].order,
            pair[0].chi2
        );
    }
    assert_eq!(refit.order, 1);
    for i in 0..3 {
        for j in 0..3 {
            let d = (refit.k[i][j] - truth.num[0][(i, j)]).abs();
            assert!(d < 4.0 * refit.k_std[i][j], "K[{i}][{j}] off by {d:e}");
        }
    }
}

#[test]
fn a_narrower_band_rescales_the_previous_models() {
    let mut rng = Rng::new(34);
    let truth = lagged(&mut rng);
    let data = synthesise(&truth, &mut rng, 1.0);
    let previous = cold(&data, OrderChoice::Fixed(1));
    // The band cut at 30 Hz: another omega_ref for the normalised coefficients.
    let keep = band().iter().take_while(|&&f| f <= 30.0).count();
    let narrow: Data = (
        data.0[..keep].to_vec(),
        data.1[..keep].to_vec(),
        data.2[..keep].to_vec(),
    );
    let refit = warm(&narrow, OrderChoice::Fixed(1), &previous);
    let fresh = cold(&narrow, OrderChoice::Fixed(1));
    let d_lag = (refit.denominator[0] - fresh.denominator[0]).abs();
    let limit = REFINED_WITHIN_STD * fresh.denominator_std[0];
    assert!(d_lag < limit, "lag off by {d_lag:e} (limit {limit:e})");
    assert!(
        (refit.chi2 - fresh.chi2).abs() < 0.05,
        "{} vs {}",
        refit.chi2,
        fresh.chi2
    );
}

/// A refit refuses what a cold fit refuses, with the same error, after a fit it could start from:
/// an order above the highest, too few bins for the order, a delay range not ordered, an
/// estimate of another length.
#[test]
fn a_refit_refuses_what_a_cold_fit_refuses() {
    let mut rng = Rng::new(37);
    let data = synthesise(&lagged(&mut rng), &mut rng, 1.0);
    let auto = cold(&data, OrderChoice::Auto);
    let few: Data = (data.0[..2].to_vec(), data.1[..2].to_vec(), data.2[..2].to_vec());
    let short = ResponseEstimate {
        response: &data.1[..data.1.len() - 1],
        ..input(&data)
    };
    let reversed = StructuralSettings {
        tau_min_s: 0.01,
        tau_max_s: -0.01,
        ..StructuralSettings::default()
    };
    let default = StructuralSettings::default();
    let cases = [
        (input(&data), OrderChoice::Fixed(MAX_ORDER + 1), default),
        (input(&few), OrderChoice::Fixed(MAX_ORDER), default),
        (input(&data), OrderChoice::Auto, reversed),
        (short, OrderChoice::Auto, default),
    ];
    for (estimate, order, settings) in cases {
        let from_cold = fit_structure(&estimate, order, &settings).expect_err("cold");
        let from_warm = refit_structure(&estimate, order, &settings, &auto).expect_err("warm");
        assert_eq!(from_warm, from_cold, "{order:?}");
        // And again from a refit on these very data (its placing kept).
        let same = refit_structure(&input(&data), OrderChoice::Fixed(0), &default, &auto).unwrap();
        let again = refit_structure(&estimate, order, &settings, &same).expect_err("again");
        assert_eq!(again, from_cold, "{order:?}");
    }
}
