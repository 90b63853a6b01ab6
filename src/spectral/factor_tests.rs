//! Tests of [`super::wilson`]: known factors, the scalar cepstral reference, near-singular input
//! and bad input. Figures are printed to stderr (`cargo test -- --nocapture`).

use super::*;
use crate::rng::Rng;
use nalgebra::{DMatrix, Matrix3};
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
    (0..n).map(|k| b.iter().enumerate().map(|(l, bl)| bl * z_pow(k, l, n)).sum()).collect()
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
        assert!(f0[(i, i)].re > 0.0 && f0[(i, i)].im.abs() < 1e-12 * f0.norm(), "{label}: diag {f0}");
        for j in i + 1..3 {
            assert!(f0[(i, j)].norm() < 1e-12 * f0.norm(), "{label}: upper triangle {f0}");
        }
    }
}

#[test]
fn vector_ma2_factor_is_recovered() {
    let mut rng = Rng::new(2024);
    let b = [random_lower(&mut rng), random_real(&mut rng, 0.25), random_real(&mut rng, 0.15)];
    // Brute-force minimum-phase check of the *true* factor on a fine grid: D^-1 causal.
    let fine = ma_on_grid(&b, 8192);
    let inverse: Vec<M3> = fine.iter().map(|d| d.try_inverse().expect("invertible")).collect();
    let neg = CausalProjector::new(8192).expect("even").negative_lag_fraction(&inverse).expect("len");
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
        .map(|j| (0..points).map(|k| values[k] * z_pow(k, j, points).conj()).sum::<Complex64>().re / points as f64)
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
    companion.complex_eigenvalues().iter().map(|w| 1.0 / w.norm()).fold(0.0, f64::max)
}

/// `(I - A z^-1)^-1 B0` on the grid.
fn var1_on_grid(a: &M3, b0: &M3, n: usize) -> Vec<M3> {
    (0..n)
        .map(|k| (M3::identity() - a * z_pow(k, 1, n)).try_inverse().expect("stable") * b0)
        .collect()
}

fn scaled_to_radius(a: Matrix3<f64>, radius: f64) -> M3 {
    let rho = a.complex_eigenvalues().iter().map(|l| l.norm()).fold(0.0, f64::max);
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
            assert!(err < 1e-8 + 10.0 * alias, "rho={radius} N={n}: factor error {err:e}");
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
    let errors: Vec<f64> = var1_case(78, 0.95, &[256, 1024, 4096]).into_iter().map(|(_, e)| e).collect();
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "error should fall with N: {errors:?}");
}
