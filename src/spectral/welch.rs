//! Welch's averaged-periodogram estimate of the cross-spectral density matrix.
//!
//! One real FFT per segment per channel; the `n (n + 1) / 2` cross products of the upper
//! triangle are accumulated per bin as the segments go by and mirrored at the end. Segments are
//! split into at most [`MAX_CHUNKS`] contiguous chunks that rayon runs in parallel, each with its
//! own buffers and accumulator; the chunk sums are added in chunk order. The chunking depends on
//! the number of segments only, so the result is bit-identical whatever the thread count.
//!
//! **Zero-padding beyond twice the segment** (the identifier pads 4x) is not done per segment:
//! a segment of `N` samples has cross-correlations at lags `|l| < N` only, so the averaged cross
//! spectra on any grid of `M >= 2N - 1` points hold them without aliasing. The segments are
//! transformed at `M = 2 fast_len(N)` ([`transform_len`]), and each summed cross spectrum is taken
//! back to its correlation (one inverse FFT of length `M`), zero-padded to `fft_len` and
//! transformed once more. In exact arithmetic this is the same estimate; it halves both the FFTs
//! and the cross products for a 4x grid. The bins common to both grids are copied from the
//! direct sums, so they are bit-identical to the unpadded estimate's; auto-spectra are kept real
//! and non-negative.

use super::pad::refine_pairs;
use super::{SpectralError, SpectralMatrix, WelchSettings, Window};
use crate::fourier::fast_len;
use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{RealFftPlanner, RealToComplex};
use std::collections::HashMap;
use std::sync::Arc;

/// The most chunks the segments are split into (so the most threads one estimate uses).
pub const MAX_CHUNKS: usize = 8;

/// The length of the per-segment FFTs for segments of `segment_len` samples on a grid of `nfft`:
/// `nfft`, or `2 fast_len(segment_len)` when that is shorter (see the module docs).
#[must_use]
pub fn transform_len(segment_len: usize, nfft: usize) -> usize {
    let short = 2 * fast_len(segment_len);
    if short < nfft { short } else { nfft }
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

    /// The forward real FFT of length `len` (planned once, then shared).
    pub(super) fn real_fft(&mut self, len: usize) -> Arc<dyn RealToComplex<f64>> {
        self.fft.plan_fft_forward(len)
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
        let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
        Ok(self
            .welch_with_parts(
                channels,
                sample_rate_hz,
                settings,
                n_segments.min(MAX_CHUNKS),
                false,
            )?
            .0)
    }

    /// [`WelchPlanner::welch_matrix`] and, from the same segment transforms, the un-padded
    /// (native, `fft_len = segment_len`) matrices of `parts` consecutive groups of segments (group
    /// `p` holds segments `p n / parts .. (p + 1) n / parts`, `n` the segment count): the even
    /// bins of a transform of twice the segment are the segment's own transform, so the groups
    /// cost only their cross products. `None` for the groups when the transform length is not a
    /// multiple of the segment (a segment of no fast length): compute them apart then. The total
    /// is summed over the `parts` groups in order (deterministic, as [`MAX_CHUNKS`] chunks are).
    ///
    /// # Errors
    /// As [`WelchPlanner::welch_matrix`]; `parts` of 0 or above the segment count is
    /// [`SpectralError::BadParts`].
    pub fn welch_matrix_parts(
        &mut self,
        channels: &[&[f64]],
        sample_rate_hz: f64,
        settings: &WelchSettings,
        parts: usize,
    ) -> Result<(SpectralMatrix, Option<Vec<SpectralMatrix>>), SpectralError> {
        let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
        if parts == 0 || parts > n_segments.max(1) {
            return Err(SpectralError::BadParts { parts, n_segments });
        }
        self.welch_with_parts(channels, sample_rate_hz, settings, parts, true)
    }

    fn welch_with_parts(
        &mut self,
        channels: &[&[f64]],
        sample_rate_hz: f64,
        settings: &WelchSettings,
        n_chunks: usize,
        want_parts: bool,
    ) -> Result<(SpectralMatrix, Option<Vec<SpectralMatrix>>), SpectralError> {
        check_input(channels, sample_rate_hz, settings)?;
        let seg = settings.segment_len;
        let nfft = settings.nfft();
        let len = transform_len(seg, nfft);
        let n = channels.len();
        let window = self.window(settings.window, seg);
        let fft = self.fft.plan_fft_forward(len);
        let plan = Plan {
            channels,
            settings,
            window: &window,
            fft: fft.as_ref(),
            n_bins: len / 2 + 1,
        };

        let n_segments = settings.n_segments(channels[0].len());
        let bounds = |c: usize| c * n_segments / n_chunks;
        let partials = (0..n_chunks)
            .into_par_iter()
            .map(|c| plan.accumulate(bounds(c)..bounds(c + 1)))
            .collect::<Result<Vec<_>, _>>()?;
        let mut sums = vec![Complex64::default(); plan.n_bins * n * (n + 1) / 2];
        for partial in &partials {
            sums.iter_mut().zip(partial).for_each(|(d, p)| *d += p);
        }
        if len != nfft {
            let inverse = self.fft.plan_fft_inverse(len);
            let forward = self.fft.plan_fft_forward(nfft);
            sums = refine_pairs(&sums, inverse.as_ref(), forward.as_ref(), seg)?;
        }

        let sum_w2: f64 = window.iter().map(|w| w * w).sum();
        let parts = (want_parts && len.is_multiple_of(seg))
            .then(|| {
                (0..n_chunks)
                    .map(|c| {
                        let count = bounds(c + 1) - bounds(c);
                        density_matrix(&partials[c], n, len / seg, seg, sample_rate_hz, sum_w2, count)
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .transpose()?;
        Ok((
            density_matrix(&sums, n, 1, nfft, sample_rate_hz, sum_w2, n_segments)?,
            parts,
        ))
    }
}

/// The one-sided density matrix on an `fft_len`-point grid from pair sums (`[pair][bin]`, pairs
/// row by row of the upper triangle) on a grid `stride` times finer: every `stride`-th bin,
/// scaled by `1 / (fs sum(w^2) count)`, doubled except at 0 and Nyquist; auto-spectra real and
/// non-negative.
fn density_matrix(
    sums: &[Complex64],
    n: usize,
    stride: usize,
    fft_len: usize,
    sample_rate_hz: f64,
    sum_w2: f64,
    count: usize,
) -> Result<SpectralMatrix, SpectralError> {
    let fine_bins = sums.len() / (n * (n + 1) / 2).max(1);
    let n_bins = fft_len / 2 + 1;
    let base = 1.0 / (sample_rate_hz * sum_w2 * count.max(1) as f64);
    let mut data = vec![Complex64::default(); n_bins * n * n];
    let mut pairs = sums.chunks_exact(fine_bins.max(1));
    for i in 0..n {
        for j in i..n {
            let pair = pairs.next().unwrap_or_default();
            for (k, bin) in data.chunks_exact_mut(n * n).enumerate() {
                let s = pair.get(k * stride).copied().unwrap_or_default();
                let scale = if k == 0 || k == n_bins - 1 {
                    base
                } else {
                    2.0 * base
                };
                if i == j {
                    bin[i * n + i] = Complex64::new(s.re.max(0.0) * scale, 0.0);
                } else {
                    let s = s * scale;
                    bin[i * n + j] = s;
                    bin[j * n + i] = s.conj();
                }
            }
        }
    }
    let frequency_hz = (0..n_bins)
        .map(|k| k as f64 * sample_rate_hz / fft_len as f64)
        .collect();
    SpectralMatrix::from_parts(sample_rate_hz, fft_len, n, count, frequency_hz, data)
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
pub(super) fn check_input(
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
    /// Sum over the segments in `segments` of `X_i X_j^*` for `i <= j`, laid out `[pair][bin]`
    /// (pairs row by row of the upper triangle; auto-spectra real). Allocates once, not per segment.
    fn accumulate(&self, segments: std::ops::Range<usize>) -> Result<Vec<Complex64>, SpectralError> {
        let (n, nb) = (self.channels.len(), self.n_bins);
        let seg = self.settings.segment_len;
        let step = self.settings.step();
        let mut input = vec![0.0; self.fft.len()];
        let mut spectra = vec![Complex64::default(); n * nb];
        let mut scratch = vec![Complex64::default(); self.fft.get_scratch_len()];
        let mut acc = vec![Complex64::default(); nb * n * (n + 1) / 2];
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
            let mut pairs = acc.chunks_exact_mut(nb);
            for i in 0..n {
                let xi = &spectra[i * nb..(i + 1) * nb];
                for j in i..n {
                    let pair = pairs.next().unwrap_or_default();
                    if i == j {
                        pair.iter_mut().zip(xi).for_each(|(a, x)| a.re += x.norm_sqr());
                    } else {
                        let xj = &spectra[j * nb..(j + 1) * nb];
                        for ((a, p), q) in pair.iter_mut().zip(xi).zip(xj) {
                            *a += p * q.conj();
                        }
                    }
                }
            }
        }
        Ok(acc)
    }
}
