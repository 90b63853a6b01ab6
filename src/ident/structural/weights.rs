//! Validation of the weights and their square roots: every input form becomes, per bin and
//! output row, the Hermitian positive semi-definite `Omega_i` and a factor `L_i` with
//! `L_i L_i^H = Omega_i`, so that `r_i Omega_i r_i^H = |r_i L_i|^2` (whitening).

use nalgebra::{Matrix3, SymmetricEigen};
use num_complex::Complex64;

use super::{StructuralError, Weights};

/// Relative tolerance of the Hermitian and semi-definiteness checks.
const TOLERANCE: f64 = 1e-9;

/// One output row's weight at one bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RowWeight {
    /// `Omega_i`, exactly Hermitian.
    pub omega: Matrix3<Complex64>,
    /// `L_i` with `L_i L_i^H = Omega_i` (eigen square root; negative rounding eigenvalues
    /// clamped to zero).
    pub white: Matrix3<Complex64>,
    /// The rank of `Omega_i` (eigenvalues above [`TOLERANCE`] of the largest): the row's complex
    /// degrees of freedom, `2 rank` real ones in its chi2.
    pub rank: u8,
}

/// Validates `weights` and returns, per bin, the three rows' weights.
pub(super) fn row_weights(weights: &Weights) -> Result<Vec<[RowWeight; 3]>, StructuralError> {
    match weights {
        Weights::Variance(variance) => variance
            .iter()
            .enumerate()
            .map(|(bin, v)| from_variance(bin, v))
            .collect(),
        Weights::RowWeight(rows) => rows
            .iter()
            .enumerate()
            .map(|(bin, m)| {
                Ok([
                    from_matrix(bin, 0, &m[0])?,
                    from_matrix(bin, 1, &m[1])?,
                    from_matrix(bin, 2, &m[2])?,
                ])
            })
            .collect(),
    }
}

/// The diagonal special case, `Omega_i = diag(1 / variance_ij)`.
fn from_variance(bin: usize, v: &Matrix3<f64>) -> Result<[RowWeight; 3], StructuralError> {
    for row in 0..3 {
        for col in 0..3 {
            let value = v[(row, col)];
            if !value.is_finite() {
                return Err(StructuralError::NonFiniteVariance { bin, row, col });
            }
            if value <= 0.0 || !(1.0 / value).is_finite() {
                return Err(StructuralError::NonPositiveVariance { bin, row, col, value });
            }
        }
    }
    Ok(std::array::from_fn(|row| {
        let diag = |f: fn(f64) -> f64| {
            Matrix3::from_fn(|j, l| Complex64::new(if j == l { f(v[(row, j)]) } else { 0.0 }, 0.0))
        };
        RowWeight {
            omega: diag(|x| 1.0 / x),
            white: diag(|x| 1.0 / x.sqrt()),
            rank: 3,
        }
    }))
}

/// A general row weight: finite, Hermitian, positive semi-definite.
fn from_matrix(bin: usize, row: usize, m: &Matrix3<Complex64>) -> Result<RowWeight, StructuralError> {
    if m.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return Err(StructuralError::NonFiniteWeight { bin, row });
    }
    let scale = m.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let adjoint = m.adjoint();
    if (m - adjoint).iter().any(|z| z.norm() > TOLERANCE * scale) {
        return Err(StructuralError::NonHermitianWeight { bin, row });
    }
    let omega = (m + adjoint).map(|z| z * 0.5);
    let eigen = SymmetricEigen::new(omega);
    let lowest = eigen.eigenvalues.iter().copied().fold(f64::INFINITY, f64::min);
    let trace: f64 = (0..3).map(|j| omega[(j, j)].re).sum();
    if !lowest.is_finite() || lowest < -TOLERANCE * trace.max(0.0) {
        return Err(StructuralError::IndefiniteWeight {
            bin,
            row,
            eigenvalue: lowest,
        });
    }
    let roots = eigen.eigenvalues.map(|l| l.max(0.0).sqrt());
    let white = Matrix3::from_fn(|j, l| eigen.eigenvectors[(j, l)] * roots[l]);
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let rank = eigen
        .eigenvalues
        .iter()
        .filter(|&&l| l > TOLERANCE * largest && l > 0.0)
        .count();
    Ok(RowWeight {
        omega,
        white,
        rank: u8::try_from(rank).unwrap_or(3),
    })
}

impl RowWeight {
    /// The weight `Omega_i / scale` (`scale > 0`), without a new eigen decomposition: its
    /// square root is `L_i / sqrt(scale)` and its rank is unchanged.
    #[must_use]
    pub fn unscaled(&self, scale: f64) -> Self {
        debug_assert!(scale.is_finite() && scale > 0.0, "scale {scale}");
        Self {
            omega: self.omega.unscale(scale),
            white: self.white.unscale(scale.sqrt()),
            rank: self.rank,
        }
    }

    /// The whitened row `r L_i`.
    pub fn whiten(&self, r: &[Complex64; 3]) -> [Complex64; 3] {
        std::array::from_fn(|l| (0..3).map(|j| r[j] * self.white[(j, l)]).sum())
    }

    /// `r Omega_i r^H` (real up to rounding; the real part).
    pub fn quadratic(&self, r: &[Complex64; 3]) -> f64 {
        let mut q = 0.0;
        for j in 0..3 {
            for l in 0..3 {
                q += (r[j] * self.omega[(j, l)] * r[l].conj()).re;
            }
        }
        q
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::from_matrix;
    use crate::rng::Rng;

    /// A weight divided by a scale without a new decomposition is the decomposition of the
    /// divided weight: the same `Omega`, a square root with `L L^H = Omega / scale`, the same
    /// rank (full and singular).
    #[test]
    fn an_unscaled_weight_is_the_weight_divided() {
        let mut rng = Rng::new(11);
        for singular in [false, true] {
            let a = Matrix3::from_fn(|_, j| {
                if singular && j == 2 {
                    Complex64::from(0.0)
                } else {
                    Complex64::new(rng.normal(), rng.normal())
                }
            });
            let m = a * a.adjoint();
            let w = from_matrix(0, 0, &m).unwrap();
            for scale in [0.01, 0.37, 5.0] {
                let got = w.unscaled(scale);
                let want = from_matrix(0, 0, &(m / Complex64::from(scale))).unwrap();
                let size = want.omega.norm();
                assert!((got.omega - want.omega).norm() < 1e-14 * size, "{scale}");
                let square = got.white * got.white.adjoint();
                assert!((square - want.omega).norm() < 1e-12 * size, "{scale}");
                assert_eq!(got.rank, want.rank);
                assert_eq!(got.rank, if singular { 2 } else { 3 });
            }
        }
    }
}
