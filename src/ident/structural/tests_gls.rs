//! Generalised least squares: full row weights, collinear inputs, their errors.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::tests::{Truth, band, random_gain};
use super::*;
use crate::rng::Rng;

/// Per-bin noise level of a row: `S_psi,ii / n_eq` (the same for every row here).
const NOISE_VAR: f64 = 1e-6;

/// The input spectrum `S_uu = B B^H` at `f`: independent unit inputs below 5 Hz; above, input 1
/// is input 0 times `c = rho e^(0.3 j)` plus an independent part of power `1 - rho^2`
/// (`rho = 0.999`: nearly rank 2), or exactly collinear above 30 Hz when `singular`.
fn input_spectrum(f: f64, singular: bool) -> Matrix3<Complex64> {
    let rho: f64 = if f < 5.0 {
        0.0
    } else if singular && f > 30.0 {
        1.0
    } else {
        0.999
    };
    let c = Complex64::from_polar(rho, 0.3);
    let one = Complex64::new(1.0, 0.0);
    let zero = Complex64::new(0.0, 0.0);
    let s = Complex64::new((1.0 - rho * rho).sqrt(), 0.0);
    let b = Matrix3::new(one, zero, zero, c, s, zero, zero, zero, one);
    b * b.adjoint()
}

/// A collinear-inputs record: the response `truth` plus row noise of covariance
/// `E[dW_i^H dW_i] = NOISE_VAR S_uu^-1` (zero noise when `noise` is false), the row weights
/// `Omega_i = S_uu / NOISE_VAR` and the per-element variances (the diagonal of the covariance).
struct Record {
    f: Vec<f64>,
    w: Vec<Matrix3<Complex64>>,
    row_weight: Vec<[Matrix3<Complex64>; 3]>,
    variance: Vec<Matrix3<f64>>,
}

fn record(truth: &Truth, rng: &mut Rng, noise: bool, singular: bool) -> Record {
    let f = band();
    let (mut w, mut row_weight, mut variance) = (Vec::new(), Vec::new(), Vec::new());
    for &fk in &f {
        let s_uu = input_spectrum(fk, singular);
        let omega = s_uu / Complex64::new(NOISE_VAR, 0.0);
        row_weight.push([omega; 3]);
        let mut wk = truth.at(fk);
        if let Some(cov) = s_uu.try_inverse().map(|m| m * Complex64::new(NOISE_VAR, 0.0)) {
            let l = cov.cholesky().expect("covariance is positive definite").l();
            variance.push(Matrix3::from_fn(|_, j| cov[(j, j)].re));
            if noise {
                for i in 0..3 {
                    let g: [Complex64; 3] = std::array::from_fn(|_| {
                        Complex64::new(rng.normal(), rng.normal()) * std::f64::consts::FRAC_1_SQRT_2
                    });
                    for j in 0..3 {
                        // dW_i = g L^H: E[dW_i^H dW_i] = L L^H.
                        let dw: Complex64 = (0..3).map(|m| g[m] * l[(j, m)].conj()).sum();
                        wk[(i, j)] += dw;
                    }
                }
            }
        } else {
            variance.push(Matrix3::repeat(f64::INFINITY));
        }
        w.push(wk);
    }
    Record {
        f,
        w,
        row_weight,
        variance,
    }
}

fn fit_rows(r: &Record, order: OrderChoice) -> Result<StructuralFit, StructuralError> {
    let input = ResponseEstimate {
        frequency_hz: &r.f,
        response: &r.w,
        weights: Weights::RowWeight(&r.row_weight),
        offset_hz: None,
    };
    fit_structure(&input, order, &StructuralSettings::default())
}

fn fit_diagonal(r: &Record, order: OrderChoice) -> StructuralFit {
    let input = ResponseEstimate {
        frequency_hz: &r.f,
        response: &r.w,
        weights: Weights::Variance(&r.variance),
        offset_hz: None,
    };
    fit_structure(&input, order, &StructuralSettings::default()).expect("fit")
}

fn max_k_error(fit: &StructuralFit, k: &Matrix3<f64>) -> f64 {
    (0..9)
        .map(|e| (fit.k[e / 3][e % 3] - k[(e / 3, e % 3)]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn noise_free_recovery_with_singular_row_weights() {
    let mut rng = Rng::new(700);
    for tau in [0.003_141_59, -0.000_77] {
        let k = random_gain(&mut rng);
        let r = record(&Truth::gain_delay(k, tau), &mut rng, false, true);
        let fit = fit_rows(&r, OrderChoice::Fixed(0)).expect("fit");
        let (dk, dt) = (max_k_error(&fit, &k), (fit.tau_s - tau).abs());
        assert!(dk < 1e-10 && dt < 1e-10, "K error {dk:e}, tau error {dt:e}");
        assert!(fit.chi2 < 1e-12, "chi2 {}", fit.chi2);
        assert!(fit.k_std.iter().flatten().all(|s| s.is_finite() && *s > 0.0));
    }
    let k = random_gain(&mut rng);
    let truth = Truth {
        num: vec![k],
        den: vec![0.003],
        tau: 0.002_2,
    };
    let r = record(&truth, &mut rng, false, true);
    let fit = fit_rows(&r, OrderChoice::Fixed(1)).expect("fit");
    assert!(
        (fit.denominator[0] - 0.003).abs() < 1e-9 * 0.003,
        "T {}",
        fit.denominator[0]
    );
    assert!((fit.tau_s - 0.002_2).abs() < 1e-10, "tau {}", fit.tau_s);
    assert!(max_k_error(&fit, &k) < 1e-10);
}

#[test]
fn diagonal_row_weights_equal_the_variance_path() {
    let mut rng = Rng::new(701);
    let truth = Truth {
        num: vec![random_gain(&mut rng)],
        den: vec![0.003],
        tau: 0.004,
    };
    let data = super::tests::synthesise(&truth, &mut rng, 1.0);
    let rows: Vec<[Matrix3<Complex64>; 3]> = data
        .2
        .iter()
        .map(|v| {
            std::array::from_fn(|i| {
                Matrix3::from_fn(|j, l| Complex64::new(if j == l { 1.0 / v[(i, j)] } else { 0.0 }, 0.0))
            })
        })
        .collect();
    let by_variance = super::tests::fit(&data, OrderChoice::Fixed(1)).expect("fit");
    let input = ResponseEstimate {
        frequency_hz: &data.0,
        response: &data.1,
        weights: Weights::RowWeight(&rows),
        offset_hz: None,
    };
    let by_rows = fit_structure(&input, OrderChoice::Fixed(1), &StructuralSettings::default()).expect("fit");
    assert!((by_rows.chi2 - by_variance.chi2).abs() < 1e-9 * by_variance.chi2);
    // The same optimum (to far below its uncertainty: the paths differ only in rounding).
    let dt = (by_rows.tau_s - by_variance.tau_s).abs();
    assert!(dt < 1e-3 * by_variance.tau_std_s, "tau differs by {dt:e}");
    for e in 0..9 {
        let (a, b) = (by_rows.k_std[e / 3][e % 3], by_variance.k_std[e / 3][e % 3]);
        assert!((a - b).abs() < 1e-9 * b, "std {a} vs {b}");
    }
}

/// Root mean square of `errors`.
fn rms(errors: &[f64]) -> f64 {
    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
}

#[test]
fn collinear_inputs_gls_is_honest_and_beats_diagonal_weights() {
    let mut rng = Rng::new(702);
    let k = random_gain(&mut rng);
    let tau = 0.003_3;
    let truth = Truth::gain_delay(k, tau);
    let replicates = 120;
    // Per parameter (nine gains, delay): GLS errors, reported stds; diagonal-fit errors.
    let mut gls = vec![Vec::new(); 10];
    let mut reported = vec![Vec::new(); 10];
    let mut diagonal = vec![Vec::new(); 10];
    for _ in 0..replicates {
        let r = record(&truth, &mut rng, true, false);
        let fit = fit_rows(&r, OrderChoice::Fixed(0)).expect("fit");
        let naive = fit_diagonal(&r, OrderChoice::Fixed(0));
        for e in 0..9 {
            let (i, j) = (e / 3, e % 3);
            gls[e].push(fit.k[i][j] - k[(i, j)]);
            reported[e].push(fit.k_std[i][j]);
            diagonal[e].push(naive.k[i][j] - k[(i, j)]);
        }
        gls[9].push(fit.tau_s - tau);
        reported[9].push(fit.tau_std_s);
        diagonal[9].push(naive.tau_s - tau);
    }
    let (mut gls_k, mut diag_k) = (Vec::new(), Vec::new());
    for p in 0..10 {
        let mean_std = reported[p].iter().sum::<f64>() / f64::from(replicates);
        let ratio = rms(&gls[p]) / mean_std;
        let gain = rms(&diagonal[p]) / rms(&gls[p]);
        eprintln!(
            "parameter {p}: GLS rms {:.3e}, reported {mean_std:.3e} (ratio {ratio:.3}), \
             diagonal rms {:.3e} ({gain:.2}x)",
            rms(&gls[p]),
            rms(&diagonal[p])
        );
        assert!(
            (0.75..=1.25).contains(&ratio),
            "parameter {p}: empirical / reported {ratio}"
        );
        if p < 9 {
            gls_k.extend_from_slice(&gls[p]);
            diag_k.extend_from_slice(&diagonal[p]);
        }
    }
    let gain = rms(&diag_k) / rms(&gls_k);
    eprintln!(
        "K rms error: GLS {:.3e}, diagonal {:.3e}, ratio {gain:.2}",
        rms(&gls_k),
        rms(&diag_k)
    );
    // The diagonal fit is given the true marginal variances (the best per-element weights): it
    // is unbiased but discards the collinear bins' information on inputs 0 and 1. Measured
    // (seed 702, 120 records): K 1.41x, columns 0 and 1 1.36..1.62x, delay 1.63x.
    assert!(gain > 1.25, "GLS gains only {gain}x over per-element weights");
    let tau_gain = rms(&diagonal[9]) / rms(&gls[9]);
    assert!(tau_gain > 1.3, "GLS gains only {tau_gain}x on the delay");
}

#[test]
fn bic_with_row_weights_chooses_0_for_gain_delay_and_finds_a_lag() {
    let mut rng = Rng::new(703);
    let auto = OrderChoice::Auto;
    let mut zero = 0;
    for seed in 0..8 {
        let truth = Truth::gain_delay(random_gain(&mut rng), rng.uniform_in(0.002, 0.006));
        let r = record(&truth, &mut rng, true, false);
        let fit = fit_rows(&r, auto).expect("fit");
        let c = &fit.candidates;
        eprintln!(
            "seed {seed}: order {}, chi2 {:.1} {:.1}, dof {}",
            fit.order, c[0].chi2, c[1].chi2, fit.dof
        );
        assert!((c[0].chi2 - fit.dof as f64).abs() < 6.0 * (2.0 * fit.dof as f64).sqrt());
        zero += usize::from(fit.order == 0);
    }
    assert!(zero >= 7, "order 0 in {zero} of 8");
    for seed in 0..4 {
        let truth = Truth {
            num: vec![random_gain(&mut rng)],
            den: vec![0.004],
            tau: 0.003,
        };
        let r = record(&truth, &mut rng, true, false);
        let fit = fit_rows(&r, auto).expect("fit");
        eprintln!("lag seed {seed}: order {}, T {:?}", fit.order, fit.denominator);
        assert!(fit.order >= 1, "seed {seed}: order {}", fit.order);
        if fit.order == 1 {
            assert!((fit.denominator[0] - 0.004).abs() < 0.1 * 0.004);
        }
    }
}

#[test]
fn bad_row_weights_are_refused_with_bin_and_row() {
    let mut rng = Rng::new(704);
    let r = record(
        &Truth::gain_delay(Matrix3::identity(), 0.003),
        &mut rng,
        false,
        false,
    );
    let run = |rows: &[[Matrix3<Complex64>; 3]]| {
        let input = ResponseEstimate {
            frequency_hz: &r.f,
            response: &r.w,
            weights: Weights::RowWeight(rows),
            offset_hz: None,
        };
        fit_structure(&input, OrderChoice::Fixed(0), &StructuralSettings::default())
    };
    let mut bad = r.row_weight.clone();
    bad[12][2][(0, 1)] += Complex64::new(1e3, 0.0);
    assert_eq!(
        run(&bad),
        Err(StructuralError::NonHermitianWeight { bin: 12, row: 2 })
    );
    let mut bad = r.row_weight.clone();
    bad[30][1] = -Matrix3::identity();
    match run(&bad) {
        Err(StructuralError::IndefiniteWeight {
            bin: 30,
            row: 1,
            eigenvalue,
        }) => {
            assert!((eigenvalue + 1.0).abs() < 1e-12);
        }
        other => panic!("expected an indefinite weight at bin 30, row 1: {other:?}"),
    }
    let mut bad = r.row_weight.clone();
    bad[5][0][(2, 2)].im = f64::NAN;
    assert_eq!(
        run(&bad),
        Err(StructuralError::NonFiniteWeight { bin: 5, row: 0 })
    );
    // An eigenvalue of -1e-12 of the trace is rounding, accepted and clamped.
    let mut nearly = r.row_weight.clone();
    nearly[7][0] =
        Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -1e-12).map(|v| Complex64::new(v, 0.0)));
    assert!(run(&nearly).is_ok());
    assert_eq!(
        run(&r.row_weight[1..]),
        Err(StructuralError::LengthMismatch {
            frequencies: 327,
            responses: 327,
            weights: 326
        })
    );
}
