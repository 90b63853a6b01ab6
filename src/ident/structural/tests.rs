//! Noise-free recovery, poles, input errors and the IEEE report.

use std::f64::consts::PI;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::*;
use crate::rng::Rng;

/// A synthetic block: `N(s) / d(s) e^(-tau s)` with physical coefficients.
pub(super) struct Truth {
    pub num: Vec<Matrix3<f64>>,
    pub den: Vec<f64>,
    pub tau: f64,
}

impl Truth {
    pub fn gain_delay(k: Matrix3<f64>, tau: f64) -> Self {
        Self {
            num: vec![k],
            den: Vec::new(),
            tau,
        }
    }

    pub fn at(&self, f: f64) -> Matrix3<Complex64> {
        let s = Complex64::new(0.0, 2.0 * PI * f);
        let mut d = Complex64::new(1.0, 0.0);
        for (m, c) in self.den.iter().enumerate() {
            d += s.powi(m as i32 + 1) * c;
        }
        let mut n = Matrix3::zeros();
        for (m, c) in self.num.iter().enumerate() {
            n += c.map(|v| s.powi(m as i32) * v);
        }
        n * ((-s * self.tau).exp() / d)
    }
}

/// 327 bins from 0.1 Hz by 0.122 Hz (to 39.87 Hz).
pub(super) fn band() -> Vec<f64> {
    (0..327).map(|k| 0.1 + 0.122 * f64::from(k)).collect()
}

/// Element standard deviation: 1e-3 mid-band, rising to 1e-2 at both edges.
pub(super) fn element_std(f: f64) -> f64 {
    let u = (f - 20.0) / 20.0;
    1e-3 * (1.0 + 9.0 * u * u)
}

/// `I` + scale errors and couplings of order 1e-3.
pub(super) fn random_gain(rng: &mut Rng) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| f64::from(u8::from(i == j)) + 1e-3 * rng.normal())
}

/// Data from `truth` on `band()`, with complex noise of variance `element_std^2 * noise_scale^2`
/// (`noise_scale = 0`: exact data; the stated variance is always the unscaled one).
pub(super) fn synthesise(
    truth: &Truth,
    rng: &mut Rng,
    noise_scale: f64,
) -> (Vec<f64>, Vec<Matrix3<Complex64>>, Vec<Matrix3<f64>>) {
    let f = band();
    let var: Vec<Matrix3<f64>> = f
        .iter()
        .map(|&f| Matrix3::repeat(element_std(f).powi(2)))
        .collect();
    let w = f
        .iter()
        .zip(&var)
        .map(|(&fk, v)| {
            truth.at(fk)
                + Matrix3::from_fn(|i, j| {
                    let sd = noise_scale * (v[(i, j)] / 2.0).sqrt();
                    Complex64::new(sd * rng.normal(), sd * rng.normal())
                })
        })
        .collect();
    (f, w, var)
}

pub(super) fn fit(
    data: &(Vec<f64>, Vec<Matrix3<Complex64>>, Vec<Matrix3<f64>>),
    order: OrderChoice,
) -> Result<StructuralFit, StructuralError> {
    let input = ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::Variance(&data.2),
        offset_hz: None,
    };
    fit_structure(&input, order, &StructuralSettings::default())
}

fn max_k_error(fit: &StructuralFit, k: &Matrix3<f64>) -> f64 {
    (0..9)
        .map(|e| (fit.k[e / 3][e % 3] - k[(e / 3, e % 3)]).abs())
        .fold(0.0, f64::max)
}

/// `gain_delay::fit_near` from a delay within a scan step of the optimum gives the full scan's
/// fit; from a delay far from it (no maximum in its cell) it falls back to the scan.
#[test]
fn order0_refined_near_a_known_delay_is_the_scanned_fit() {
    let mut rng = Rng::new(5);
    let k = random_gain(&mut rng);
    let tau = 0.004_321;
    let data = synthesise(&Truth::gain_delay(k, tau), &mut rng, 0.3);
    let input = ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::Variance(&data.2),
        offset_hz: None,
    };
    let rows = weights::row_weights(&input.weights).unwrap();
    let prepared = model::Prepared::new(&input, std::sync::Arc::from(rows));
    let (lo, hi) = (-0.02, 0.05);
    let scanned = gain_delay::fit(&prepared, lo, hi, 1.0);
    let step = 2.0 * PI / prepared.omega_ref / 16.0;
    for near in [
        scanned.tau - 0.6 * step,
        scanned.tau + 0.3 * step,
        scanned.tau + 20.0 * step,
    ] {
        let refined = gain_delay::fit_near(&prepared, near, lo, hi, 1.0);
        assert!(
            (refined.tau - scanned.tau).abs() < 1e-12,
            "from {near}: {} vs {}",
            refined.tau,
            scanned.tau
        );
        for (a, b) in refined.num[0].iter().zip(&scanned.num[0]) {
            assert!((a - b).abs() < 1e-9, "from {near}: {a} vs {b}");
        }
    }
}

#[test]
fn order0_noise_free_recovers_gain_and_fractional_delay() {
    let mut rng = Rng::new(1);
    for tau in [0.002_345_678_9, 0.004_567_123, 0.005_912_3, -0.001_3] {
        let k = random_gain(&mut rng);
        let data = synthesise(&Truth::gain_delay(k, tau), &mut rng, 0.0);
        let fit = fit(&data, OrderChoice::Fixed(0)).expect("fit");
        let dk = max_k_error(&fit, &k);
        let dt = (fit.tau_s - tau).abs();
        assert!(dk < 1e-12, "K error {dk:e} at tau {tau}");
        assert!(dt < 1e-10, "tau error {dt:e} at tau {tau}");
        assert!(fit.chi2 < 1e-12, "chi2 {}", fit.chi2);
        assert!(fit.denominator.is_empty() && fit.poles.is_empty() && fit.stable);
        let err = (fit.response(13.3) - Truth::gain_delay(k, tau).at(13.3))
            .map(Complex64::norm)
            .max();
        assert!(err < 1e-11, "response error {err:e}");
    }
}

#[test]
fn order1_noise_free_recovers_time_constant_and_delay() {
    let mut rng = Rng::new(2);
    for (t, tau) in [(0.004, 0.003_21), (0.002, 0.005_07)] {
        let k = random_gain(&mut rng);
        let truth = Truth {
            num: vec![k],
            den: vec![t],
            tau,
        };
        let data = synthesise(&truth, &mut rng, 0.0);
        let fit = fit(&data, OrderChoice::Fixed(1)).expect("fit");
        assert_eq!(fit.order, 1);
        let dt = (fit.denominator[0] - t).abs() / t;
        assert!(dt < 1e-9, "T relative error {dt:e}");
        assert!((fit.tau_s - tau).abs() < 1e-10, "tau {} vs {tau}", fit.tau_s);
        assert!(max_k_error(&fit, &k) < 1e-10);
        assert!(fit.stable);
        let pole = fit.poles[0];
        assert!((pole[0] + 1.0 / t).abs() < 1e-6 * (1.0 / t) && pole[1].abs() < 1e-9);
    }
}

#[test]
fn order2_noise_free_recovers_coefficients_and_poles() {
    // d(s) = 1 + 2 zeta s / wn + s^2 / wn^2, wn = 2 pi 60 rad/s, zeta = 0.6;
    // N(s) = K + N1 s, the numerator's zero above the band.
    let mut rng = Rng::new(3);
    let (wn, zeta) = (2.0 * PI * 60.0, 0.6);
    let k = random_gain(&mut rng);
    let n1 = k * 4e-4 + Matrix3::from_fn(|_, _| 1e-5 * rng.normal());
    let truth = Truth {
        num: vec![k, n1],
        den: vec![2.0 * zeta / wn, 1.0 / (wn * wn)],
        tau: 0.002_7,
    };
    let data = synthesise(&truth, &mut rng, 0.0);
    let fit = fit(&data, OrderChoice::Fixed(2)).expect("fit");
    for (got, want) in fit.denominator.iter().zip(&truth.den) {
        assert!((got - want).abs() < 1e-7 * want.abs(), "d {got:e} vs {want:e}");
    }
    let dn1 = (0..9)
        .map(|e| (fit.numerator[1][e / 3][e % 3] - n1[(e / 3, e % 3)]).abs())
        .fold(0.0, f64::max);
    assert!(dn1 < 1e-9, "N1 error {dn1:e}");
    assert!(max_k_error(&fit, &k) < 1e-9);
    // The poles: -zeta wn +- j wn sqrt(1 - zeta^2).
    let (re, im) = (-zeta * wn, wn * (1.0 - zeta * zeta).sqrt());
    assert_eq!(fit.poles.len(), 2);
    for p in &fit.poles {
        assert!(
            (p[0] - re).abs() < 1e-6 * wn && (p[1].abs() - im).abs() < 1e-6 * wn,
            "{p:?}"
        );
    }
    assert!(fit.poles[0][1] * fit.poles[1][1] < 0.0, "a conjugate pair");
    assert!(fit.stable);
    let candidates: Vec<usize> = fit.candidates.iter().map(|c| c.order).collect();
    assert_eq!(candidates, vec![0, 1, 2]);
}

#[test]
fn unstable_best_fit_is_flagged() {
    // A right-half-plane pole: W = K e^(-tau s) / (1 - T s). The best order-1 fit is unstable
    // and must say so; Auto must not choose it.
    let mut rng = Rng::new(4);
    let k = random_gain(&mut rng);
    let truth = Truth {
        num: vec![k],
        den: vec![-0.004],
        tau: 0.003,
    };
    let data = synthesise(&truth, &mut rng, 0.0);
    let fixed = fit(&data, OrderChoice::Fixed(1)).expect("fit");
    assert!(!fixed.stable, "poles {:?}", fixed.poles);
    assert!(fixed.poles[0][0] > 0.0);
    assert!(!fixed.candidates[1].stable);
    let auto = fit(&data, OrderChoice::Auto).expect("fit");
    assert!(auto.stable && auto.candidates.iter().any(|c| !c.stable));
}

#[test]
fn ieee_report_of_a_hand_made_gain() {
    let k = Matrix3::new(
        1.000_250, 0.001_5, -0.000_7, //
        -0.002, 0.999_100, 0.000_3, //
        0.000_05, -0.001_1, 1.0,
    );
    let mut rng = Rng::new(5);
    let data = synthesise(&Truth::gain_delay(k, 0.004), &mut rng, 0.0);
    let fit = fit(&data, OrderChoice::Fixed(0)).expect("fit");
    let ppm = [250.0, -900.0, 0.0];
    for i in 0..3 {
        assert!(
            (fit.scale_factor_error_ppm[i] - ppm[i]).abs() < 1e-5,
            "{:?}",
            fit.scale_factor_error_ppm
        );
        assert!((fit.scale_factor_error_std_ppm[i] - fit.k_std[i][i] * 1e6).abs() < 1e-9);
    }
    let mrad = [[0.0, 1.5, -0.7], [-2.0, 0.0, 0.3], [0.05, -1.1, 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            assert!((fit.misalignment_mrad[i][j] - mrad[i][j]).abs() < 1e-8);
            let want_std = if i == j { 0.0 } else { fit.k_std[i][j] * 1e3 };
            assert!((fit.misalignment_std_mrad[i][j] - want_std).abs() < 1e-12);
        }
    }
    let json = serde_json::to_value(&fit).expect("serialise");
    assert!(json.get("scale_factor_error_ppm").is_some() && json.get("tau_std_s").is_some());
}

#[test]
fn bad_inputs_are_refused_with_their_bin() {
    let mut rng = Rng::new(6);
    let good = synthesise(&Truth::gain_delay(Matrix3::identity(), 0.003), &mut rng, 0.0);
    let run = |f: &[f64], w: &[Matrix3<Complex64>], v: &[Matrix3<f64>], order| {
        let input = ResponseEstimate {
            frequency_hz: f,
            response: w,
            weights: Weights::Variance(v),
            offset_hz: None,
        };
        fit_structure(&input, order, &StructuralSettings::default())
    };
    let (f, w, v) = (&good.0[..], &good.1[..], &good.2[..]);
    let auto = OrderChoice::Auto;
    assert_eq!(run(&[], &[], &[], auto), Err(StructuralError::EmptyBand));
    assert_eq!(
        run(f, &w[1..], v, auto),
        Err(StructuralError::LengthMismatch {
            frequencies: 327,
            responses: 326,
            weights: 327
        })
    );
    let mut bad_w = w.to_vec();
    bad_w[17][(1, 2)].im = f64::NAN;
    assert_eq!(
        run(f, &bad_w, v, auto),
        Err(StructuralError::NonFiniteResponse {
            bin: 17,
            row: 1,
            col: 2
        })
    );
    let mut bad_v = v.to_vec();
    bad_v[40][(2, 0)] = f64::INFINITY;
    assert_eq!(
        run(f, w, &bad_v, auto),
        Err(StructuralError::NonFiniteVariance {
            bin: 40,
            row: 2,
            col: 0
        })
    );
    bad_v[40][(2, 0)] = 0.0;
    assert_eq!(
        run(f, w, &bad_v, auto),
        Err(StructuralError::NonPositiveVariance {
            bin: 40,
            row: 2,
            col: 0,
            value: 0.0
        })
    );
    let mut bad_f = f.to_vec();
    bad_f[9] = -bad_f[8];
    assert_eq!(
        run(&bad_f, w, v, auto),
        Err(StructuralError::BadFrequency {
            bin: 9,
            value: -bad_f[8]
        })
    );
    // Two bins at one frequency (beside one line, at its centroid) are two observations there.
    let mut shared = f.to_vec();
    shared[9] = shared[8];
    assert!(run(&shared, w, v, auto).is_ok());
    assert_eq!(
        run(f, w, v, OrderChoice::Fixed(5)),
        Err(StructuralError::OrderTooHigh { order: 5, max: 4 })
    );
    assert_eq!(
        run(&f[..7], &w[..7], &v[..7], OrderChoice::Fixed(3)),
        Err(StructuralError::TooFewBins {
            order: 3,
            parameters: 31,
            required: 8,
            bins: 7
        })
    );
    assert_eq!(
        run(&f[..1], &w[..1], &v[..1], auto),
        Err(StructuralError::TooFewBins {
            order: 0,
            parameters: 10,
            required: 2,
            bins: 1
        })
    );
    // Auto on a short band fits only the orders it supports.
    let short = run(&f[..5], &w[..5], &v[..5], auto).expect("orders 0 and 1 fit");
    assert_eq!(short.candidates.len(), 2);
    let input = ResponseEstimate {
        frequency_hz: f,
        response: w,
        weights: Weights::Variance(v),
        offset_hz: None,
    };
    let settings = StructuralSettings {
        tau_min_s: 0.01,
        tau_max_s: 0.01,
        ..Default::default()
    };
    assert_eq!(
        fit_structure(&input, auto, &settings),
        Err(StructuralError::BadTauRange {
            tau_min_s: 0.01,
            tau_max_s: 0.01
        })
    );
}

#[test]
fn degenerate_data_gives_no_nan() {
    // An all-zero response: the delay is undetermined, so its deviation is infinite, never NaN.
    let f = band();
    let w = vec![Matrix3::zeros(); f.len()];
    let v = vec![Matrix3::repeat(1e-6); f.len()];
    let input = ResponseEstimate {
        frequency_hz: &f,
        response: &w,
        weights: Weights::Variance(&v),
        offset_hz: None,
    };
    let result = fit_structure(&input, OrderChoice::Auto, &StructuralSettings::default());
    let fit = result.expect("order 0 is defined on zero data");
    assert!(!report::has_nan(&fit));
    assert_eq!(fit.order, 0);
    assert!(fit.k.iter().flatten().all(|v| v.abs() < 1e-300));
    assert!(fit.tau_std_s.is_infinite());
    assert!(fit.k_std.iter().flatten().all(|s| s.is_finite() && *s > 0.0));
}

/// `carry_even_gain` on a delay-only fit (fitted over the even gain, so `K` is kept): each
/// deviation widened in quadrature by `g`'s (the static figures alike), the response
/// `g(f) K e^(-j 2 pi f tau)` in closed form with `g` held above the band's top; once only, and
/// never at an order above 0.
#[test]
fn an_even_gain_is_carried_by_a_delay_only_model() {
    use crate::ident::gain_curvature::EvenGain;
    let mut rng = Rng::new(8);
    let k = random_gain(&mut rng);
    let tau = 0.0041;
    let data = synthesise(&Truth::gain_delay(k, tau), &mut rng, 1.0);
    let before = fit(&data, OrderChoice::Fixed(0)).expect("fit");
    let even = EvenGain {
        coefficients: [5e-6, 1e-10],
        coefficients_std: [4e-7, 6e-11],
        k_change: std::array::from_fn(|i| std::array::from_fn(|j| 1e-3 * (1.0 + (3 * i + j) as f64))),
        k_change_std: std::array::from_fn(|i| std::array::from_fn(|j| 1e-4 * (1.0 + (i + 2 * j) as f64))),
        band_top_hz: 30.0,
    };
    let mut after = before.clone();
    assert!(after.carry_even_gain(even));
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(after.k[i][j].to_bits(), before.k[i][j].to_bits());
            let std = before.k_std[i][j].hypot(even.k_change_std[i][j]);
            assert!((after.k_std[i][j] - std).abs() < 1e-15, "{i} {j}");
            if i == j {
                assert!((after.scale_factor_error_std_ppm[i] - std * 1e6).abs() < 1e-6);
            } else {
                assert!((after.misalignment_std_mrad[i][j] - std * 1e3).abs() < 1e-9);
            }
        }
    }
    assert_eq!((after.tau_s, after.tau_std_s), (before.tau_s, before.tau_std_s));
    for f in [0.3_f64, 7.0, 24.5, 30.0, 80.0] {
        // g held at its band top's value above it.
        let held = 2.0 * PI * f.min(30.0);
        let g = 1.0 + 5e-6 * held * held + 1e-10 * held.powi(4);
        let want =
            Matrix3::from_fn(|i, j| Complex64::from_polar(g * after.k[i][j], -2.0 * PI * f * after.tau_s));
        let err = (after.response(f) - want).map(Complex64::norm).max();
        assert!(err < 1e-12, "{f} Hz: {err:e}");
    }
    // Once only: a second even gain changes nothing.
    let again = after.clone();
    assert!(!after.carry_even_gain(even));
    assert_eq!(after, again);
    // A rational order's poles and zeros are the block's own: left as fitted.
    let lagged = Truth {
        num: vec![k],
        den: vec![0.003],
        tau,
    };
    let mut first = fit(&synthesise(&lagged, &mut rng, 0.0), OrderChoice::Fixed(1)).expect("fit");
    let unchanged = first.clone();
    assert!(!first.carry_even_gain(even));
    assert_eq!(first, unchanged);
}

/// Delays outside the -20 to 50 ms searched first are found by the wider search (before: the
/// range's end), with the gain, on noisy data: far beyond it, and just past its ends (0.1 and
/// 0.15 ms past, where the evidence bar alone would keep the end: the same lobe, cut off).
#[test]
fn order0_finds_delays_beyond_the_usual_range() {
    let mut rng = Rng::new(61);
    for tau in [-0.25, -0.1, -0.0213, -0.02015, 0.0501, 0.0537, 0.12, 0.29] {
        let k = random_gain(&mut rng);
        let data = synthesise(&Truth::gain_delay(k, tau), &mut rng, 1.0);
        let fit = fit(&data, OrderChoice::Fixed(0)).expect("fit");
        assert!(
            (fit.tau_s - tau).abs() < 5.0 * fit.tau_std_s,
            "tau {tau}: {} +- {}",
            fit.tau_s,
            fit.tau_std_s
        );
        assert!(max_k_error(&fit, &k) < 5e-3, "tau {tau}: {:?}", fit.k);
    }
}
