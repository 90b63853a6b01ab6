//! The one-sided cross-spectral density matrix `S(f)`, stored `[frequency][row][col]`.

use super::SpectralError;
use nalgebra::DMatrix;
use num_complex::Complex64;
use std::ops::Index;

/// A one-sided cross-spectral density matrix per frequency bin, units^2/Hz
/// (conventions in the [module docs](super)).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralMatrix {
    /// Sample rate of the signals, Hz.
    pub sample_rate_hz: f64,
    /// FFT length `N` (the segment length, or the zero-padded `fft_len`), samples.
    pub fft_len: usize,
    /// Number of channels `n`; each bin is an `n x n` matrix.
    pub n_channels: usize,
    /// Number of segments averaged.
    pub n_averages: usize,
    /// Bin frequencies `k fs / N`, `k = 0..=N/2`, ascending, Hz.
    pub frequency_hz: Vec<f64>,
    /// `S[f][i][j]` at `(f * n + i) * n + j`.
    data: Vec<Complex64>,
}

impl SpectralMatrix {
    /// Assembles a matrix from its parts; `data` is laid out `[frequency][row][col]`.
    ///
    /// # Errors
    /// [`SpectralError::ShapeMismatch`] if `data.len() != frequency_hz.len() * n_channels^2`.
    pub fn from_parts(
        sample_rate_hz: f64,
        fft_len: usize,
        n_channels: usize,
        n_averages: usize,
        frequency_hz: Vec<f64>,
        data: Vec<Complex64>,
    ) -> Result<Self, SpectralError> {
        let n_bins = frequency_hz.len();
        let expected = n_bins * n_channels * n_channels;
        if data.len() != expected {
            return Err(SpectralError::ShapeMismatch {
                n_bins,
                n_channels,
                expected,
                len: data.len(),
            });
        }
        Ok(Self {
            sample_rate_hz,
            fft_len,
            n_channels,
            n_averages,
            frequency_hz,
            data,
        })
    }

    /// Number of frequency bins (`N/2 + 1` for a Welch estimate).
    #[must_use]
    pub fn n_bins(&self) -> usize {
        self.frequency_hz.len()
    }

    /// Bin spacing `fs / N`, Hz.
    #[must_use]
    pub fn df_hz(&self) -> f64 {
        self.sample_rate_hz / self.fft_len as f64
    }

    /// `S[f][i][j]`, or `None` if any index is out of range.
    #[must_use]
    pub fn get(&self, f: usize, i: usize, j: usize) -> Option<Complex64> {
        let n = self.n_channels;
        if f >= self.n_bins() || i >= n || j >= n {
            return None;
        }
        self.data.get((f * n + i) * n + j).copied()
    }

    /// The `n x n` matrix of bin `f`, row-major.
    ///
    /// # Panics
    /// If `f >= n_bins()`, like slice indexing.
    #[must_use]
    pub fn bin(&self, f: usize) -> &[Complex64] {
        let nn = self.n_channels * self.n_channels;
        &self.data[f * nn..(f + 1) * nn]
    }

    /// The `n x n` matrix of bin `f` as a nalgebra matrix.
    ///
    /// # Panics
    /// If `f >= n_bins()`, like slice indexing.
    #[must_use]
    pub fn matrix(&self, f: usize) -> DMatrix<Complex64> {
        DMatrix::from_row_slice(self.n_channels, self.n_channels, self.bin(f))
    }

    /// All values, `[frequency][row][col]`.
    #[must_use]
    pub fn as_slice(&self) -> &[Complex64] {
        &self.data
    }

    /// Power spectral density of channel `i` over frequency (the real diagonal), units^2/Hz.
    ///
    /// # Panics
    /// If `i >= n_channels`.
    #[must_use]
    pub fn psd(&self, i: usize) -> Vec<f64> {
        (0..self.n_bins()).map(|f| self[(f, i, i)].re).collect()
    }

    /// Magnitude-squared coherence `|S_ij|^2 / (S_ii S_jj)` of channels `i` and `j` over
    /// frequency, in `[0, 1]`; 0 where either channel has no power.
    ///
    /// # Panics
    /// If `i` or `j >= n_channels`.
    #[must_use]
    pub fn coherence(&self, i: usize, j: usize) -> Vec<f64> {
        (0..self.n_bins())
            .map(|f| {
                let denom = self[(f, i, i)].re * self[(f, j, j)].re;
                if denom > 0.0 {
                    (self[(f, i, j)].norm_sqr() / denom).min(1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }
}

impl Index<(usize, usize, usize)> for SpectralMatrix {
    type Output = Complex64;

    /// `S[f][i][j]`; panics if an index is out of range (use [`SpectralMatrix::get`] to check).
    fn index(&self, (f, i, j): (usize, usize, usize)) -> &Complex64 {
        let n = self.n_channels;
        assert!(i < n && j < n, "channel ({i}, {j}) out of range for {n} channels");
        &self.data[(f * n + i) * n + j]
    }
}

#[cfg(test)]
mod tests {
    use super::{Complex64, SpectralError, SpectralMatrix};

    fn two_by_two() -> SpectralMatrix {
        let c = |re, im| Complex64::new(re, im);
        let data = vec![
            c(4.0, 0.0),
            c(1.0, 1.0),
            c(1.0, -1.0),
            c(1.0, 0.0), // bin 0
            c(0.0, 0.0),
            c(0.0, 0.0),
            c(0.0, 0.0),
            c(9.0, 0.0), // bin 1: channel 0 silent
        ];
        SpectralMatrix::from_parts(10.0, 8, 2, 3, vec![0.0, 1.25], data).unwrap()
    }

    #[test]
    fn accessors_follow_the_layout() {
        let s = two_by_two();
        assert_eq!((s.n_bins(), s.df_hz()), (2, 1.25));
        assert_eq!(s.get(0, 0, 1), Some(Complex64::new(1.0, 1.0)));
        assert_eq!(s.get(0, 1, 0), Some(Complex64::new(1.0, -1.0)));
        assert_eq!(s.get(1, 1, 1), Some(Complex64::new(9.0, 0.0)));
        assert_eq!(
            (s.get(2, 0, 0), s.get(0, 2, 0), s.get(0, 0, 2)),
            (None, None, None)
        );
        assert_eq!(s[(1, 1, 1)], Complex64::new(9.0, 0.0));
        assert_eq!(s.bin(1)[3], Complex64::new(9.0, 0.0));
        assert_eq!(s.matrix(0)[(0, 1)], Complex64::new(1.0, 1.0));
        assert_eq!(s.psd(0), [4.0, 0.0]);
        assert_eq!(s.coherence(0, 1), [0.5, 0.0], "silent channel gives 0, never NaN");
    }

    #[test]
    fn from_parts_checks_the_shape() {
        let err = SpectralMatrix::from_parts(1.0, 8, 2, 1, vec![0.0], vec![Complex64::default(); 3]);
        assert_eq!(
            err,
            Err(SpectralError::ShapeMismatch {
                n_bins: 1,
                n_channels: 2,
                expected: 4,
                len: 3
            })
        );
    }
}
