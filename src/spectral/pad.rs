//! Zero-padding a summed Welch cross spectrum after the fact (see [`super::welch`]'s docs): from
//! the sums on a grid of `len >= 2 N` points (`N` the segment length) to the sums on the finer
//! grid of `nfft` points, through the segments' cross-correlation, which has lags `|l| < N` only.

use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{ComplexToReal, RealToComplex};

use super::SpectralError;

/// `sums` holds one-sided spectra of `inverse.len() / 2 + 1` bins per pair, pair after pair;
/// returns the same pairs on `forward.len() / 2 + 1` bins. Bins common to both grids (DC, and
/// every coarse bin when the fine grid is a whole multiple of the coarse one) are copied unchanged.
///
/// # Errors
/// [`SpectralError::Fft`] should the FFTs refuse their buffers.
pub(super) fn refine_pairs(
    sums: &[Complex64],
    inverse: &dyn ComplexToReal<f64>,
    forward: &dyn RealToComplex<f64>,
    segment_len: usize,
) -> Result<Vec<Complex64>, SpectralError> {
    let (len, nfft) = (inverse.len(), forward.len());
    let (coarse, fine) = (len / 2 + 1, nfft / 2 + 1);
    let fft_error = |e: realfft::FftError| SpectralError::Fft(e.to_string());
    let mut out = vec![Complex64::default(); sums.len() / coarse * fine];
    out.par_chunks_exact_mut(fine)
        .zip(sums.par_chunks_exact(coarse))
        .try_for_each_init(
            || {
                (
                    vec![Complex64::default(); coarse],
                    vec![0.0; len],
                    vec![0.0; nfft],
                )
            },
            |(spectrum, correlation, padded), (out, sum)| {
                spectrum.copy_from_slice(sum);
                // A real pair's cross spectrum is Hermitian: DC and Nyquist are real.
                spectrum[0].im = 0.0;
                if len.is_multiple_of(2) {
                    spectrum[coarse - 1].im = 0.0;
                }
                inverse.process(spectrum, correlation).map_err(fft_error)?;
                let norm = 1.0 / len as f64;
                padded.fill(0.0);
                for lag in 0..segment_len.min(len) {
                    padded[lag] = correlation[lag] * norm;
                }
                for lag in 1..segment_len.min(len) {
                    padded[nfft - lag] = correlation[len - lag] * norm;
                }
                forward.process(padded, out).map_err(fft_error)?;
                // Coarse bin k lies on the fine grid when k nfft / len is whole (always DC).
                for (k, s) in sum.iter().enumerate() {
                    if (k * nfft).is_multiple_of(len) {
                        out[k * nfft / len] = *s;
                    }
                }
                Ok(())
            },
        )?;
    Ok(out)
}
