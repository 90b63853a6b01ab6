//! Trigonometric interpolation of a function on the two-sided FFT grid onto a grid `r` times
//! finer (the same conventions as [`super::causal`]: FFT order, lags `h[n]` by the inverse DFT).
//!
//! A function whose lags lie within `-N/2 < n < N/2` (a Welch estimate on a zero-padded grid:
//! its lags stop at the segment length) is a trigonometric polynomial, so its values on the finer
//! grid are exact: the lags are moved to a grid of `r N` bins, non-negative ones at the front and
//! negative ones at the back, and transformed forward. Bin `k` of the input is bin `r k` of the
//! output. The Nyquist lag (`+N/2` and `-N/2` on the input's circle) is split in two halves, so a
//! Hermitian density stays Hermitian.
//!
//! Why: the identifier's spectral factor and causal projection are computed on a finite grid.
//! Wilson's iteration involves the factor's inverse, whose impulse response grows long when the
//! density has a large dynamic range (an input whose power is concentrated far below the band's
//! top); on a grid that cannot hold it, the factor comes out with energy at negative lags, and the
//! causal projection then cuts part of the gain itself. A finer grid holds it
//! (`ident::factorisation` refines until the factor is causal).
//!
//! Contracts: `r >= 1`; the input's length `N` must be even and non-zero, else a
//! [`RefineError`]; NaN or infinite inputs spread over their element's whole output, as in any
//! FFT. Units are those of the input.

use nalgebra::SMatrix;
use num_complex::Complex64;
use rustfft::FftPlanner;

/// Why a refinement was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RefineError {
    /// The grid length is zero or odd.
    #[error("refinement needs an even, non-zero grid length, got {len}")]
    BadGridLength {
        /// The input's length.
        len: usize,
    },
    /// The refinement factor is zero.
    #[error("refinement factor must be at least 1")]
    ZeroFactor,
}

/// `f` (two-sided, `N` bins) interpolated onto `r N` bins; bin `r k` of the result is `f[k]`.
///
/// # Errors
/// [`RefineError`] for an odd or empty grid or `r = 0`.
pub fn refined<const R: usize, const C: usize>(
    f: &[SMatrix<Complex64, R, C>],
    r: usize,
) -> Result<Vec<SMatrix<Complex64, R, C>>, RefineError> {
    let n = f.len();
    if n == 0 || !n.is_multiple_of(2) {
        return Err(RefineError::BadGridLength { len: n });
    }
    if r == 0 {
        return Err(RefineError::ZeroFactor);
    }
    if r == 1 {
        return Ok(f.to_vec());
    }
    let fine = r * n;
    let mut planner = FftPlanner::<f64>::new();
    let inverse = planner.plan_fft_inverse(n);
    let forward = planner.plan_fft_forward(fine);
    let mut out = vec![SMatrix::<Complex64, R, C>::zeros(); fine];
    let mut lags = vec![Complex64::ZERO; n];
    let mut spread = vec![Complex64::ZERO; fine];
    let half = n / 2;
    let scale = 1.0 / n as f64;
    for i in 0..R {
        for j in 0..C {
            lags.iter_mut().zip(f).for_each(|(l, m)| *l = m[(i, j)]);
            inverse.process(&mut lags);
            spread.fill(Complex64::ZERO);
            spread[..half].copy_from_slice(&lags[..half]);
            spread[fine - half + 1..].copy_from_slice(&lags[half + 1..]);
            spread[half] = lags[half] * 0.5;
            spread[fine - half] = lags[half] * 0.5;
            for z in &mut spread {
                *z *= scale;
            }
            forward.process(&mut spread);
            out.iter_mut().zip(&spread).for_each(|(m, z)| m[(i, j)] = *z);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix2;

    use super::*;

    /// `F(z) = sum_n h[n] z^-n` evaluated directly at `z = e^{2 pi i k / M}`.
    fn direct(h: &[(i64, Matrix2<Complex64>)], k: usize, m: usize) -> Matrix2<Complex64> {
        h.iter().fold(Matrix2::zeros(), |acc, (n, c)| {
            let phase = -2.0 * std::f64::consts::PI * (k as f64) * (*n as f64) / m as f64;
            acc + c * Complex64::from_polar(1.0, phase)
        })
    }

    fn lags() -> Vec<(i64, Matrix2<Complex64>)> {
        let c = |a: f64, b: f64| Complex64::new(a, b);
        vec![
            (
                0,
                Matrix2::new(c(2.0, 0.0), c(0.3, 0.1), c(0.3, -0.1), c(1.0, 0.0)),
            ),
            (
                1,
                Matrix2::new(c(0.5, 0.2), c(-0.1, 0.0), c(0.05, 0.4), c(0.2, -0.3)),
            ),
            (
                -3,
                Matrix2::new(c(-0.2, 0.1), c(0.0, 0.7), c(0.1, 0.1), c(0.6, 0.0)),
            ),
            (
                5,
                Matrix2::new(c(0.01, -0.02), c(0.3, 0.3), c(-0.4, 0.0), c(0.0, 0.05)),
            ),
        ]
    }

    #[test]
    fn a_trigonometric_polynomial_is_exact_on_the_finer_grid() {
        let h = lags();
        let n = 16;
        let coarse: Vec<_> = (0..n).map(|k| direct(&h, k, n)).collect();
        for r in [1, 2, 4, 8] {
            let fine = refined(&coarse, r).unwrap();
            assert_eq!(fine.len(), r * n);
            for (k, m) in fine.iter().enumerate() {
                let want = direct(&h, k, r * n);
                assert!((m - want).norm() < 1e-12, "r {r} bin {k}: {m} vs {want}");
            }
        }
    }

    #[test]
    fn the_input_bins_are_kept_and_a_hermitian_density_stays_hermitian() {
        // A density with energy at the Nyquist lag: the split keeps every bin Hermitian.
        let n = 8;
        let c = |a: f64, b: f64| Complex64::new(a, b);
        let h = [(
            0i64,
            Matrix2::new(c(3.0, 0.0), c(0.2, 0.5), c(0.2, -0.5), c(2.0, 0.0)),
        )];
        let mut coarse: Vec<_> = (0..n).map(|k| direct(&h, k, n)).collect();
        for (k, m) in coarse.iter_mut().enumerate() {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            *m += Matrix2::new(c(0.4 * sign, 0.0), c(0.0, 0.0), c(0.0, 0.0), c(0.1 * sign, 0.0));
        }
        let fine = refined(&coarse, 4).unwrap();
        for (k, m) in coarse.iter().enumerate() {
            assert!((fine[4 * k] - m).norm() < 1e-12, "bin {k}");
        }
        for m in &fine {
            assert!((m - m.adjoint()).norm() < 1e-12);
        }
    }

    #[test]
    fn bad_grids_and_factors_are_refused() {
        let one = vec![Matrix2::<Complex64>::identity(); 3];
        assert_eq!(refined(&one, 2), Err(RefineError::BadGridLength { len: 3 }));
        assert_eq!(
            refined::<2, 2>(&[], 2),
            Err(RefineError::BadGridLength { len: 0 })
        );
        let two = vec![Matrix2::<Complex64>::identity(); 4];
        assert_eq!(refined(&two, 0), Err(RefineError::ZeroFactor));
    }
}
