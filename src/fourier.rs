//! Whole-record real FFTs for the observer and the simulator (not for spectral estimation: see
//! `spectral` for Welch).
//!
//! Conventions: `forward` is unnormalised, `X_k = sum_n x_n e^{-2 pi i k n / L}`, bins
//! `k = 0..=L/2` at `f_k = k fs / L` ascending (one-sided storage of a real signal). `inverse`
//! includes the `1/L` factor, so `inverse(forward(x)) == x`. The imaginary parts of the DC and
//! (even `L`) Nyquist bins are ignored by `inverse`, since a real signal cannot have them.
//! Plans and scratch are cached per length (the `realfft` planner pattern).

use std::sync::Arc;

use num_complex::Complex64;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

/// Real FFT plans and scratch for one record length.
pub struct RecordFft {
    len: usize,
    sample_rate_hz: f64,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    scratch: Vec<Complex64>,
}

impl RecordFft {
    /// Plans for records of `len` samples at `sample_rate_hz`. `len` must be at least 2
    /// (an internal invariant: callers pad records to [`fast_len`] first).
    #[must_use]
    pub fn new(len: usize, sample_rate_hz: f64) -> Self {
        let mut planner = RealFftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(len);
        let inverse = planner.plan_fft_inverse(len);
        let scratch_len = forward.get_scratch_len().max(inverse.get_scratch_len());
        Self {
            len,
            sample_rate_hz,
            forward,
            inverse,
            scratch: vec![Complex64::default(); scratch_len],
        }
    }

    /// Record length in samples.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a plan has at least two samples.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of one-sided bins, `len/2 + 1`.
    #[must_use]
    pub fn n_bins(&self) -> usize {
        self.len / 2 + 1
    }

    /// Frequency of bin `k`, Hz.
    #[must_use]
    pub fn frequency_hz(&self, k: usize) -> f64 {
        k as f64 * self.sample_rate_hz / self.len as f64
    }

    /// Sample rate, Hz.
    #[must_use]
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// Unnormalised forward transform of `x` (which must have `len` samples; shorter input is
    /// zero-padded, longer input truncated).
    pub fn forward(&mut self, x: &[f64]) -> Vec<Complex64> {
        let mut input = vec![0.0; self.len];
        let m = x.len().min(self.len);
        input[..m].copy_from_slice(&x[..m]);
        let mut out = vec![Complex64::default(); self.n_bins()];
        // Lengths match the plan by construction, so the transform cannot fail.
        let _ = self
            .forward
            .process_with_scratch(&mut input, &mut out, &mut self.scratch);
        out
    }

    /// Normalised inverse transform (`1/len` applied) of a one-sided spectrum of `n_bins` bins.
    pub fn inverse(&mut self, mut spectrum: Vec<Complex64>) -> Vec<f64> {
        spectrum.resize(self.n_bins(), Complex64::default());
        spectrum[0].im = 0.0;
        if self.len.is_multiple_of(2) {
            let last = self.n_bins() - 1;
            spectrum[last].im = 0.0;
        }
        let mut out = vec![0.0; self.len];
        let _ = self
            .inverse
            .process_with_scratch(&mut spectrum, &mut out, &mut self.scratch);
        let scale = 1.0 / self.len as f64;
        for v in &mut out {
            *v *= scale;
        }
        out
    }
}

/// The smallest length `>= n` whose only prime factors are 2, 3 and 5 (fast for every FFT size).
#[must_use]
pub fn fast_len(n: usize) -> usize {
    let mut m = n.max(2);
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_known_sinusoid() {
        for len in [8, 30, 243, 1000] {
            let mut fft = RecordFft::new(len, 100.0);
            let x: Vec<f64> = (0..len)
                .map(|n| (n as f64 * 0.37).sin() + 0.1 * n as f64)
                .collect();
            let spec = fft.forward(&x);
            let y = fft.inverse(spec);
            for (a, b) in x.iter().zip(&y) {
                assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()));
            }
            // A cosine at bin 3 with amplitude 2 gives X_3 = len (2/2).
            let c: Vec<f64> = (0..len)
                .map(|n| 2.0 * (2.0 * std::f64::consts::PI * 3.0 * n as f64 / len as f64).cos())
                .collect();
            let spec = fft.forward(&c);
            assert!((spec[3].re - len as f64).abs() < 1e-9 * len as f64);
            assert!(spec[3].im.abs() < 1e-9 * len as f64);
            assert!((fft.frequency_hz(3) - 300.0 / len as f64).abs() < 1e-12);
        }
    }

    #[test]
    fn fast_len_is_smooth_and_minimal() {
        assert_eq!(fast_len(1), 2);
        assert_eq!(fast_len(7), 8);
        assert_eq!(fast_len(11), 12);
        assert_eq!(fast_len(1001), 1024);
        for n in [97, 1234, 150_001] {
            let m = fast_len(n);
            assert!(m >= n);
            for k in n..m {
                assert_ne!(fast_len(k), k, "{k} is smooth but skipped");
            }
        }
    }
}
