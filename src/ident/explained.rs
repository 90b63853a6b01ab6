//! The part of a block's output spectrum its inputs explain, `S_xu S_uu^-1 S_ux`, and the
//! residual (disturbance) spectrum `S_psi = S_xx - S_xu S_uu^-1 S_ux`, at one bin.
//!
//! Computed along `S_uu`'s eigenvectors `v_k`: `sum_k (S_xu v_k)(S_xu v_k)^H / lambda_k`. Where
//! `S_uu` is ill-conditioned (a stand's sine on two axes and nothing on the third: condition
//! numbers of 1e7 at the sine's bin) the explicit product `(S_xu S_uu^-1) S_ux` sums terms of
//! `|S_xu|^2 / lambda_min`, ten million times the output's power, that cancel to it: the residual
//! then carries rounding of 1e-6 of the output's power, more than a gyro's own noise, and came
//! out negative (a non-finite structural weight followed). Along the eigenvectors the term of a
//! small `lambda_k` is `|S_xu v_k|^2 / lambda_k`, itself of the order of the output's power, and
//! the residual is resolved to the rounding of `S_xx`.
//!
//! Units: those of the spectra (output units squared per Hz for `S_xx`). Contracts: `S_uu` is
//! made Hermitian first; its eigenvalues are floored at `floor` (the identifier's
//! [`super::factorisation::input_floor`]) and the result says whether the floor was needed; with
//! `floor` 0 an eigenvalue that is not positive gives `None` (a singular `S_uu`), as does any
//! value that is not finite. The residual's diagonal is never below [`RESOLUTION`] of `S_xx`'s:
//! below that it is rounding, and the row weights `n_eq S_uu / S_psi,ii` divide by it.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use num_complex::Complex64;

/// The residual's diagonal is not resolved below this fraction of the output's own power: a few
/// hundred roundings of `S_xx,ii` (the Welch sums' and this subtraction's).
pub const RESOLUTION: f64 = 256.0 * f64::EPSILON;

/// `S_uu`'s eigen decomposition at one bin, its eigenvalues floored: the one decomposition its
/// inverse, the explained part and the residual are all taken from.
#[derive(Debug, Clone)]
pub struct InputEigen {
    vectors: Matrix3<Complex64>,
    values: Vector3<f64>,
    floored: bool,
}

impl InputEigen {
    /// The decomposition of `S_uu` (made Hermitian) with its eigenvalues floored at `floor`;
    /// `None` when not finite, or when an eigenvalue is not positive after the floor (a singular
    /// `S_uu` with `floor` 0).
    #[must_use]
    pub fn new(s_uu: &Matrix3<Complex64>, floor: f64) -> Option<Self> {
        if !finite(s_uu) {
            return None;
        }
        let eig = SymmetricEigen::new((s_uu + s_uu.adjoint()) * Complex64::from(0.5));
        let mut floored = false;
        let mut values = eig.eigenvalues;
        for lambda in values.iter_mut() {
            if !lambda.is_finite() {
                return None;
            }
            if *lambda < floor {
                floored = true;
                *lambda = floor;
            }
            if *lambda <= 0.0 {
                return None;
            }
        }
        Some(Self {
            vectors: eig.eigenvectors,
            values,
            floored,
        })
    }

    /// Whether the floor was needed.
    #[must_use]
    pub fn floored(&self) -> bool {
        self.floored
    }

    /// The (floored) inverse `S_uu^-1`.
    #[must_use]
    pub fn inverse(&self) -> Matrix3<Complex64> {
        let inv = self.values.map(|l| Complex64::from(1.0 / l));
        self.vectors * Matrix3::from_diagonal(&inv) * self.vectors.adjoint()
    }

    /// `S_xu S_uu^-1 S_ux` (exactly Hermitian); `None` when not finite.
    #[must_use]
    pub fn explained(&self, s_xu: &Matrix3<Complex64>) -> Option<Matrix3<Complex64>> {
        if !finite(s_xu) {
            return None;
        }
        let mut sum = Matrix3::<Complex64>::zeros();
        for k in 0..3 {
            let b = s_xu * self.vectors.column(k);
            sum += b * b.adjoint() / Complex64::from(self.values[k]);
        }
        let sum = (sum + sum.adjoint()) * Complex64::from(0.5);
        finite(&sum).then_some(sum)
    }

    /// `S_psi = S_xx - S_xu S_uu^-1 S_ux` (exactly Hermitian, its diagonal at least
    /// [`RESOLUTION`] of `S_xx`'s); `None` when not finite.
    #[must_use]
    pub fn residual(
        &self,
        s_xx: &Matrix3<Complex64>,
        s_xu: &Matrix3<Complex64>,
    ) -> Option<Matrix3<Complex64>> {
        if !finite(s_xx) {
            return None;
        }
        let r = s_xx - self.explained(s_xu)?;
        let mut r = (r + r.adjoint()) * Complex64::from(0.5);
        for i in 0..3 {
            let least = RESOLUTION * s_xx[(i, i)].re.abs();
            r[(i, i)] = Complex64::from(r[(i, i)].re.max(least));
        }
        finite(&r).then_some(r)
    }
}

fn finite(m: &Matrix3<Complex64>) -> bool {
    m.iter().all(|z| z.re.is_finite() && z.im.is_finite())
}

/// `S_xu S_uu^-1 S_ux` (exactly Hermitian) with `S_uu`'s eigenvalues floored at `floor`, and
/// whether the floor was needed; `None` when not finite, or singular with `floor` 0.
#[must_use]
pub fn explained(
    s_uu: &Matrix3<Complex64>,
    s_xu: &Matrix3<Complex64>,
    floor: f64,
) -> Option<(Matrix3<Complex64>, bool)> {
    let eig = InputEigen::new(s_uu, floor)?;
    Some((eig.explained(s_xu)?, eig.floored()))
}

#[cfg(test)]
#[path = "explained_tests.rs"]
mod tests;
