use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use num_complex::Complex64;

use super::{InputEigen, RESOLUTION, explained};
use crate::rng::Rng;

fn complex_matrix(rng: &mut Rng) -> Matrix3<Complex64> {
    Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()))
}

/// `S_uu = V diag(eigenvalues) V^H` with a random unitary `V` (the eigenvectors of a random
/// Hermitian matrix).
fn input_spectrum(rng: &mut Rng, eigenvalues: [f64; 3]) -> Matrix3<Complex64> {
    let a = complex_matrix(rng);
    let v = SymmetricEigen::new(a + a.adjoint()).eigenvectors;
    let d = Matrix3::from_diagonal(&Vector3::from(eigenvalues).map(Complex64::from));
    v * d * v.adjoint()
}

/// A block `x = H u + n` with white noise of density `noise` on each output: its exact
/// spectra (no estimation error), so the residual is `noise I`.
fn spectra(
    rng: &mut Rng,
    eigenvalues: [f64; 3],
    noise: f64,
) -> (Matrix3<Complex64>, Matrix3<Complex64>, Matrix3<Complex64>) {
    let s_uu = input_spectrum(rng, eigenvalues);
    let h = complex_matrix(rng);
    let s_xu = h * s_uu;
    let s_xx = h * s_uu * h.adjoint() + Matrix3::identity() * Complex64::from(noise);
    (s_uu, s_xu, s_xx)
}

#[test]
fn explained_agrees_with_the_explicit_inverse_on_well_conditioned_inputs() {
    let mut rng = Rng::new(71);
    for _ in 0..20 {
        let (s_uu, s_xu, _) = spectra(&mut rng, [2.0, 1.0, 0.5], 0.0);
        let naive = s_xu * s_uu.try_inverse().unwrap() * s_xu.adjoint();
        let (stable, floored) = explained(&s_uu, &s_xu, 1e-9).unwrap();
        assert!(!floored);
        assert!(
            (stable - naive).norm() < 1e-12 * naive.norm(),
            "{stable} vs {naive}"
        );
    }
}

#[test]
fn the_residual_of_an_ill_conditioned_input_is_resolved_where_the_explicit_inverse_is_not() {
    // A sine on two axes: condition number 3e7 (the sine programme's bin at 7.2 Hz); the outputs'
    // noise is a millionth of their power.
    let mut rng = Rng::new(72);
    let noise = 1e-7;
    let mut naive_worst: f64 = 0.0;
    for _ in 0..20 {
        let (s_uu, s_xu, s_xx) = spectra(&mut rng, [367.0, 1.15e-5, 21.0], noise);
        let r = InputEigen::new(&s_uu, 0.0)
            .unwrap()
            .residual(&s_xx, &s_xu)
            .unwrap();
        let exact = Matrix3::identity() * Complex64::from(noise);
        assert!((r - exact).norm() < 1e-3 * noise, "{r} vs {exact}");
        let naive = s_xx - s_xu * s_uu.try_inverse().unwrap() * s_xu.adjoint();
        naive_worst = naive_worst.max((naive - exact).norm());
    }
    // The explicit inverse's rounding is at least the noise itself on some of these draws: the
    // test would fail a residual computed that way.
    assert!(
        naive_worst > 1e-3 * noise,
        "explicit inverse's worst error {naive_worst:e}"
    );
}

#[test]
fn a_residual_that_vanishes_is_floored_at_the_outputs_rounding() {
    let mut rng = Rng::new(73);
    let (s_uu, s_xu, s_xx) = spectra(&mut rng, [3.0, 2.0, 1.0], 0.0);
    let r = InputEigen::new(&s_uu, 1e-9)
        .unwrap()
        .residual(&s_xx, &s_xu)
        .unwrap();
    for i in 0..3 {
        let least = RESOLUTION * s_xx[(i, i)].re;
        assert!(
            r[(i, i)].re >= least && r[(i, i)].re < 1e-10 * s_xx[(i, i)].re,
            "{r}"
        );
    }
    // Its row weights are finite: the structural fit can divide by it.
    for w in super::super::identify::row_weights(&s_uu, &r, 10.0) {
        assert!(w.iter().all(|z| z.re.is_finite() && z.im.is_finite()), "{w}");
    }
}

#[test]
fn the_floor_is_said_and_singular_or_non_finite_inputs_are_refused() {
    let mut rng = Rng::new(74);
    // A diagonal S_uu with an eigenvalue below the floor: its floored inverse in closed form.
    let s_uu = Matrix3::from_diagonal(&Vector3::new(1.0, 1e-12, 2.0).map(Complex64::from));
    let s_xu = complex_matrix(&mut rng);
    let (with_floor, floored) = explained(&s_uu, &s_xu, 1e-6).unwrap();
    assert!(floored);
    let inv = Matrix3::from_diagonal(&Vector3::new(1.0, 1e6, 0.5).map(Complex64::from));
    let naive = s_xu * inv * s_xu.adjoint();
    assert!((InputEigen::new(&s_uu, 1e-6).unwrap().inverse() - inv).norm() < 1e-9 * inv.norm());
    assert!((with_floor - naive).norm() < 1e-9 * naive.norm());
    let (s_uu, s_xu, _) = spectra(&mut rng, [1.0, 1e-12, 1.0], 0.0);
    let singular = input_spectrum(&mut rng, [1.0, 0.0, 1.0]);
    let exact_zero = Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 1.0).map(Complex64::from));
    assert!(explained(&exact_zero, &s_xu, 0.0).is_none());
    assert!(explained(&singular, &s_xu, 1e-9).is_some());
    let mut nan = s_uu;
    nan[(0, 0)] = Complex64::new(f64::NAN, 0.0);
    assert!(explained(&nan, &s_xu, 1e-9).is_none());
    let mut nan_xu = s_xu;
    nan_xu[(1, 2)] = Complex64::new(0.0, f64::INFINITY);
    assert!(
        InputEigen::new(&s_uu, 1e-9)
            .unwrap()
            .residual(&s_uu, &nan_xu)
            .is_none()
    );
}

#[test]
fn one_decomposition_gives_the_inverse_and_the_residual() {
    let mut rng = Rng::new(75);
    let (s_uu, s_xu, s_xx) = spectra(&mut rng, [2.0, 0.5, 0.1], 0.3);
    let eig = InputEigen::new(&s_uu, 0.0).unwrap();
    assert!(!eig.floored());
    // Against nalgebra's LU inverse on a well-conditioned S_uu.
    let lu = s_uu.try_inverse().unwrap();
    assert!(
        (eig.inverse() - lu).norm() < 1e-12 * lu.norm(),
        "{}",
        eig.inverse() - lu
    );
    // The residual through the explicit inverse agrees where S_uu is well-conditioned.
    let naive = s_xx - s_xu * lu * s_xu.adjoint();
    let r = eig.residual(&s_xx, &s_xu).unwrap();
    assert!((r - naive).norm() < 1e-12 * s_xx.norm(), "{}", r - naive);
    // A non-finite output spectrum is refused, not carried.
    let mut bad = s_xx;
    bad[(2, 2)] = Complex64::new(f64::NAN, 0.0);
    assert!(eig.residual(&bad, &s_xu).is_none());
}
