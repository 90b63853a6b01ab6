//! The lower bound of the `spectra` stage: a bare loop of the same real FFTs plus the cross
//! products, with nothing else (no input checks, no detrending, no scaling, no reshaping into
//! matrices), parallel over the same chunks of segments as [`crate::spectral::welch`].
//!
//! The FFT length is the one the estimator transforms at ([`transform_len`]) for the identifier's
//! zero-padded grid ([`grid_len`]: [`ZERO_PAD`](crate::ident::spectra::ZERO_PAD) times the segment length unless the settings say otherwise).

use num_complex::Complex64;
use rayon::prelude::*;
use realfft::RealFftPlanner;

use crate::ident::spectra::grid_len;
use crate::spectral::welch::{MAX_CHUNKS, transform_len};
use crate::spectral::{SpectralError, WelchSettings};

/// Sums over the segments of `X_i conj(X_j)` for every pair `i <= j` of `channels`, laid out
/// `[pair][bin]` (pairs row by row of the upper triangle).
///
/// # Errors
/// [`SpectralError::Fft`] should the FFT refuse its buffers (it does not for these lengths).
pub fn welch_sums(channels: &[&[f64]], settings: &WelchSettings) -> Result<Vec<Complex64>, SpectralError> {
    let seg = settings.segment_len;
    let len = transform_len(seg, grid_len(settings));
    let nb = len / 2 + 1;
    let n = channels.len();
    let n_pairs = n * (n + 1) / 2;
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(len);
    let window = settings.window.coefficients(seg);
    let step = settings.step();
    let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
    let n_chunks = n_segments.clamp(1, MAX_CHUNKS);
    let partials = (0..n_chunks)
        .into_par_iter()
        .map(|c| {
            let mut input = vec![0.0; len];
            let mut spectra = vec![Complex64::default(); n * nb];
            let mut acc = vec![Complex64::default(); n_pairs * nb];
            for s in c * n_segments / n_chunks..(c + 1) * n_segments / n_chunks {
                for (x, out) in channels.iter().zip(spectra.chunks_exact_mut(nb)) {
                    for ((v, x), w) in input.iter_mut().zip(&x[s * step..]).zip(&window) {
                        *v = x * w;
                    }
                    input[seg..].fill(0.0);
                    fft.process(&mut input, out)
                        .map_err(|e| SpectralError::Fft(e.to_string()))?;
                }
                let mut pair = acc.chunks_exact_mut(nb);
                for i in 0..n {
                    for j in i..n {
                        let a = pair.next().unwrap_or_default();
                        let (xi, xj) = (&spectra[i * nb..(i + 1) * nb], &spectra[j * nb..(j + 1) * nb]);
                        for ((a, p), q) in a.iter_mut().zip(xi).zip(xj) {
                            *a += p * q.conj();
                        }
                    }
                }
            }
            Ok(acc)
        })
        .collect::<Result<Vec<_>, SpectralError>>()?;
    let mut total = vec![Complex64::default(); n_pairs * nb];
    for p in &partials {
        total.iter_mut().zip(p).for_each(|(t, v)| *t += v);
    }
    Ok(total)
}
