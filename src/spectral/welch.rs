//! Welch's averaged-periodogram estimate of the cross-spectral density matrix.
//!
//! One real FFT per segment per channel; the `n (n + 1) / 2` cross products of the upper
//! triangle are accumulated per bin as the segments go by and mirrored at the end. Segments are
//! split into at most [`MAX_CHUNKS`] contiguous chunks that rayon runs in parallel, each with its
//! own buffers and accumulator; the chunk sums are added in chunk order. The chunking depends on
//! the number of segments only, so the result is bit-identical whatever the thread count.

use super::{SpectralError, SpectralMatrix, WelchSettings, Window};
use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{RealFftPlanner, RealToComplex};
use std::collections::HashMap;
use std::sync::Arc;

/// The most chunks the segments are split into (so the most threads one estimate uses).
pub const MAX_CHUNKS: usize = 8;

/// The length of the per-segment FFTs for segments of `segment_len` samples on a grid of `nfft`.
#[must_use]
pub fn transform_len(segment_len: usize, nfft: usize) -> usize {
    let _ = segment_len;
    nfft
}

/// Owns the FFT plans and window vectors, so repeated estimates reuse them (`RustFFT`'s planner
/// pattern): keep one per worker and call [`WelchPlanner::welch_matrix`] on it.
pub struct WelchPlanner {
    fft: RealFftPlanner<f64>,
    windows: HashMap<(Window, usize), Arc<[f64]>>,
}

impl Default for WelchPlanner {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for WelchPlanner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WelchPlanner")
            .field("cached_windows", &self.windows.len())
            .finish_non_exhaustive()
    }
}

/// Everything a chunk needs to read, shared by all chunks.
struct Plan<'a> {
    channels: &'a [&'a [f64]],
    settings: &'a WelchSettings,
    window: &'a [f64],
    fft: &'a dyn RealToComplex<f64>,
    n_bins: usize,
}

impl WelchPlanner {
    /// A planner with empty caches.
    #[must_use]
    pub fn new() -> Self {
        Self {
            fft: RealFftPlanner::new(),
            windows: HashMap::new(),
        }
    }

    /// The periodic `window` of length `n`, computed once per `(window, n)` and then shared.
    pub fn window(&mut self, window: Window, n: usize) -> Arc<[f64]> {
        Arc::clone(
            self.windows
                .entry((window, n))
                .or_insert_with(|| window.coefficients(n).into()),
        )
    }

    /// The one-sided cross-spectral density matrix of `channels` (all the same length, sampled
    /// at `sample_rate_hz`), by Welch's method with `settings`. Conventions: [module docs](super).
    ///
    /// # Errors
    /// - [`SpectralError::NoChannels`] if `channels` is empty;
    /// - [`SpectralError::ChannelLengthMismatch`] if a channel's length differs from channel 0's;
    /// - [`SpectralError::BadSampleRate`] if `sample_rate_hz` is not finite and positive;
    /// - whatever [`WelchSettings::validate`] says about `settings` and the channel length;
    /// - [`SpectralError::NonFinite`] at the first NaN or infinite sample.
    pub fn welch_matrix(
        &mut self,
        channels: &[&[f64]],
        sample_rate_hz: f64,
        settings: &WelchSettings,
    ) -> Result<SpectralMatrix, SpectralError> {
        check_input(channels, sample_rate_hz, settings)?;
        let seg = settings.segment_len;
        let nfft = settings.nfft();
        let n_bins = nfft / 2 + 1;
        let n = channels.len();
        let window = self.window(settings.window, seg);
        let fft = self.fft.plan_fft_forward(nfft);
        let plan = Plan {
            channels,
            settings,
            window: &window,
            fft: fft.as_ref(),
            n_bins,
        };

        let n_segments = settings.n_segments(channels[0].len());
        let n_chunks = n_segments.min(MAX_CHUNKS);
        let partials = (0..n_chunks)
            .into_par_iter()
            .map(|c| plan.accumulate(c * n_segments / n_chunks..(c + 1) * n_segments / n_chunks))
            .collect::<Result<Vec<_>, _>>()?;
        let mut data = vec![Complex64::default(); n_bins * n * n];
        for partial in &partials {
            data.iter_mut().zip(partial).for_each(|(d, p)| *d += p);
        }

        let sum_w2: f64 = window.iter().map(|w| w * w).sum();
        let base = 1.0 / (sample_rate_hz * sum_w2 * n_segments as f64);
        for (f, bin) in data.chunks_exact_mut(n * n).enumerate() {
            let scale = if f == 0 || f == n_bins - 1 {
                base
            } else {
                2.0 * base
            };
            for i in 0..n {
                bin[i * n + i] *= scale; // real, with +0 imaginary part
                for j in i + 1..n {
                    let s = bin[i * n + j] * scale;
                    bin[i * n + j] = s;
                    bin[j * n + i] = s.conj();
                }
            }
        }
        let frequency_hz = (0..n_bins)
            .map(|k| k as f64 * sample_rate_hz / nfft as f64)
            .collect();
        SpectralMatrix::from_parts(sample_rate_hz, nfft, n, n_segments, frequency_hz, data)
    }
}

/// [`WelchPlanner::welch_matrix`] with a fresh planner, for one-off estimates.
///
/// # Errors
/// As [`WelchPlanner::welch_matrix`].
pub fn welch_matrix(
    channels: &[&[f64]],
    sample_rate_hz: f64,
    settings: &WelchSettings,
) -> Result<SpectralMatrix, SpectralError> {
    WelchPlanner::new().welch_matrix(channels, sample_rate_hz, settings)
}

/// The input checks of [`WelchPlanner::welch_matrix`], in its documented order.
fn check_input(
    channels: &[&[f64]],
    sample_rate_hz: f64,
    settings: &WelchSettings,
) -> Result<(), SpectralError> {
    let first = channels.first().ok_or(SpectralError::NoChannels)?;
    let expected = first.len();
    if let Some((channel, x)) = channels.iter().enumerate().find(|(_, x)| x.len() != expected) {
        return Err(SpectralError::ChannelLengthMismatch {
            channel,
            len: x.len(),
            expected,
        });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(SpectralError::BadSampleRate { sample_rate_hz });
    }
    settings.validate(expected)?;
    for (channel, x) in channels.iter().enumerate() {
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFinite { channel, index });
        }
    }
    Ok(())
}

impl Plan<'_> {
    /// Sum over the segments in `segments` of `X_i X_j^*` for `i <= j` (lower triangle left 0),
    /// laid out `[frequency][row][col]`. Allocates once, not per segment.
    fn accumulate(&self, segments: std::ops::Range<usize>) -> Result<Vec<Complex64>, SpectralError> {
        let (n, nb) = (self.channels.len(), self.n_bins);
        let seg = self.settings.segment_len;
        let step = self.settings.step();
        let mut input = vec![0.0; self.settings.nfft()];
        let mut spectra = vec![Complex64::default(); n * nb];
        let mut scratch = vec![Complex64::default(); self.fft.get_scratch_len()];
        let mut acc = vec![Complex64::default(); nb * n * n];
        for s in segments {
            let start = s * step;
            for (x, out) in self.channels.iter().zip(spectra.chunks_exact_mut(nb)) {
                let (data, padding) = input.split_at_mut(seg);
                data.copy_from_slice(&x[start..start + seg]);
                self.settings.detrend.apply(data);
                data.iter_mut().zip(self.window).for_each(|(v, w)| *v *= w);
                padding.fill(0.0);
                self.fft
                    .process_with_scratch(&mut input, out, &mut scratch)
                    .map_err(|e| SpectralError::Fft(e.to_string()))?;
            }
            for (f, bin) in acc.chunks_exact_mut(n * n).enumerate() {
                for i in 0..n {
                    let xi = spectra[i * nb + f];
                    bin[i * n + i].re += xi.norm_sqr();
                    for j in i + 1..n {
                        bin[i * n + j] += xi * spectra[j * nb + f].conj();
                    }
                }
            }
        }
        Ok(acc)
    }
}
