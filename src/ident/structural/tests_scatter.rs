//! Weights that overstate the noise (`scatter`): the deviations follow the estimate's own scatter
//! once the estimate is aligned (it has offsets), and stay as wide as the weights say without
//! (the fit's chi2/dof below 1 never narrows them).

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::tests::{Truth, band, random_gain};
use super::*;
use crate::rng::Rng;

/// Each element's true complex variance.
const VARIANCE: f64 = 1e-6;

/// How many times the true variance the weights state.
const OVERSTATED: f64 = 10.0;

/// The rms over `seeds` runs of the gains' normalised errors, with and without offsets.
fn k_z_rms(seeds: u64, offsets: bool) -> f64 {
    let f = band();
    let weights: Vec<[Matrix3<Complex64>; 3]> = f
        .iter()
        .map(|_| [Matrix3::from_diagonal_element(Complex64::from(1.0 / (OVERSTATED * VARIANCE))); 3])
        .collect();
    let zeros = vec![Matrix3::zeros(); f.len()];
    let mut sum = 0.0;
    for seed in 0..seeds {
        let mut rng = Rng::new(500 + seed);
        let k = random_gain(&mut rng);
        let truth = Truth::gain_delay(k, 0.004);
        let response: Vec<Matrix3<Complex64>> = f
            .iter()
            .map(|&fk| {
                truth.at(fk)
                    + Matrix3::from_fn(|_, _| {
                        Complex64::new(rng.normal(), rng.normal()) * (0.5 * VARIANCE).sqrt()
                    })
            })
            .collect();
        let input = ResponseEstimate {
            frequency_hz: &f,
            response: &response,
            weights: Weights::RowWeight(&weights),
            offset_hz: offsets.then_some(&zeros[..]),
        };
        let fit = fit_structure(&input, OrderChoice::Fixed(0), &StructuralSettings::default()).unwrap();
        for e in 0..9 {
            let (i, j) = (e / 3, e % 3);
            sum += ((fit.k[i][j] - k[(i, j)]) / fit.k_std[i][j]).powi(2);
        }
    }
    (sum / (9 * seeds) as f64).sqrt()
}

/// Twenty runs: the gains' normalised errors have rms near 1 with the aligned estimate's
/// narrowed weights, and about `1 / sqrt(10)` with the weights as given.
#[test]
fn overstated_weights_are_narrowed_to_the_scatter() {
    let narrowed = k_z_rms(20, true);
    assert!((0.8..=1.25).contains(&narrowed), "narrowed: {narrowed}");
    let as_given = k_z_rms(20, false);
    assert!(as_given < 0.45, "as given: {as_given}");
}
