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

/// A record on `band()` of `K e^(-s 4 ms)` (`K` from `seed`) with complex noise of variance
/// [`VARIANCE`] per element, its weights stating [`OVERSTATED`] times that, and zero offsets.
struct Record {
    f: Vec<f64>,
    k: Matrix3<f64>,
    response: Vec<Matrix3<Complex64>>,
    weights: Vec<[Matrix3<Complex64>; 3]>,
    zeros: Vec<Matrix3<Complex64>>,
}

impl Record {
    fn new(seed: u64) -> Self {
        let f = band();
        let mut rng = Rng::new(seed);
        let k = random_gain(&mut rng);
        let truth = Truth::gain_delay(k, 0.004);
        let noise = (0.5 * VARIANCE).sqrt();
        let response = f
            .iter()
            .map(|&fk| {
                truth.at(fk) + Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()) * noise)
            })
            .collect();
        let stated = Matrix3::from_diagonal_element(Complex64::from(1.0 / (OVERSTATED * VARIANCE)));
        Self {
            weights: vec![[stated; 3]; f.len()],
            zeros: vec![Matrix3::zeros(); f.len()],
            f,
            k,
            response,
        }
    }

    /// The estimate, with its zero offsets (aligned) or without.
    fn input(&self, offsets: bool) -> ResponseEstimate<'_> {
        ResponseEstimate {
            frequency_hz: &self.f,
            response: &self.response,
            weights: Weights::RowWeight(&self.weights),
            offset_hz: offsets.then_some(&self.zeros[..]),
        }
    }
}

/// The rms over `seeds` runs of the gains' normalised errors, with and without offsets.
fn k_z_rms(seeds: u64, offsets: bool) -> f64 {
    let mut sum = 0.0;
    for seed in 0..seeds {
        let r = Record::new(500 + seed);
        let fit = fit_structure(
            &r.input(offsets),
            OrderChoice::Fixed(0),
            &StructuralSettings::default(),
        )
        .unwrap();
        for e in 0..9 {
            let (i, j) = (e / 3, e % 3);
            sum += ((fit.k[i][j] - r.k[(i, j)]) / fit.k_std[i][j]).powi(2);
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

/// With row weights that get narrowed, the narrowing depends on the data and the order-0 fit
/// alone: a refit for another order is `warm`'s "same data", bit for bit the cold fit of that
/// order, and from scratch; and a fit asking not to narrow keeps the deviations as given.
#[test]
fn narrowed_weights_keep_the_warm_contract() {
    let r = Record::new(41);
    let input = r.input(true);
    let settings = StructuralSettings::default();
    let auto = fit_structure(&input, OrderChoice::Auto, &settings).unwrap();
    for order in [OrderChoice::Fixed(0), OrderChoice::Fixed(1)] {
        let refit = refit_structure(&input, order, &settings, &auto).unwrap();
        let cold = fit_structure(&input, order, &settings).unwrap();
        assert!(refit.fitted.from_scratch(), "{order:?}");
        assert_eq!(refit.tau_s.to_bits(), cold.tau_s.to_bits(), "{order:?}");
        assert_eq!(refit.k, cold.k, "{order:?}");
        assert_eq!(refit.k_std, cold.k_std, "{order:?}");
        assert_eq!(refit.chi2.to_bits(), cold.chi2.to_bits(), "{order:?}");
    }
    let as_given = StructuralSettings {
        narrow_to_scatter: false,
        ..StructuralSettings::default()
    };
    let wide = fit_structure(&input, OrderChoice::Fixed(0), &as_given).unwrap();
    let narrow = fit_structure(&input, OrderChoice::Fixed(0), &settings).unwrap();
    let ratio = wide.k_std[0][0] / narrow.k_std[0][0];
    assert!((2.0..4.0).contains(&ratio), "{ratio}");
}
