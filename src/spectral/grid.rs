//! One-sided <-> two-sided spectral density grids.
//!
//! # Conventions
//! - The **two-sided** grid has `N` bins (`N` even, `N >= 2`) in FFT order: bin `k` is the frequency
//!   `k * fs / N` for `k = 0..=N/2`, and bin `N - k` is the frequency `-k * fs / N`. Bin `N/2` is
//!   the Nyquist frequency `fs / 2` (it is its own negative). A two-sided density integrates over
//!   `[-fs/2, fs/2)` to the covariance: `R(0) = (fs / N) * sum_k S[k]` in units of `x^2 / Hz`.
//! - The **one-sided** grid holds bins `0..=N/2` of a one-sided density as Welch's method returns
//!   it: interior bins (`0 < f < fs/2`) carry the factor 2 that folds the negative frequencies in;
//!   DC and Nyquist do not.
//! - For a real process `S(-f) = conj(S(f)) = S(f)^T` (elementwise conjugate; equal to the
//!   transpose because `S(f)` is Hermitian). That is how the negative frequencies are filled.
//!
//! A spectral factor `D` with `D D^H = S` must be taken of the **two-sided** density for the
//! Wiener-Kolmogorov formulas (`Phi = Gamma^-1 [T]_+ D^-1` etc.): a factor of the one-sided
//! density would be `sqrt(2)` too large in the interior and wrong at DC and Nyquist.
//!
//! # Contracts
//! - Empty or too-short inputs are errors ([`GridError`]); nothing panics.
//! - Values are copied and scaled only: NaN and infinities pass through unchanged (they are
//!   checked where they matter, e.g. by the factoriser).
//! - Units: the density units are whatever the input carries; only the factor 2 changes.

use nalgebra::SMatrix;
use num_complex::Complex64;

/// Why a grid conversion was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GridError {
    /// The one-sided input has fewer than the 2 bins (DC and Nyquist) of the smallest grid `N = 2`.
    #[error("one-sided grid needs at least 2 bins (DC and Nyquist), got {len}")]
    TooShortOneSided {
        /// The number of bins given.
        len: usize,
    },
    /// The two-sided input is empty or has an odd length.
    #[error("two-sided grid needs an even, non-zero number of bins, got {len}")]
    BadTwoSidedLength {
        /// The number of bins given.
        len: usize,
    },
}

/// The frequency of bin `k` of a two-sided grid of `n` bins at sample rate `fs` (Hz), FFT order:
/// `k * fs / n` for `k <= n/2` (so the Nyquist bin is `+fs/2`), `(k - n) * fs / n` above.
#[must_use]
pub fn bin_frequency(k: usize, n: usize, fs: f64) -> f64 {
    let k = k % n.max(1);
    if 2 * k <= n {
        k as f64 * fs / n as f64
    } else {
        -((n - k) as f64) * fs / n as f64
    }
}

/// The two-sided density on all `N = 2 * (len - 1)` bins from bins `0..=N/2` of a one-sided one.
///
/// Interior bins are halved, DC and Nyquist kept, and bin `N - k` (frequency `-f_k`) is filled with
/// `conj(S[k])` elementwise (= `S[k]^T` for Hermitian bins, the real-process symmetry).
///
/// # Errors
/// [`GridError::TooShortOneSided`] if `one_sided` has fewer than 2 bins.
pub fn two_sided_from_one_sided<const R: usize, const C: usize>(
    one_sided: &[SMatrix<Complex64, R, C>],
) -> Result<Vec<SMatrix<Complex64, R, C>>, GridError> {
    let m = one_sided.len();
    if m < 2 {
        return Err(GridError::TooShortOneSided { len: m });
    }
    let n = 2 * (m - 1);
    let mut out = Vec::with_capacity(n);
    out.push(one_sided[0]);
    out.extend(one_sided[1..m - 1].iter().map(|s| s * Complex64::new(0.5, 0.0)));
    out.push(one_sided[m - 1]);
    out.extend(
        one_sided[1..m - 1]
            .iter()
            .rev()
            .map(|s| s.map(|z| z.conj() * 0.5)),
    );
    debug_assert_eq!(out.len(), n);
    Ok(out)
}

/// Bins `0..=N/2` of the one-sided density from a two-sided one of `N` bins: interior bins
/// doubled, DC and Nyquist kept. The negative-frequency bins are not read (for a real process they
/// carry no extra information).
///
/// # Errors
/// [`GridError::BadTwoSidedLength`] if `two_sided` is empty or of odd length.
pub fn one_sided_from_two_sided<const R: usize, const C: usize>(
    two_sided: &[SMatrix<Complex64, R, C>],
) -> Result<Vec<SMatrix<Complex64, R, C>>, GridError> {
    let n = two_sided.len();
    if n == 0 || !n.is_multiple_of(2) {
        return Err(GridError::BadTwoSidedLength { len: n });
    }
    let half = n / 2;
    Ok(two_sided[..=half]
        .iter()
        .enumerate()
        .map(|(k, s)| {
            if k == 0 || k == half {
                *s
            } else {
                s * Complex64::new(2.0, 0.0)
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Matrix2;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    /// A random Hermitian 2x2 "density" bin; real (symmetric) at DC and Nyquist.
    fn random_one_sided(rng: &mut Rng, m: usize) -> Vec<Matrix2<Complex64>> {
        (0..m)
            .map(|k| {
                let edge = k == 0 || k == m - 1;
                let off = c(rng.normal(), if edge { 0.0 } else { rng.normal() });
                Matrix2::new(
                    c(1.0 + rng.uniform(), 0.0),
                    off,
                    off.conj(),
                    c(1.0 + rng.uniform(), 0.0),
                )
            })
            .collect()
    }

    #[test]
    fn halving_rule_and_negative_frequencies() {
        let mut rng = Rng::new(7);
        let one = random_one_sided(&mut rng, 5);
        let two = two_sided_from_one_sided(&one).expect("valid");
        assert_eq!(two.len(), 8);
        assert_eq!(two[0], one[0], "DC kept");
        assert_eq!(two[4], one[4], "Nyquist kept");
        for k in 1..4 {
            assert_eq!(two[k], one[k] * c(0.5, 0.0), "interior bin {k} halved");
            assert_eq!(two[8 - k], two[k].transpose(), "S(-f) = S(f)^T at bin {k}");
            assert_eq!(
                two[8 - k],
                two[k].map(|z| z.conj()),
                "S(-f) = conj S(f) at bin {k}"
            );
        }
        // The lag-0 covariance (the sum over the two-sided grid) is real: the interior bins'
        // quadrature (imaginary) parts cancel against the negative frequencies, their real parts
        // (already holding both signs in the one-sided density) are counted once.
        let two_sum: Matrix2<Complex64> = two.iter().sum();
        let one_sum_real: Matrix2<Complex64> = one.iter().sum::<Matrix2<Complex64>>().map(|z| c(z.re, 0.0));
        assert!((two_sum - one_sum_real).norm() < 1e-12 * one_sum_real.norm());
    }

    #[test]
    fn round_trips() {
        let mut rng = Rng::new(11);
        for m in [2, 3, 17, 65] {
            let one = random_one_sided(&mut rng, m);
            let two = two_sided_from_one_sided(&one).expect("valid");
            assert_eq!(two.len(), 2 * (m - 1));
            let back = one_sided_from_two_sided(&two).expect("valid");
            assert_eq!(back.len(), m);
            for (a, b) in one.iter().zip(&back) {
                assert!((a - b).norm() <= 1e-15 * a.norm());
            }
            let two_again = two_sided_from_one_sided(&back).expect("valid");
            for (a, b) in two.iter().zip(&two_again) {
                assert!((a - b).norm() <= 1e-15 * a.norm());
            }
        }
    }

    #[test]
    fn bad_lengths_are_errors() {
        let none: [Matrix2<Complex64>; 0] = [];
        assert_eq!(
            two_sided_from_one_sided(&none),
            Err(GridError::TooShortOneSided { len: 0 })
        );
        assert_eq!(
            two_sided_from_one_sided(&[Matrix2::identity()]),
            Err(GridError::TooShortOneSided { len: 1 })
        );
        assert_eq!(
            one_sided_from_two_sided(&none),
            Err(GridError::BadTwoSidedLength { len: 0 })
        );
        assert_eq!(
            one_sided_from_two_sided(&[Matrix2::<Complex64>::identity(); 3]),
            Err(GridError::BadTwoSidedLength { len: 3 })
        );
    }

    #[test]
    fn bin_frequencies_in_fft_order() {
        let f: Vec<f64> = (0..8).map(|k| bin_frequency(k, 8, 16.0)).collect();
        assert_eq!(f, [0.0, 2.0, 4.0, 6.0, 8.0, -6.0, -4.0, -2.0]);
    }
}
