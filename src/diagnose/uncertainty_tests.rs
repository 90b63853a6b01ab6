use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use super::{Covariance, TAPER_VARIANCE, band_limit_std, sandwich_widening, slots};
use crate::diagnose::band_limit::BandLimitShape;
use crate::diagnose::fit::pack;
use crate::diagnose::structure::{Structure, Theta, lag_damping_held};
use crate::rng::Rng;

/// Least squares on 800 groups (a design's count) weighted as if the noise were white;
/// `loud` is its standard deviation on the last tenth, where the second regressor lives.
/// The variance ratios (widening squared) of noise draw `seed`, and the closed form's,
/// `(X'X)^-1 X' Sigma X (X'X)^-1` over `(X'X)^-1`.
fn ratios_against_closed_form(loud: f64, seed: u64) -> ([f64; 2], [f64; 2]) {
    let n = 800;
    let mut rng = Rng::new(1);
    let x: Vec<Vector2<f64>> = (0..n)
        .map(|g| {
            let second = if g >= 9 * n / 10 {
                1.0 + rng.normal()
            } else {
                0.05 * rng.normal()
            };
            Vector2::new(1.0 + 0.3 * rng.normal(), second)
        })
        .collect();
    let sigma = |g: usize| if g >= 9 * n / 10 { loud } else { 1.0 };
    let xtx: Matrix2<f64> = x.iter().map(|v| v * v.transpose()).sum();
    let meat: Matrix2<f64> = x
        .iter()
        .enumerate()
        .map(|(g, v)| sigma(g).powi(2) * v * v.transpose())
        .sum();
    let inv = xtx.try_inverse().expect("regular");
    let truth = inv * meat * inv;
    // Cost sum (y - x b)^2: Hessian 2 X'X, group scores -2 x_g e_g.
    let bread = DMatrix::from_fn(2, 2, |i, j| inv[(i, j)] / 2.0);
    let mut noise = Rng::new(seed);
    let scores: Vec<DVector<f64>> = x
        .iter()
        .enumerate()
        .map(|(g, v)| DVector::from_column_slice(&(-2.0 * sigma(g) * noise.normal() * v).data.0[0]))
        .collect();
    // Real observations of unit variance: the model's covariance is (X'X)^-1 = 2 H^-1.
    let model = DMatrix::from_fn(2, 2, |i, j| inv[(i, j)]);
    let widening = sandwich_widening(&bread, &scores, &model).expect("enough clusters");
    (
        [widening[0].powi(2), widening[1].powi(2)],
        [0, 1].map(|i| truth[(i, i)] / inv[(i, i)]),
    )
}

#[test]
fn the_sandwich_widens_where_the_misfit_piles_up_and_only_there() {
    // The estimate of one draw scatters (the second parameter's information lies in 20 of
    // the 200 clusters); over 40 draws its mean is the closed form's, less the sandwich's
    // known small-sample bias where few clusters carry a parameter (each of the 20 has a
    // leverage near 1/20 on it: about 10 % low here, 1 % on the first parameter).
    let draws = 40;
    let mut mean = [0.0; 2];
    let mut expected = [0.0; 2];
    for seed in 0..draws {
        let (got, closed) = ratios_against_closed_form(4.0, 100 + seed);
        expected = closed;
        for i in 0..2 {
            mean[i] += got[i] / draws as f64;
        }
    }
    assert!(expected[1] > 9.0, "{expected:?}");
    for (i, tolerance) in [(0, 0.05), (1, 0.15)] {
        assert!(
            (mean[i] / expected[i] - 1.0).abs() < tolerance,
            "variance ratios {mean:?}, closed form {expected:?}"
        );
    }
    // White noise as weighted: nothing to widen beyond the estimate's own scatter.
    let mut white = [0.0; 2];
    for seed in 0..draws {
        let (got, _) = ratios_against_closed_form(1.0, 100 + seed);
        for i in 0..2 {
            white[i] += got[i] / draws as f64;
        }
    }
    assert!(white.iter().all(|w| (1.0..1.15).contains(w)), "{white:?}");
}

#[test]
fn the_frequency_taper_factor_is_that_of_a_hann_window() {
    let n = 200_000_usize;
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let t = k as f64 - 0.5 * (n as f64 - 1.0);
        let w = (std::f64::consts::PI * k as f64 / n as f64).sin().powi(2);
        a += w.powi(4) * t * t;
        b += t * t;
        c += w * w * t * t;
    }
    let brute = a * b / (c * c);
    assert!((brute - super::TAPER_FREQUENCY_VARIANCE).abs() < 1e-6, "{brute}");
    let pi2 = std::f64::consts::PI.powi(2);
    let closed = 35.0 * pi2 * (24.0 * pi2 - 205.0) / (108.0 * (2.0 * pi2 - 15.0).powi(2));
    assert!(
        (closed - super::TAPER_FREQUENCY_VARIANCE).abs() < 1e-10,
        "{closed}"
    );
}

#[test]
fn the_taper_factor_is_that_of_a_hann_window() {
    // mean(w^4) / mean(w^2)^2 of the periodic Hann window, by brute force.
    let n = 4096_usize;
    let w: Vec<f64> = (0..n)
        .map(|k| (std::f64::consts::PI * k as f64 / n as f64).sin().powi(2))
        .collect();
    let m2 = w.iter().map(|v| v * v).sum::<f64>() / n as f64;
    let m4 = w.iter().map(|v| v.powi(4)).sum::<f64>() / n as f64;
    assert!(
        (m4 / (m2 * m2) - TAPER_VARIANCE).abs() < 1e-9,
        "{}",
        m4 / (m2 * m2)
    );
}

#[test]
fn each_nonlinear_slot_holds_its_own_parameter() {
    let structure = Structure {
        skew: true,
        lag: Some(crate::diagnose::structure::LagShape::FirstOrder),
        band_limit: Some(BandLimitShape::Causal2),
        resonance_axes: vec![1, 2],
        ..Structure::default()
    };
    let theta = Theta {
        tau_s: 4e-3,
        skew_s: [0.3e-3, -0.1e-3],
        lag_s: 2e-3,
        lag_damping: 0.0,
        band_limit_t_s: 3e-3,
        resonances: vec![(20.0, 0.05), (30.0, 0.2)],
    };
    let (x, _) = pack(&structure, &theta);
    let slot = slots(&structure);
    assert_eq!(x.len(), 1 + structure.n_nonlinear_extra());
    assert!((x[slot.skew.expect("skew")] - 0.3).abs() < 1e-12);
    assert!((x[slot.lag.expect("lag")] - 2.0).abs() < 1e-12);
    assert!((x[slot.band_limit.expect("band limit")] - 3.0).abs() < 1e-12);
    assert!((x[slot.resonances] - 20.0).abs() < 1e-12);
    assert!((x[slot.resonances + 2] - 30.0).abs() < 1e-12);
    // A second-order lag's damping (as its logarithm) follows its time constant, and the
    // resonances move one slot on; unpacking gives the parameters back.
    let second = Structure {
        lag: Some(crate::diagnose::structure::LagShape::SecondOrder),
        ..structure
    };
    let theta = Theta {
        lag_damping: 0.7,
        ..theta
    };
    let (x, _) = pack(&second, &theta);
    let slot = slots(&second);
    assert_eq!(x.len(), 1 + second.n_nonlinear_extra());
    assert!((x[slot.lag.expect("lag") + 1] - 0.7f64.ln()).abs() < 1e-12);
    assert!((x[slot.band_limit.expect("band limit")] - 3.0).abs() < 1e-12);
    assert!((x[slot.resonances] - 20.0).abs() < 1e-12);
    let back = crate::diagnose::fit::unpack(&second, &x, [0.1, 40.0]).expect("in range");
    assert!((back.lag_damping - 0.7).abs() < 1e-12 && (back.lag_s - 2e-3).abs() < 1e-15);
    // A damping outside the range kept is refused.
    let mut outside = x.clone();
    outside[slot.lag.expect("lag") + 1] = 0.1f64.ln();
    assert!(crate::diagnose::fit::unpack(&second, &outside, [0.1, 40.0]).is_none());
    // A damping held at a bound (within 2 %) is said so; a Butterworth's and a Bessel's are not.
    assert!(lag_damping_held(0.5) && lag_damping_held(0.505) && lag_damping_held(3.95));
    assert!(!lag_damping_held(0.5f64.sqrt()) && !lag_damping_held(0.866) && !lag_damping_held(2.0));
}

#[test]
fn the_band_limits_deviations_follow_its_time_constants() {
    // T = 2 ms with 0.1 ms of deviation (slot 1, ms units, after two linear parameters).
    let matrix = DMatrix::from_diagonal(&DVector::from_column_slice(&[1.0, 1.0, 0.04, 0.01]));
    let cov = Covariance { matrix, n_linear: 2 };
    let (t, sd_t, top) = (2e-3, 0.1e-3, 30.0);
    let v = band_limit_std(BandLimitShape::ZeroPhase { order: 1 }, t, top, Some(&cov), 1);
    let read = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    assert!((read("T_s") - sd_t).abs() < 1e-12, "{v}");
    // sd(f_c) = sd(T) / (2 pi T^2).
    let corner = sd_t / (std::f64::consts::TAU * t * t);
    assert!((read("corner_hz") / corner - 1.0).abs() < 1e-9, "{v}");
    // d/dT sqrt(1 + (w T)^2) = w^2 T / sqrt(1 + (w T)^2).
    let w = std::f64::consts::TAU * top;
    let rise = w * w * t / (1.0 + (w * t).powi(2)).sqrt() * sd_t;
    assert!((read("gain_rise_at_band_top") / rise - 1.0).abs() < 1e-5, "{v}");
    // No corner's deviation at T = 0.
    let v = band_limit_std(BandLimitShape::Causal2, 0.0, top, Some(&cov), 1);
    assert!(v["corner_hz"].is_null(), "{v}");
    // No reference rate but for the interpolated shape.
    assert!(v.get("reference_rate_hz").is_none(), "{v}");
    // The interpolated shape, T = 1 / (120 Hz) with 0.01 ms: sd(f_r) = sd(T) / T^2, its corner
    // 0.3189 of that; d/dT (1 / sinc^2(f T)) by the series of sinc to fourth order.
    let matrix = DMatrix::from_diagonal(&DVector::from_column_slice(&[1.0, 1.0, 0.04, 1e-4]));
    let cov = Covariance { matrix, n_linear: 2 };
    let (t, sd_t) = (1.0 / 120.0, 1e-5);
    let v = band_limit_std(BandLimitShape::Interpolated, t, top, Some(&cov), 1);
    let read = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    assert!(
        (read("reference_rate_hz") / (sd_t / (t * t)) - 1.0).abs() < 1e-9,
        "{v}"
    );
    let corner = crate::model::band_limit::INTERPOLATED_CORNER * sd_t / (t * t);
    assert!((read("corner_hz") / corner - 1.0).abs() < 1e-9, "{v}");
    // 1 / sinc^2(x) = 1 + (pi x)^2 / 3 + (pi x)^4 / 15 + (2/189)(pi x)^6 + ..., x = f T: its
    // slope by these three terms, 0.36 % short at x = 0.25.
    let slope = |t: f64| {
        let y2 = (std::f64::consts::PI * top).powi(2);
        2.0 * y2 * t / 3.0 + 4.0 * y2 * y2 * t.powi(3) / 15.0 + 12.0 / 189.0 * y2.powi(3) * t.powi(5)
    };
    assert!(
        (read("gain_rise_at_band_top") / (slope(t) * sd_t) - 1.0).abs() < 5e-3,
        "{v}"
    );
}
