//! The causal projection `[.]_+` of functions sampled on a two-sided FFT grid.
//!
//! # Conventions
//! - A function `F` on the two-sided grid of `N` bins (FFT order, see [`super::grid`]) has the lag
//!   sequence `h[n] = (1/N) sum_k F[k] e^{+2 pi i k n / N}` (the inverse DFT), so that
//!   `F[k] = sum_n h[n] e^{-2 pi i k n / N}`, i.e. `F(z) = sum_n h[n] z^-n` with `z = e^{2 pi i k / N}`.
//! - Lags `n = 0..N/2-1` are the non-negative lags (lag 0 = the constant term, `F(z = inf)`),
//!   `n = N/2+1..N-1` are the negative lags `n - N`. The Nyquist lag `n = N/2` is both `+N/2` and
//!   `-N/2` on the circle: every projection here keeps **half** of it, so that
//!   `[F]_+ + [F]_-` with the same split gives back `F`.
//! - `[F]_+` ([`CausalProjector::causal_part`]) keeps lag 0, the positive lags and half the Nyquist
//!   lag, and zeroes the negative lags. [`CausalProjector::causal_part_half_zero_lag`] keeps half of
//!   lag 0 (Wilson's `[g]_+`), [`CausalProjector::strictly_causal_part`] none of it.
//! - Matrix-valued functions are projected element by element.
//!
//! # Contracts
//! - `N` must be even and non-zero, and every input must have exactly `N` bins, otherwise a
//!   [`CausalError`]; nothing panics.
//! - NaN or infinite inputs are not checked: they spread over the whole grid of their element
//!   (every output bin depends on every input bin).
//! - Units are those of the input (the projection is linear and dimensionless).
//!
//! All FFT plans and buffers are owned by the [`CausalProjector`] and reused: one projection of an
//! `R x C` function does two batched FFT passes of `R*C` transforms and no allocation after the
//! first call of a given shape.

use std::sync::Arc;

use nalgebra::SMatrix;
use num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

/// Why a causal projection was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CausalError {
    /// The grid length is zero or odd.
    #[error("causal projection needs an even, non-zero grid length, got {len}")]
    BadGridLength {
        /// The requested grid length.
        len: usize,
    },
    /// The input does not have the projector's grid length.
    #[error("input has {found} bins, the projector was planned for {expected}")]
    LengthMismatch {
        /// The projector's grid length.
        expected: usize,
        /// The input's length.
        found: usize,
    },
}

/// Cached FFT plans and scratch for projections on one grid length.
pub struct CausalProjector {
    n: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    buffer: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

impl std::fmt::Debug for CausalProjector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CausalProjector")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}

impl CausalProjector {
    /// Plans the forward and inverse FFTs for a grid of `n` bins.
    ///
    /// # Errors
    /// [`CausalError::BadGridLength`] if `n` is zero or odd.
    pub fn new(n: usize) -> Result<Self, CausalError> {
        Self::with_planner(n, &mut FftPlanner::new())
    }

    /// As [`CausalProjector::new`], sharing the plan cache of an existing `planner`.
    ///
    /// # Errors
    /// [`CausalError::BadGridLength`] if `n` is zero or odd.
    pub fn with_planner(n: usize, planner: &mut FftPlanner<f64>) -> Result<Self, CausalError> {
        if n == 0 || !n.is_multiple_of(2) {
            return Err(CausalError::BadGridLength { len: n });
        }
        let forward = planner.plan_fft_forward(n);
        let inverse = planner.plan_fft_inverse(n);
        let scratch_len = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        Ok(Self {
            n,
            forward,
            inverse,
            buffer: Vec::new(),
            scratch: vec![Complex64::ZERO; scratch_len],
        })
    }

    /// The grid length `N` this projector was planned for.
    #[must_use]
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always `false`: a projector's grid has at least 2 bins (kept for the `len`/`is_empty` pair).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// `[F]_+` in place: keeps lag 0, the positive lags and half the Nyquist lag.
    ///
    /// # Errors
    /// [`CausalError::LengthMismatch`] if `f.len()` is not the projector's grid length.
    pub fn causal_part<const R: usize, const C: usize>(
        &mut self,
        f: &mut [SMatrix<Complex64, R, C>],
    ) -> Result<(), CausalError> {
        self.project(f, 1.0)
    }

    /// `[F]_+` with half of lag 0 (Wilson's operator), in place.
    ///
    /// # Errors
    /// [`CausalError::LengthMismatch`] if `f.len()` is not the projector's grid length.
    pub fn causal_part_half_zero_lag<const R: usize, const C: usize>(
        &mut self,
        f: &mut [SMatrix<Complex64, R, C>],
    ) -> Result<(), CausalError> {
        self.project(f, 0.5)
    }

    /// The strictly causal part (positive lags and half the Nyquist lag; lag 0 removed), in place.
    ///
    /// # Errors
    /// [`CausalError::LengthMismatch`] if `f.len()` is not the projector's grid length.
    pub fn strictly_causal_part<const R: usize, const C: usize>(
        &mut self,
        f: &mut [SMatrix<Complex64, R, C>],
    ) -> Result<(), CausalError> {
        self.project(f, 0.0)
    }

    /// The lag sequence `h[n] = (1/N) sum_k F[k] e^{+2 pi i k n / N}`, `n = 0..N`, of `f`.
    ///
    /// # Errors
    /// [`CausalError::LengthMismatch`] if `f.len()` is not the projector's grid length.
    pub fn lags<const R: usize, const C: usize>(
        &mut self,
        f: &[SMatrix<Complex64, R, C>],
    ) -> Result<Vec<SMatrix<Complex64, R, C>>, CausalError> {
        self.load(f)?;
        self.inverse
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        let scale = 1.0 / self.n as f64;
        let mut out = f.to_vec();
        self.store(&mut out, scale);
        Ok(out)
    }

    /// The fraction of the energy of `f`'s lag sequence at negative lags:
    /// `sum_{n = N/2+1}^{N-1} ||h[n]||_F^2 / sum_n ||h[n]||_F^2` (0 for an all-zero `f`; the
    /// Nyquist lag counts as non-negative). About 0 for a causal function.
    ///
    /// # Errors
    /// [`CausalError::LengthMismatch`] if `f.len()` is not the projector's grid length.
    pub fn negative_lag_fraction<const R: usize, const C: usize>(
        &mut self,
        f: &[SMatrix<Complex64, R, C>],
    ) -> Result<f64, CausalError> {
        let h = self.lags(f)?;
        let total: f64 = h.iter().map(SMatrix::norm_squared).sum();
        let negative: f64 = h[self.n / 2 + 1..].iter().map(SMatrix::norm_squared).sum();
        Ok(if total > 0.0 { negative / total } else { 0.0 })
    }

    /// Inverse FFT, lag weights (`zero_lag_weight` at lag 0, 1 on positive lags, 1/2 at Nyquist,
    /// 0 on negative lags, all times `1/N`), forward FFT.
    fn project<const R: usize, const C: usize>(
        &mut self,
        f: &mut [SMatrix<Complex64, R, C>],
        zero_lag_weight: f64,
    ) -> Result<(), CausalError> {
        self.load(f)?;
        let n = self.n;
        let half = n / 2;
        let scale = 1.0 / n as f64;
        self.inverse
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        for lags in self.buffer.chunks_exact_mut(n) {
            lags[0] *= zero_lag_weight * scale;
            lags[1..half].iter_mut().for_each(|h| *h *= scale);
            lags[half] *= 0.5 * scale;
            lags[half + 1..].fill(Complex64::ZERO);
        }
        self.forward
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        self.store(f, 1.0);
        Ok(())
    }

    /// Copies `f` into the buffer, one contiguous run of `N` bins per matrix element.
    fn load<const R: usize, const C: usize>(
        &mut self,
        f: &[SMatrix<Complex64, R, C>],
    ) -> Result<(), CausalError> {
        if f.len() != self.n {
            return Err(CausalError::LengthMismatch {
                expected: self.n,
                found: f.len(),
            });
        }
        let n = self.n;
        self.buffer.resize(R * C * n, Complex64::ZERO);
        for (e, run) in self.buffer.chunks_exact_mut(n).enumerate() {
            for (slot, m) in run.iter_mut().zip(f) {
                *slot = m[e];
            }
        }
        Ok(())
    }

    /// Copies the buffer back into `f` (same layout as [`Self::load`]), times `scale`.
    fn store<const R: usize, const C: usize>(&self, f: &mut [SMatrix<Complex64, R, C>], scale: f64) {
        for (e, run) in self.buffer.chunks_exact(self.n).enumerate() {
            for (m, v) in f.iter_mut().zip(run) {
                m[e] = v * scale;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Matrix2x3;
    use std::f64::consts::PI;

    fn random_function(rng: &mut Rng, n: usize) -> Vec<Matrix2x3<Complex64>> {
        (0..n)
            .map(|_| Matrix2x3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal())))
            .collect()
    }

    /// O(N^2) reference: naive inverse DFT, lag weights, naive forward DFT.
    fn naive_projection(f: &[Matrix2x3<Complex64>], zero_lag_weight: f64) -> Vec<Matrix2x3<Complex64>> {
        let n = f.len();
        let w = |k: usize, l: usize, sign: f64| {
            Complex64::from_polar(1.0, sign * 2.0 * PI * (k * l % n) as f64 / n as f64)
        };
        let lags: Vec<Matrix2x3<Complex64>> = (0..n)
            .map(|l| {
                let h: Matrix2x3<Complex64> = (0..n).map(|k| f[k] * w(k, l, 1.0)).sum();
                let weight = match l {
                    0 => zero_lag_weight,
                    l if 2 * l < n => 1.0,
                    l if 2 * l == n => 0.5,
                    _ => 0.0,
                };
                h * Complex64::from(weight / n as f64)
            })
            .collect();
        (0..n)
            .map(|k| (0..n).map(|l| lags[l] * w(k, l, -1.0)).sum())
            .collect()
    }

    fn max_diff(a: &[Matrix2x3<Complex64>], b: &[Matrix2x3<Complex64>]) -> f64 {
        a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max)
    }

    #[test]
    fn matches_naive_dft_on_random_data() {
        let mut rng = Rng::new(3);
        for n in [2, 6, 16, 50] {
            let mut p = CausalProjector::new(n).expect("even n");
            let f = random_function(&mut rng, n);
            let scale = f.iter().map(Matrix2x3::norm).fold(0.0, f64::max);
            for (weight, which) in [(1.0, 0), (0.5, 1), (0.0, 2)] {
                let mut fast = f.clone();
                match which {
                    0 => p.causal_part(&mut fast),
                    1 => p.causal_part_half_zero_lag(&mut fast),
                    _ => p.strictly_causal_part(&mut fast),
                }
                .expect("right length");
                let err = max_diff(&fast, &naive_projection(&f, weight));
                assert!(err < 1e-12 * scale * n as f64, "n={n} weight={weight}: {err}");
            }
        }
    }

    #[test]
    fn pure_delays() {
        let n = 32;
        let mut p = CausalProjector::new(n).expect("even n");
        for d in -20_i64..=20 {
            let delay = |k: usize| Complex64::from_polar(1.0, -2.0 * PI * k as f64 * d as f64 / n as f64);
            let f: Vec<Matrix2x3<Complex64>> = (0..n).map(|k| Matrix2x3::from_element(delay(k))).collect();
            let lag = d.rem_euclid(n as i64) as usize;
            let expected_gain = match lag {
                0 => 1.0,
                l if 2 * l < n => 1.0,
                l if 2 * l == n => 0.5,
                _ => 0.0,
            };
            let mut g = f.clone();
            p.causal_part(&mut g).expect("right length");
            let want: Vec<_> = f.iter().map(|m| m * Complex64::from(expected_gain)).collect();
            assert!(
                max_diff(&g, &want) < 1e-13,
                "delay {d}: gain should be {expected_gain}"
            );
            let neg = p.negative_lag_fraction(&f).expect("right length");
            assert!(
                (neg - if 2 * lag > n { 1.0 } else { 0.0 }).abs() < 1e-13,
                "delay {d}: {neg}"
            );
        }
    }

    #[test]
    fn projections_split_the_function() {
        // The three projections differ only by the lag-0 term, which is the mean of F over the grid.
        let mut rng = Rng::new(5);
        let n = 24;
        let mut p = CausalProjector::new(n).expect("even n");
        let f = random_function(&mut rng, n);
        let lag0: Matrix2x3<Complex64> = f.iter().sum::<Matrix2x3<Complex64>>() / Complex64::from(n as f64);
        let (mut full, mut half, mut strict) = (f.clone(), f.clone(), f.clone());
        p.causal_part(&mut full).expect("len");
        p.causal_part_half_zero_lag(&mut half).expect("len");
        p.strictly_causal_part(&mut strict).expect("len");
        for k in 0..n {
            assert!((full[k] - strict[k] - lag0).norm() < 1e-13);
            assert!((half[k] - strict[k] - lag0 * Complex64::from(0.5)).norm() < 1e-13);
        }
    }

    #[test]
    fn bad_lengths_are_errors() {
        assert_eq!(
            CausalProjector::new(0).err(),
            Some(CausalError::BadGridLength { len: 0 })
        );
        assert_eq!(
            CausalProjector::new(7).err(),
            Some(CausalError::BadGridLength { len: 7 })
        );
        let mut p = CausalProjector::new(8).expect("even n");
        let mut short = vec![Matrix2x3::<Complex64>::zeros(); 6];
        assert_eq!(
            p.causal_part(&mut short),
            Err(CausalError::LengthMismatch {
                expected: 8,
                found: 6
            })
        );
        assert!(p.lags(&short).is_err());
        let mut empty: Vec<Matrix2x3<Complex64>> = Vec::new();
        assert!(p.strictly_causal_part(&mut empty).is_err());
    }
}
