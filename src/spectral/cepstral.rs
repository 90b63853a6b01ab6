//! Scalar minimum-phase spectral factor by the Kolmogorov (cepstral) method.
//!
//! An independent reference for the matrix factoriser of [`super::factor`] at size 1: for a
//! positive density `s` on the two-sided grid, `log s` has the lag sequence (cepstrum)
//! `c[n] = (1/N) sum_k log s[k] e^{+2 pi i k n / N}`; the minimum-phase factor is
//! `d = exp(FFT(c_+))` with `c_+[0] = c[0] / 2`, `c_+[n] = c[n]` for `0 < n < N/2`,
//! `c_+[N/2] = c[N/2] / 2` and the negative lags zeroed (the projection
//! [`super::causal::CausalProjector::causal_part_half_zero_lag`]). Then `|d|^2 = s` on the grid,
//! `d` is causal and minimum phase (its logarithm is causal), and its lag-0 term
//! `exp(c[0] / 2) = exp(mean log s / 2)` is real and positive (the Kolmogorov-Szego formula) —
//! the same normalisation as [`super::factor::wilson`].
//!
//! # Contracts
//! - Grid convention of [`super::grid`]: `N` bins, FFT order, `N` even and non-zero.
//! - Every bin must be finite and strictly positive: a zero bin has no logarithm. Violations are
//!   errors ([`CepstralError`]), never NaN outputs.
//! - Units: `d` has the square root of the units of `s`.
//! - Accuracy is limited by cepstral aliasing: the cepstrum decays like the factor's impulse response
//!   (for a pole at radius `r`, like `r^n / n`), so the grid needs `r^(N/2)` negligible.

use nalgebra::SMatrix;
use num_complex::Complex64;

use super::causal::{CausalError, CausalProjector};

/// Why the cepstral factor was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CepstralError {
    /// Empty or odd-length grid.
    #[error("cepstral factor needs an even, non-zero grid length, got {len}")]
    BadGridLength {
        /// The input length.
        len: usize,
    },
    /// A bin is NaN, infinite, zero or negative.
    #[error("bin {bin} of the density is {value}: the cepstral method needs finite positive values")]
    NotPositive {
        /// The first offending bin.
        bin: usize,
        /// Its value.
        value: f64,
    },
}

impl From<CausalError> for CepstralError {
    fn from(e: CausalError) -> Self {
        match e {
            CausalError::BadGridLength { len } | CausalError::LengthMismatch { found: len, .. } => {
                Self::BadGridLength { len }
            }
        }
    }
}

/// The minimum-phase factor `d` with `|d[k]|^2 = s[k]` of a scalar two-sided density `s`.
///
/// # Errors
/// [`CepstralError::BadGridLength`] for an empty or odd-length `s`;
/// [`CepstralError::NotPositive`] if any bin is not finite and strictly positive.
pub fn min_phase_scalar_cepstral(s: &[f64]) -> Result<Vec<Complex64>, CepstralError> {
    let mut projector = CausalProjector::new(s.len())?;
    if let Some((bin, &value)) = s.iter().enumerate().find(|&(_, v)| !(v.is_finite() && *v > 0.0)) {
        return Err(CepstralError::NotPositive { bin, value });
    }
    let mut log_s: Vec<SMatrix<Complex64, 1, 1>> = s
        .iter()
        .map(|&v| SMatrix::from_element(Complex64::new(v.ln(), 0.0)))
        .collect();
    projector.causal_part_half_zero_lag(&mut log_s)?;
    Ok(log_s.iter().map(|m| m[0].exp()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn ar1_closed_form() {
        // d(z) = sigma / (1 - a z^-1) is minimum phase for |a| < 1; s = |d|^2.
        for &(n, a, sigma) in &[(64_usize, 0.3, 2.0), (256, -0.6, 0.5), (1024, 0.9, 1.0)] {
            let exact: Vec<Complex64> = (0..n)
                .map(|k| {
                    let z_inv = Complex64::from_polar(1.0, -2.0 * PI * k as f64 / n as f64);
                    Complex64::from(sigma) / (Complex64::from(1.0) - z_inv * a)
                })
                .collect();
            let s: Vec<f64> = exact.iter().map(Complex64::norm_sqr).collect();
            let d = min_phase_scalar_cepstral(&s).expect("positive density");
            let err = d
                .iter()
                .zip(&exact)
                .map(|(x, y)| (x - y).norm() / y.norm())
                .fold(0.0, f64::max);
            assert!(err < 1e-12, "n={n} a={a}: relative error {err}");
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert_eq!(
            min_phase_scalar_cepstral(&[]),
            Err(CepstralError::BadGridLength { len: 0 })
        );
        assert_eq!(
            min_phase_scalar_cepstral(&[1.0; 5]),
            Err(CepstralError::BadGridLength { len: 5 })
        );
        assert_eq!(
            min_phase_scalar_cepstral(&[1.0, 2.0, 0.0, 1.0]),
            Err(CepstralError::NotPositive { bin: 2, value: 0.0 })
        );
        assert_eq!(
            min_phase_scalar_cepstral(&[1.0, -2.0, 1.0, 1.0]),
            Err(CepstralError::NotPositive { bin: 1, value: -2.0 })
        );
        assert!(matches!(
            min_phase_scalar_cepstral(&[1.0, 1.0, 1.0, f64::NAN]),
            Err(CepstralError::NotPositive { bin: 3, .. })
        ));
    }
}
