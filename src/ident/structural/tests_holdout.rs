//! Held-out prediction ([`held_out_chi2`]) and admissibility rule 7, on synthetic estimates whose
//! truth is known: two independent halves of the same response.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::admissible::{Rejection, not_predictive};
use super::tests::{Truth, random_gain, synthesise};
use super::*;
use crate::rng::Rng;

type Estimate = (Vec<f64>, Vec<Matrix3<Complex64>>, Vec<Matrix3<f64>>);

fn estimate(data: &Estimate) -> ResponseEstimate<'_> {
    ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::Variance(&data.2),
        offset_hz: None,
    }
}

fn held_out(a: &Estimate, b: &Estimate) -> [Option<f64>; MAX_ORDER + 1] {
    held_out_chi2(&estimate(a), &estimate(b), &StructuralSettings::default()).expect("held out")
}

/// The whole record from its two halves: the mean response, half the variance.
fn whole(a: &Estimate, b: &Estimate) -> Estimate {
    let w =
        a.1.iter()
            .zip(&b.1)
            .map(|(x, y)| (x + y) * Complex64::from(0.5))
            .collect();
    (a.0.clone(), w, a.2.iter().map(|v| v * 0.5).collect())
}

fn pick<T: Copy>(keep: &[usize], v: &[T]) -> Vec<T> {
    keep.iter().map(|&k| v[k]).collect()
}

fn lag_truth(rng: &mut Rng) -> Truth {
    Truth {
        num: vec![random_gain(rng)],
        den: vec![0.004],
        tau: 0.003,
    }
}

#[test]
fn rule_7_keeps_an_order_only_below_every_lower_order() {
    assert_eq!(
        not_predictive(0, &[Some(5.0)]),
        None,
        "order 0 has no lower order"
    );
    assert_eq!(not_predictive(2, &[Some(10.0), Some(9.0), Some(8.5)]), None);
    assert_eq!(
        not_predictive(2, &[Some(10.0), Some(9.0), Some(9.5)]),
        Some(Rejection::NotPredictive {
            held_out_chi2: Some(9.5),
            lower_order: 1,
            lower_held_out_chi2: 9.0,
        })
    );
    assert_eq!(
        not_predictive(1, &[Some(10.0), Some(10.0)]),
        Some(Rejection::NotPredictive {
            held_out_chi2: Some(10.0),
            lower_order: 0,
            lower_held_out_chi2: 10.0,
        }),
        "a tie is no evidence"
    );
    assert_eq!(
        not_predictive(3, &[Some(10.0), None, Some(12.0), None]),
        Some(Rejection::NotPredictive {
            held_out_chi2: None,
            lower_order: 0,
            lower_held_out_chi2: 10.0,
        }),
        "an order not fitted to both halves is not validated"
    );
    assert_eq!(
        not_predictive(1, &[None, Some(3.0)]),
        None,
        "nothing to compare with"
    );
}

#[test]
fn exact_halves_on_different_bins_predict_each_other_exactly() {
    // Noise-free halves of a first-order block; the second on every other bin and a lower top,
    // so its models are normalised to another reference frequency.
    let mut rng = Rng::new(7);
    let truth = lag_truth(&mut rng);
    let a = synthesise(&truth, &mut rng, 0.0);
    let keep: Vec<usize> = (0..a.0.len() - 40).step_by(2).collect();
    let b: Estimate = (pick(&keep, &a.0), pick(&keep, &a.1), pick(&keep, &a.2));
    let h = held_out(&a, &b);
    let (h0, h1) = (h[0].expect("order 0"), h[1].expect("order 1"));
    assert!(h0 > 1e3, "order 0 cannot hold the lag: {h0}");
    assert!(
        h1 < 1e-6 * h0,
        "order 1 predicts the other half exactly: {h1} vs {h0}"
    );
}

#[test]
fn noise_fitting_orders_fail_rule_7_and_a_real_pole_passes_it() {
    let mut rng = Rng::new(77);
    let seeds = 16;
    let (mut passed_high, mut auto_zero, mut expected) = (0, 0, Vec::new());
    for _ in 0..seeds {
        let truth = Truth::gain_delay(random_gain(&mut rng), rng.uniform_in(0.002, 0.006));
        let (a, b) = (
            synthesise(&truth, &mut rng, 1.0),
            synthesise(&truth, &mut rng, 1.0),
        );
        let h = held_out(&a, &b);
        assert!(
            h.iter().all(Option::is_some),
            "every order fitted to both halves: {h:?}"
        );
        // Each half's model misses the other half's estimate by that half's noise (18 real
        // data per bin) plus its own estimation error (p real parameters).
        let bins = a.0.len() as f64;
        expected.push(h[0].unwrap_or(f64::NAN) / (2.0 * (18.0 * bins + 10.0)));
        passed_high += (2..=MAX_ORDER)
            .filter(|&n| not_predictive(n, &h).is_none())
            .count();
        let full = whole(&a, &b);
        let settings = StructuralSettings {
            held_out_chi2: Some(h),
            ..StructuralSettings::default()
        };
        let fit = fit_structure(&estimate(&full), OrderChoice::Auto, &settings).expect("fit");
        auto_zero += usize::from(fit.order == 0);
        assert!(
            fit.candidates.iter().all(|c| c.held_out_chi2.is_some()),
            "every candidate carries its held-out chi2"
        );
    }
    let mean = expected.iter().sum::<f64>() / seeds as f64;
    eprintln!(
        "held-out chi2 of order 0 over its expectation: {mean:.4}; orders 2-4 passing rule 7: {passed_high} of {}",
        3 * seeds
    );
    // Std of the mean: sqrt(2 / (36 bins)) / sqrt(16) ~ 0.3 %.
    assert!(
        (mean - 1.0).abs() < 0.02,
        "held-out chi2 of the true order: {mean}"
    );
    assert!(
        passed_high * 10 <= 3 * seeds,
        "orders 2-4 passed rule 7 in {passed_high} of {}",
        3 * seeds
    );
    assert_eq!(auto_zero, seeds, "auto with rule 7 keeps order 0");

    for _ in 0..8 {
        let truth = lag_truth(&mut rng);
        let (a, b) = (
            synthesise(&truth, &mut rng, 1.0),
            synthesise(&truth, &mut rng, 1.0),
        );
        let h = held_out(&a, &b);
        assert_eq!(
            not_predictive(1, &h),
            None,
            "a real pole predicts the other half: {h:?}"
        );
        let settings = StructuralSettings {
            held_out_chi2: Some(h),
            ..StructuralSettings::default()
        };
        let fit = fit_structure(&estimate(&whole(&a, &b)), OrderChoice::Auto, &settings).expect("fit");
        assert!(fit.order >= 1, "the lag is kept: order {}", fit.order);
    }
}
