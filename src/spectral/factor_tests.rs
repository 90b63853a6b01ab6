//! Tests of [`super::wilson`]: known factors, the scalar cepstral reference, near-singular input
//! and bad input. Figures are printed to stderr (`cargo test -- --nocapture`).

use super::*;
use crate::rng::Rng;
use crate::spectral::cepstral::min_phase_scalar_cepstral;
use nalgebra::{DMatrix, Matrix3, Matrix3x2};
use std::f64::consts::PI;

type M3 = Matrix3<Complex64>;

fn c(x: f64) -> Complex64 {
    Complex64::new(x, 0.0)
}

/// `e^{-2 pi i k l / n}` = `z^-l` on bin `k`.
fn z_pow(k: usize, l: usize, n: usize) -> Complex64 {
    Complex64::from_polar(1.0, -2.0 * PI * ((k * l) % n) as f64 / n as f64)
}

fn random_real(rng: &mut Rng, scale: f64) -> M3 {
    M3::from_fn(|_, _| c(scale * rng.normal()))
}

fn random_lower(rng: &mut Rng) -> M3 {
    M3::from_fn(|i, j| match i.cmp(&j) {
        std::cmp::Ordering::Greater => c(rng.normal()),
        std::cmp::Ordering::Equal => c(0.5 + rng.uniform()),
        std::cmp::Ordering::Less => c(0.0),
    })
}

/// `sum_l B_l z^-l` on the grid.
fn ma_on_grid(b: &[M3], n: usize) -> Vec<M3> {
    (0..n)
        .map(|k| b.iter().enumerate().map(|(l, bl)| bl * z_pow(k, l, n)).sum())
        .collect()
}

fn density(d: &[M3]) -> Vec<M3> {
    d.iter().map(|x| x * x.adjoint()).collect()
}

/// `max_k ||a_k - b_k|| / max_k ||b_k||`.
fn rel_diff<const D: usize>(a: &[SMatrix<Complex64, D, D>], b: &[SMatrix<Complex64, D, D>]) -> f64 {
    let scale = b.iter().map(SMatrix::norm).fold(0.0, f64::max);
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
}

/// The factor's structural properties: causal, minimum phase, lag-0 lower triangular with a
/// positive real diagonal.
fn assert_structure(f: &SpectralFactor<3>, label: &str) {
    let mut p = CausalProjector::new(f.factor.len()).expect("even grid");
    let causal = p.negative_lag_fraction(&f.factor).expect("len");
    let inverse = f.inverse().expect("invertible");
    let inv_causal = p.negative_lag_fraction(&inverse).expect("len");
    let f0 = f.zero_lag();
    eprintln!("{label}: negative-lag energy F {causal:.1e}, F^-1 {inv_causal:.1e}");
    assert!(causal < 1e-20, "{label}: F not causal ({causal:e})");
    assert!(inv_causal < 1e-20, "{label}: F^-1 not causal ({inv_causal:e})");
    for i in 0..3 {
        assert!(
            f0[(i, i)].re > 0.0 && f0[(i, i)].im.abs() < 1e-12 * f0.norm(),
            "{label}: diag {f0}"
        );
        for j in i + 1..3 {
            assert!(
                f0[(i, j)].norm() < 1e-12 * f0.norm(),
                "{label}: upper triangle {f0}"
            );
        }
    }
}

#[test]
fn vector_ma2_factor_is_recovered() {
    let mut rng = Rng::new(2024);
    let b = [
        random_lower(&mut rng),
        random_real(&mut rng, 0.25),
        random_real(&mut rng, 0.15),
    ];
    // Brute-force minimum-phase check of the *true* factor on a fine grid: D^-1 causal.
    let fine = ma_on_grid(&b, 8192);
    let inverse: Vec<M3> = fine
        .iter()
        .map(|d| d.try_inverse().expect("invertible"))
        .collect();
    let neg = CausalProjector::new(8192)
        .expect("even")
        .negative_lag_fraction(&inverse)
        .expect("len");
    assert!(neg < 1e-24, "test factor is not minimum phase: {neg:e}");

    let r = max_zero_radius(&b);
    eprintln!("MA(2): largest zero radius of det D(z) = {r:.3}");
    assert!(r < 1.0);
    for n in [64, 256, 1024, 4096] {
        let d = ma_on_grid(&b, n);
        let f = wilson(&density(&d), &WilsonSettings::default()).expect("valid density");
        let err = rel_diff(&f.factor, &d);
        eprintln!(
            "MA(2) N={n}: {} iterations, converged {}, reconstruction {:.1e}, |F - D| {err:.1e}",
            f.iterations, f.converged, f.reconstruction_error
        );
        assert!(f.converged, "N={n}");
        assert_eq!(f.floored_bins, 0);
        assert!(f.reconstruction_error < 1e-10, "N={n}");
        // The factor's inverse decays like r^n: its wrap-around at lag N/2 limits any grid method.
        assert!(err < 1e-8 + r.powi(n as i32 / 2), "N={n}: factor error {err:e}");
        if r.powi(n as i32 / 2) < 1e-12 {
            assert_structure(&f, &format!("MA(2) N={n}"));
        }
    }
}

/// The largest modulus of the zeros of `det(sum_l B_l z^-l)` (minimum phase iff < 1), from the
/// roots of the polynomial `p(w) = det(sum_l B_l w^l)` (`w = 1/z`), whose coefficients are read off
/// an exact DFT of `p` on `P > deg p` points.
fn max_zero_radius(b: &[M3]) -> f64 {
    let degree = 3 * (b.len() - 1);
    let points = degree + 2;
    let values: Vec<Complex64> = ma_on_grid(b, points).iter().map(M3::determinant).collect();
    // ma_on_grid evaluates at w = e^{-2 pi i k / P}; coefficient j = (1/P) sum_k p_k w_k^{-j}.
    let coeff: Vec<f64> = (0..=degree)
        .map(|j| {
            (0..points)
                .map(|k| values[k] * z_pow(k, j, points).conj())
                .sum::<Complex64>()
                .re
                / points as f64
        })
        .collect();
    let companion = DMatrix::from_fn(degree, degree, |i, j| {
        if i == 0 {
            -coeff[degree - 1 - j] / coeff[degree]
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion
        .complex_eigenvalues()
        .iter()
        .map(|w| 1.0 / w.norm())
        .fold(0.0, f64::max)
}

/// `(I - A z^-1)^-1 B0` on the grid.
fn var1_on_grid(a: &M3, b0: &M3, n: usize) -> Vec<M3> {
    (0..n)
        .map(|k| {
            (M3::identity() - a * z_pow(k, 1, n))
                .try_inverse()
                .expect("stable")
                * b0
        })
        .collect()
}

fn scaled_to_radius(a: Matrix3<f64>, radius: f64) -> M3 {
    let rho = a
        .complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max);
    (a * (radius / rho)).map(c)
}

/// Factorises `S = D D^H` for `D = (I - A z^-1)^-1 B0`, `rho(A) = radius`, on grids `ns`; checks
/// convergence, and the factor error against the true `D` up to the wrap-around of its impulse
/// response (`~ radius^(N/2)`), which limits any grid method. Returns the factors and errors.
fn var1_case(seed: u64, radius: f64, ns: &[usize]) -> Vec<(SpectralFactor<3>, f64)> {
    let mut rng = Rng::new(seed);
    let b0 = random_lower(&mut rng);
    let a = scaled_to_radius(Matrix3::from_fn(|_, _| rng.normal()), radius);
    ns.iter()
        .map(|&n| {
            let d = var1_on_grid(&a, &b0, n);
            let f = wilson(&density(&d), &WilsonSettings::default()).expect("valid density");
            let err = rel_diff(&f.factor, &d);
            eprintln!(
                "VAR(1) rho={radius} N={n}: {} iterations, reconstruction {:.1e}, |F - D| {err:.1e}",
                f.iterations, f.reconstruction_error
            );
            assert!(f.converged && f.reconstruction_error < 1e-9, "rho={radius} N={n}");
            let alias = radius.powi(n as i32 / 2);
            assert!(
                err < 1e-8 + 10.0 * alias,
                "rho={radius} N={n}: factor error {err:e}"
            );
            if alias < 1e-12 {
                assert_structure(&f, &format!("VAR(1) rho={radius} N={n}"));
            }
            (f, err)
        })
        .collect()
}

#[test]
fn var1_factor_is_recovered() {
    var1_case(77, 0.5, &[64, 256, 1024, 4096]);
}

#[test]
fn var1_near_unit_root_converges_with_grid() {
    let errors: Vec<f64> = var1_case(78, 0.95, &[256, 1024, 4096])
        .into_iter()
        .map(|(_, e)| e)
        .collect();
    assert!(
        errors.windows(2).all(|w| w[1] < w[0]),
        "error should fall with N: {errors:?}"
    );
}

type S1 = SMatrix<Complex64, 1, 1>;

/// Scalar Wilson on `s` vs the cepstral factor; returns the Wilson result and their difference.
fn scalar_vs_cepstral(s: &[f64], label: &str) -> (SpectralFactor<1>, Vec<Complex64>, f64) {
    let grid: Vec<S1> = s.iter().map(|&v| S1::new(c(v))).collect();
    let f = wilson(&grid, &WilsonSettings::default()).expect("valid density");
    let d = min_phase_scalar_cepstral(s).expect("positive density");
    let reference: Vec<S1> = d.iter().map(|&z| S1::new(z)).collect();
    let err = rel_diff(&f.factor, &reference);
    eprintln!(
        "{label}: {} iterations, converged {}, reconstruction {:.1e}, |Wilson - cepstral| {err:.1e}",
        f.iterations, f.converged, f.reconstruction_error
    );
    assert!(f.converged && f.reconstruction_error < 1e-10, "{label}");
    assert_eq!(f.floored_bins, 0, "{label}");
    (f, d, err)
}

#[test]
fn scalar_wilson_matches_cepstral_and_closed_form() {
    // AR(1): d(z) = sigma / (1 - a z^-1), the closed-form minimum-phase factor.
    let (n, a, sigma) = (256, 0.8, 1.5);
    let exact: Vec<Complex64> = (0..n).map(|k| c(sigma) / (c(1.0) - z_pow(k, 1, n) * a)).collect();
    let s: Vec<f64> = exact.iter().map(Complex64::norm_sqr).collect();
    let (f, d, err) = scalar_vs_cepstral(&s, "AR(1) a=0.8 N=256");
    assert!(err < 1e-10);
    let scale = exact.iter().map(|z| z.norm()).fold(0.0, f64::max);
    for k in 0..n {
        assert!(
            (f.factor[k][0] - exact[k]).norm() < 1e-10 * scale,
            "Wilson vs closed form, bin {k}"
        );
        assert!(
            (d[k] - exact[k]).norm() < 1e-10 * scale,
            "cepstral vs closed form, bin {k}"
        );
    }

    // AR(2) with a sharp resonance: poles at radius 0.98, angle 0.3 pi (peak/valley ~ 1e4).
    let n = 4096;
    let (r, theta) = (0.98_f64, 0.3 * PI);
    let s: Vec<f64> = (0..n)
        .map(|k| {
            1.0 / (c(1.0) - z_pow(k, 1, n) * (2.0 * r * theta.cos()) + z_pow(k, 2, n) * (r * r)).norm_sqr()
        })
        .collect();
    assert!(scalar_vs_cepstral(&s, "AR(2) r=0.98 N=4096").2 < 1e-8);

    // Digital 4th-order Butterworth lowpass (|H|^2 = 1 / (1 + (tan(pi f) / tan(pi fc))^8), a
    // rational function of z, fc = fs/8) on a 1e-6 floor: a 60 dB stop band.
    let n = 2048;
    let s: Vec<f64> = (0..n)
        .map(|k| {
            let f = crate::spectral::grid::bin_frequency(k, n, 1.0);
            let t = (PI * f).tan() / (PI * 0.125).tan();
            1.0 / (1.0 + t.powi(8)) + 1e-6
        })
        .collect();
    assert!(scalar_vs_cepstral(&s, "Butterworth on 1e-6 floor N=2048").2 < 1e-8);
}

/// No NaN; every non-finite or unbounded figure is a failure.
fn assert_finite<const D: usize>(f: &SpectralFactor<D>) {
    assert!(
        f.factor
            .iter()
            .all(|m| m.iter().all(|z| z.re.is_finite() && z.im.is_finite()))
    );
    assert!(f.reconstruction_error.is_finite() && f.max_loading.is_finite());
}

/// Reconstruction error bound on floored input: the clamp moves each bin by at most
/// `sqrt(D) * max_loading` in Frobenius norm.
fn assert_error_within_loading(f: &SpectralFactor<3>, s: &[M3], label: &str) {
    let smallest = s.iter().map(M3::norm).fold(f64::INFINITY, f64::min);
    let bound = 3.0_f64.sqrt() * f.max_loading / smallest + 1e-9;
    eprintln!(
        "{label}: {} iterations, converged {}, floored {} of {} bins, max loading {:.1e}, \
         reconstruction {:.1e} (bound {bound:.1e})",
        f.iterations,
        f.converged,
        f.floored_bins,
        s.len(),
        f.max_loading,
        f.reconstruction_error
    );
    assert!(f.reconstruction_error <= bound, "{label}");
}

#[test]
fn rank_deficient_density_is_floored() {
    let mut rng = Rng::new(9);
    let n = 512;
    let c0 = Matrix3x2::from_fn(|_, _| c(rng.normal()));
    let c1 = Matrix3x2::from_fn(|_, _| c(0.3 * rng.normal()));
    let s: Vec<M3> = (0..n)
        .map(|k| {
            let d = c0 + c1 * z_pow(k, 1, n);
            d * d.adjoint()
        })
        .collect();
    let f = wilson(&s, &WilsonSettings::default()).expect("valid density");
    assert_finite(&f);
    assert_eq!(f.floored_bins, n, "every bin is rank 2");
    let max_trace = s.iter().map(|m| m.trace().re).fold(0.0, f64::max);
    assert!(f.max_loading > 0.0 && f.max_loading <= 1e-9 * max_trace * (1.0 + 1e-6));
    assert!(f.converged);
    assert_error_within_loading(&f, &s, "rank 2");
}

#[test]
fn deep_valley_is_floored() {
    // A zero at radius 1 - 1e-7 on channel 1: |1 - a z^-1|^2 = 1e-14 at DC.
    let mut rng = Rng::new(10);
    let n = 1024;
    let b0 = random_lower(&mut rng);
    let b1 = random_real(&mut rng, 0.2);
    let a = 1.0 - 1e-7;
    let s: Vec<M3> = (0..n)
        .map(|k| {
            let d = b0 + b1 * z_pow(k, 1, n);
            let valley = c(1.0) - z_pow(k, 1, n) * a;
            let d = M3::from_diagonal(&nalgebra::Vector3::new(valley, c(1.0), c(1.0))) * d;
            d * d.adjoint()
        })
        .collect();
    let f = wilson(&s, &WilsonSettings::default()).expect("valid density");
    assert_finite(&f);
    assert!(f.floored_bins > 0, "the valley must be floored");
    assert!(f.floored_bins < n, "only the valley");
    assert_error_within_loading(&f, &s, "1e-14 valley");
}

#[test]
fn non_convergence_is_reported_not_an_error() {
    let n = 1024;
    let s: Vec<S1> = (0..n)
        .map(|k| S1::new(c(1.0 / (c(1.0) - z_pow(k, 1, n) * 0.99).norm_sqr())))
        .collect();
    let settings = WilsonSettings {
        max_iter: 1,
        ..WilsonSettings::default()
    };
    let f = wilson(&s, &settings).expect("valid density");
    assert_eq!(f.iterations, 1);
    assert!(!f.converged);
    assert!(f.reconstruction_error > settings.tolerance && f.reconstruction_error.is_finite());
}

#[test]
fn bad_inputs_are_errors() {
    let ok = || vec![M3::identity(); 8];
    let run = |s: &[M3]| wilson(s, &WilsonSettings::default()).map(|_| ());
    assert_eq!(run(&[]), Err(FactorError::Empty));
    assert_eq!(run(&ok()[..7]), Err(FactorError::OddLength { len: 7 }));
    let mut s = ok();
    s[3][(1, 2)] = c(f64::NAN);
    assert_eq!(run(&s), Err(FactorError::NonFinite { bin: 3 }));
    let mut s = ok();
    s[5][(0, 0)] = c(f64::INFINITY);
    assert_eq!(run(&s), Err(FactorError::NonFinite { bin: 5 }));
    let mut s = ok();
    s[2] = M3::zeros();
    assert_eq!(run(&s), Err(FactorError::ZeroBin { bin: 2 }));
    let mut s = ok();
    s[6][(2, 0)] = c(0.1);
    assert!(matches!(run(&s), Err(FactorError::NonHermitian { bin: 6, asymmetry }) if asymmetry > 0.05));
    // Scalar and NaN in the first bin: an error, not a panic.
    let scalar = [S1::new(c(f64::NAN)), S1::new(c(1.0))];
    assert_eq!(
        wilson(&scalar, &WilsonSettings::default()),
        Err(FactorError::NonFinite { bin: 0 })
    );
}

#[test]
fn bad_settings_and_singular_covariance_are_errors() {
    let s = vec![M3::identity(); 4];
    for (settings, name) in [
        (
            WilsonSettings {
                tolerance: f64::NAN,
                ..WilsonSettings::default()
            },
            "tolerance",
        ),
        (
            WilsonSettings {
                eigen_floor: -1.0,
                ..WilsonSettings::default()
            },
            "eigen_floor",
        ),
        (
            WilsonSettings {
                hermitian_tolerance: f64::INFINITY,
                ..WilsonSettings::default()
            },
            "hermitian_tolerance",
        ),
        (
            WilsonSettings {
                max_iter: 0,
                ..WilsonSettings::default()
            },
            "max_iter",
        ),
    ] {
        assert!(
            matches!(wilson(&s, &settings), Err(FactorError::BadSetting { name: got, .. }) if got == name)
        );
    }
    // Exactly rank one everywhere, no floor: the lag-0 covariance has a zero pivot.
    let v = nalgebra::Vector3::new(c(1.0), c(2.0), c(0.0));
    let singular = vec![v * v.adjoint(); 4];
    let no_floor = WilsonSettings {
        eigen_floor: 0.0,
        ..WilsonSettings::default()
    };
    assert_eq!(wilson(&singular, &no_floor), Err(FactorError::SingularCovariance));
}

#[test]
fn inverse_reports_the_singular_bin() {
    let mut factor = vec![M3::identity(); 4];
    factor[2] = M3::from_diagonal(&nalgebra::Vector3::new(c(1.0), c(0.0), c(1.0)));
    let f = SpectralFactor {
        factor,
        iterations: 0,
        converged: true,
        reconstruction_error: 0.0,
        floored_bins: 0,
        max_loading: 0.0,
        from_start: false,
    };
    assert_eq!(f.inverse(), Err(FactorError::SingularFactor { bin: 2 }));
}

#[test]
fn slightly_non_hermitian_input_uses_its_hermitian_part() {
    let mut rng = Rng::new(12);
    let n = 128;
    let b = [random_lower(&mut rng), random_real(&mut rng, 0.2)];
    let s = density(&ma_on_grid(&b, n));
    let skewed: Vec<M3> = s
        .iter()
        .map(|m| m + M3::from_fn(|i, j| c(if i > j { 1e-9 } else { 0.0 })))
        .collect();
    let f = wilson(&skewed, &WilsonSettings::default()).expect("within the Hermitian tolerance");
    let exact = wilson(&s, &WilsonSettings::default()).expect("valid");
    assert!(rel_diff(&f.factor, &exact.factor) < 1e-8);
    let strict = WilsonSettings {
        hermitian_tolerance: 1e-12,
        ..WilsonSettings::default()
    };
    assert!(matches!(
        wilson(&skewed, &strict),
        Err(FactorError::NonHermitian { bin: 0, .. })
    ));
}

#[test]
fn a_start_from_a_nearby_density_factors_it_in_fewer_steps() {
    let mut rng = Rng::new(91);
    let b0 = random_lower(&mut rng);
    let a = scaled_to_radius(Matrix3::from_fn(|_, _| rng.normal()), 0.9);
    let n = 1024;
    // The same process estimated twice: the second density 1 % off, smoothly in frequency.
    let nearby = scaled_to_radius(
        a.map(|z| z.re) + Matrix3::from_fn(|_, _| 0.01 * rng.normal()),
        0.9,
    );
    let (before, after) = (var1_on_grid(&a, &b0, n), var1_on_grid(&nearby, &b0, n));
    let settings = WilsonSettings::default();
    let start = wilson(&density(&before), &settings).expect("valid density");
    let cold = wilson(&density(&after), &settings).expect("valid density");
    let warm = wilson_from(&density(&after), &settings, Some(&start.factor)).expect("valid density");
    eprintln!(
        "cold {} steps, from the nearby factor {}",
        cold.iterations, warm.iterations
    );
    assert!(cold.converged && warm.converged && warm.from_start && !cold.from_start);
    assert!(
        warm.iterations < cold.iterations,
        "{} vs {}",
        warm.iterations,
        cold.iterations
    );
    assert!(
        warm.reconstruction_error < 1e-9,
        "{:e}",
        warm.reconstruction_error
    );
    // The true factor (its impulse response decays as 0.9^l: 0.9^512 wraps around at 1e-23).
    assert!(rel_diff(&warm.factor, &after) < 1e-8, "not the true factor");
    assert!(rel_diff(&warm.factor, &cold.factor) < 1e-8);
    assert_structure(&warm, "from a nearby factor");
    // A start on another grid, or with a NaN, is not used: exactly the cold result.
    let other_grid = wilson_from(&density(&after), &settings, Some(&start.factor[..n / 2]));
    assert_eq!(other_grid.expect("valid"), cold);
    let mut broken = start.factor.clone();
    broken[3][(0, 0)] = Complex64::new(f64::NAN, 0.0);
    assert_eq!(
        wilson_from(&density(&after), &settings, Some(&broken)).expect("valid"),
        cold
    );
}
