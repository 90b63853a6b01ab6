//! The spectral stage: the 6x6 one-sided Welch matrix of `[u; x]` for a block, split into
//! `S_uu`, `S_xu`, `S_xx` per bin (`S_xu = E[x u^H]`, so `x = W u` gives `S_xu = W S_uu`), plus
//! the equivalent number of independent averages of the overlapping segments (Welch 1967), which
//! sets the confidence of everything estimated from these spectra.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::alignment::{aligned, alignment_lag, restore_delay};
use super::signals::BlockSignals;
use super::stretches::{FinerStretches, StationarityCache, StretchSpectra, finer_segment_len, stretch_count};
use crate::spectral::centroid::{InputCentroids, InputMoments};
use crate::spectral::{SpectralError, SpectralMatrix, WelchPlanner, WelchSettings};

/// One block's spectral matrices on the one-sided Welch grid.
#[derive(Clone, Debug)]
pub struct BlockSpectra {
    /// Samples by which the outputs were moved earlier before the estimate
    /// ([`super::alignment`]; their delay given back in `s_xu` and the stretches'), 0 for none;
    /// negative: moved later (the inputs lag).
    pub aligned_samples: i64,
    /// Bin frequencies `k fs / N`, `k = 0..=N/2`, Hz.
    pub frequency_hz: Vec<f64>,
    /// Input spectral matrix per bin.
    pub s_uu: Vec<Matrix3<Complex64>>,
    /// Output-input cross-spectral matrix per bin.
    pub s_xu: Vec<Matrix3<Complex64>>,
    /// Output spectral matrix per bin.
    pub s_xx: Vec<Matrix3<Complex64>>,
    /// Number of segments averaged.
    pub n_averages: usize,
    /// Equivalent number of independent averages (overlap-corrected).
    pub equivalent_averages: f64,
    /// Each stretch's spectral matrices (the stationarity check, [`super::stretches`], and the
    /// halves of the held-out validation, [`super::holdout`]); two halves for a record too short
    /// for the stationarity check, empty for one too short to halve.
    pub stretches: Vec<StretchSpectra>,
    /// Stretches on a shorter segment for the stationarity check of a record too short for
    /// [`super::stretches::MIN_STRETCHES`] stretches at the settings' segment
    /// ([`super::stretches::finer_segment_len`]); `None` when `stretches` suffice or no shorter
    /// segment gives enough.
    pub finer_stretches: Option<FinerStretches>,
    /// The stretches' fits for the last band asked ([`super::stretches::cached_stationarity`]).
    pub stationarity_cache: StationarityCache,
    /// The held-out figures for the last band asked ([`super::holdout::cached_held_out`]).
    pub held_out_cache: super::holdout::HeldOutCache,
    /// The usable band found inside the auto limits asked ([`super::identify::resolve_band`]).
    /// This and the two caches above belong to these spectra: a copy whose spectral matrices are
    /// then changed must be given empty ones (`Default::default()`).
    pub usable_band_cache: super::band_cache::BandCache<[f64; 2]>,
    /// Variance inflation from the correlation of neighbouring native bins ([`bin_correlation`]).
    pub bin_correlation: f64,
    /// Per native bin, the inputs' power centroid ([`crate::spectral::centroid`]), Hz: the
    /// frequency at which the structural model is evaluated there ([`Self::fit_frequency_hz`]),
    /// each column moved there by its offset ([`Self::centroid_offset_hz`]).
    /// Empty: the bin centres.
    pub centroid_hz: Vec<f64>,
    /// Per native bin, where the `H1` estimate's columns lie about [`Self::centroid_hz`]
    /// (`spectral::centroid`, "Offset matrix"): `H1 = W(f_c) + W'(f_c) G`, Hz. Empty: none.
    pub centroid_offset_hz: Vec<Matrix3<Complex64>>,
    /// Whether these are the gyro's spectra and its outputs coloured the observer's angle-noise
    /// model (`stand::colour`): then its own noise is in that model, and the identification
    /// widens its gains' deviations by the bias that leaves ([`super::witness_noise`]). Set by
    /// the session; `false` from [`block_spectra`].
    pub gyro_witnessed: bool,
    /// For a block of a run whose gyro coloured the model (the gyro and an accelerometer beside
    /// it): what the model left out
    /// ([`super::left_out_noise`]), whose possible bias the identification puts into the gains'
    /// deviations. Set by the session; `None` from [`block_spectra`].
    pub left_out_noise: Option<std::sync::Arc<super::left_out_noise::LeftOutNoise>>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// FFT length (the two-sided grid length), samples.
    pub fft_len: usize,
    /// Welch segment length, samples: bins `k fft_len / segment_len` are the estimate's native,
    /// roughly independent resolution.
    pub segment_len: usize,
}

impl BlockSpectra {
    /// [`Self::aligned_samples`] in seconds.
    #[must_use]
    pub fn aligned_s(&self) -> f64 {
        self.aligned_samples as f64 / self.sample_rate_hz
    }

    /// Bins between two native (un-padded) bins: `fft_len / segment_len`, at least 1. Native bin
    /// `b` is bin `b * native_step()` of the padded grid.
    #[must_use]
    pub fn native_step(&self) -> usize {
        (self.fft_len / self.segment_len.max(1)).max(1)
    }

    /// Where the model is compared with an `H1` estimate (a ratio of the bin's own spectra) at
    /// bin `k`: the inputs' power centroid at a native bin ([`Self::centroid_hz`]), else the
    /// bin's centre.
    #[must_use]
    pub fn fit_frequency_hz(&self, k: usize) -> f64 {
        self.native_index(k)
            .and_then(|m| self.centroid_hz.get(m).copied())
            .unwrap_or(self.frequency_hz[k])
    }

    /// The native bin that padded bin `k` is, if it is one: native bin `m` is padded bin
    /// `m native_step()` only on a grid a whole multiple of the segment.
    #[must_use]
    pub fn native_index(&self, k: usize) -> Option<usize> {
        let step = self.native_step();
        let aligned = self.fft_len.is_multiple_of(self.segment_len.max(1));
        (aligned && k.is_multiple_of(step)).then_some(k / step)
    }

    /// The offset matrix `G` of bin `k` ([`Self::centroid_offset_hz`]) where the model is
    /// compared at a native bin's centroid; `None` elsewhere and for a zero `G`.
    #[must_use]
    pub fn fit_offset_hz(&self, k: usize, estimate: super::settings::Estimate) -> Option<Matrix3<Complex64>> {
        self.native_index(k)
            .filter(|_| estimate == super::settings::Estimate::H1)
            .and_then(|m| self.centroid_offset_hz.get(m).copied())
            .filter(|g| g.iter().any(|z| *z != Complex64::new(0.0, 0.0)))
    }

    /// [`Self::fit_offset_hz`] over `bins` (a zero matrix where there is none); `None` when no
    /// bin has one.
    #[must_use]
    pub fn fit_offsets_hz(
        &self,
        bins: &[usize],
        estimate: super::settings::Estimate,
    ) -> Option<Vec<Matrix3<Complex64>>> {
        let offsets: Vec<Option<Matrix3<Complex64>>> =
            bins.iter().map(|&k| self.fit_offset_hz(k, estimate)).collect();
        offsets
            .iter()
            .any(Option::is_some)
            .then(|| offsets.into_iter().map(Option::unwrap_or_default).collect())
    }

    /// Where the model is compared with `estimate` at bin `k`: [`Self::fit_frequency_hz`] for
    /// `H1`; the bin's centre for the causal Wiener filter, which is a filter's response on the
    /// grid (each bin made from the spectra at every frequency), not a ratio of the bin's content.
    #[must_use]
    pub fn model_frequency_hz(&self, k: usize, estimate: super::settings::Estimate) -> f64 {
        match estimate {
            super::settings::Estimate::H1 => self.fit_frequency_hz(k),
            super::settings::Estimate::CausalWiener => self.frequency_hz[k],
        }
    }
}

/// Zero-padding factor of the identifier's spectra when the settings give no `fft_len`. The Welch
/// estimate's correlation spans `2 segment_len - 1` lags, so its exact minimum-phase factor is a
/// causal FIR of `segment_len` taps; a grid of `4 segment_len` holds that factor, shifted by any
/// plausible delay, without wrapping, which keeps the causal projection `[.]_+` exact.
pub const ZERO_PAD: usize = 4;

/// The identifier's FFT length: the settings' `fft_len` (else [`ZERO_PAD`] segments) rounded up
/// to a whole number of segments. The native (un-padded) bins are then bins of the padded grid,
/// every `fft_len / segment_len`-th, at their own frequencies: the whole record's fit, the
/// stretches of the stationarity check and the held-out halves (each on its native grid) are
/// compared at the same frequencies. A user's `fft_len` between two multiples (scipy's `nfft`
/// allows any even length) would put the padded bins the fit uses beside the native ones the
/// stretches are estimated at: their delays came out 22 % off, said by nothing. Padding further
/// samples the same estimate more finely and changes nothing else.
#[must_use]
pub fn grid_len(settings: &WelchSettings) -> usize {
    let segment = settings.segment_len.max(1);
    let asked = settings.fft_len.unwrap_or(ZERO_PAD.saturating_mul(segment));
    // A length whose next multiple overflows is left as asked (the estimator refuses it).
    asked.div_ceil(segment).checked_mul(segment).unwrap_or(asked)
}

/// Computes the block's spectra with `planner` (plans and windows are reused across calls); the
/// FFT length is [`grid_len`].
///
/// # Errors
/// The Welch estimator's errors: bad settings, a run shorter than one segment, NaN samples.
pub fn block_spectra(
    planner: &mut WelchPlanner,
    signals: &BlockSignals,
    sample_rate_hz: f64,
    settings: &WelchSettings,
) -> Result<BlockSpectra, SpectralError> {
    let settings = &WelchSettings {
        fft_len: Some(grid_len(settings)),
        ..*settings
    };
    let whole: Vec<&[f64]> = signals
        .input
        .iter()
        .chain(signals.output.iter())
        .map(Vec::as_slice)
        .collect();
    let (m, parts) = record_matrix(planner, &whole, sample_rate_hz, settings)?;
    let window = planner.window(settings.window, settings.segment_len);
    let (s_uu, s_xu, s_xx) = (part(&m, 0, 0), part(&m, 3, 0), part(&m, 3, 3));
    // The outputs moved by whole samples where they lag the inputs enough to smear the estimate
    // (`super::alignment`); the record's estimate again on the aligned copies.
    let lag = alignment_lag(&s_uu, &s_xu, &s_xx, &window, sample_rate_hz);
    let record_len = whole.first().map_or(0, |c| c.len());
    let lag = if record_len.saturating_sub(lag.unsigned_abs() as usize) >= settings.segment_len {
        lag
    } else {
        0
    };
    let (channels, start) = aligned(&whole, lag);
    // The first estimate's blocks are kept unless the aligned estimate replaces them.
    let (m, parts, lag, channels, start, (s_uu, s_xu, s_xx)) = if lag == 0 {
        (m, parts, lag, channels, start, (s_uu, s_xu, s_xx))
    } else {
        let (moved, moved_parts) = record_matrix(planner, &channels, sample_rate_hz, settings)?;
        // Kept only where it brings the outputs closer to the inputs: a lag read off a
        // distorted impulse response would smear the estimate more.
        if super::alignment::coherence_gain(&m, &moved) > 0.0 {
            let blocks = (part(&moved, 0, 0), part(&moved, 3, 0), part(&moved, 3, 3));
            (moved, moved_parts, lag, channels, start, blocks)
        } else {
            (m, parts, 0, whole.clone(), 0, (s_uu, s_xu, s_xx))
        }
    };
    let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
    let n_stretches = stretch_count(n_segments);
    let mut stretches = match parts {
        Some(parts) => stretches_of(&parts, n_segments, settings, sample_rate_hz, &window),
        None => stretch_spectra(planner, &channels, sample_rate_hz, settings, &window)?,
    };
    // The inputs' moments per stretch (the same groups of segments), summed for the record.
    let inputs = [channels[0], channels[1], channels[2]];
    let moments = planner.input_moments(inputs, sample_rate_hz, settings, n_stretches.max(1))?;
    let centroids = moments
        .as_ref()
        .and_then(|parts| InputMoments::sum(&parts.iter().collect::<Vec<_>>()))
        .map_or_else(
            || InputCentroids::centres(sample_rate_hz, settings.segment_len),
            |m| m.centroids(),
        );
    if let Some(parts) = moments
        && parts.len() == stretches.len()
    {
        for (stretch, m) in stretches.iter_mut().zip(parts) {
            stretch.moments = Some(m);
        }
    }
    let n_samples = channels.first().map_or(0, |c| c.len());
    // Only where the settings' segment gives too few stretches (`finer_segment_len` says None
    // otherwise).
    let mut finer_stretches = match finer_segment_len(settings, n_samples) {
        Some(segment_len) => {
            let finer = WelchSettings {
                segment_len,
                fft_len: None,
                ..*settings
            };
            let window = planner.window(finer.window, segment_len);
            Some(FinerStretches {
                segment_len,
                stretches: stretch_spectra(planner, &channels, sample_rate_hz, &finer, &window)?,
            })
        }
        None => None,
    };
    let stretch_sets =
        std::iter::once(&mut stretches).chain(finer_stretches.as_mut().map(|f| &mut f.stretches));
    for set in stretch_sets {
        for stretch in set.iter_mut() {
            let moments = stretch.moments.as_ref();
            restore_delay(&mut stretch.s_xu, lag, sample_rate_hz, |b| {
                moments.and_then(|m| m.centroid_at(b)).map(|(fc, _)| fc)
            });
            stretch.span_s = stretch.span_s.map(|t| t + start as f64 / sample_rate_hz);
        }
    }
    let mut spectra = BlockSpectra {
        aligned_samples: lag,
        centroid_hz: centroids.hz,
        centroid_offset_hz: centroids.offset_hz,
        gyro_witnessed: false,
        left_out_noise: None,
        stretches,
        finer_stretches,
        stationarity_cache: StationarityCache::default(),
        held_out_cache: super::holdout::HeldOutCache::default(),
        usable_band_cache: super::band_cache::BandCache::default(),
        frequency_hz: m.frequency_hz.clone(),
        s_uu,
        s_xu,
        s_xx,
        n_averages: m.n_averages,
        equivalent_averages: equivalent_averages(&window, settings.step(), m.n_averages),
        bin_correlation: bin_correlation(&window),
        sample_rate_hz,
        fft_len: settings.nfft(),
        segment_len: settings.segment_len,
    };
    // Each native bin given back its delay where the fit compares it (at its centroid).
    let mut s_xu = std::mem::take(&mut spectra.s_xu);
    let at = |k: usize| spectra.centroid_hz.get(spectra.native_index(k)?).copied();
    restore_delay(&mut s_xu, lag, sample_rate_hz, at);
    spectra.s_xu = s_xu;
    Ok(spectra)
}

/// The `3 x 3` block of `m` from row `r0` and column `c0` at every bin (`[u; x]`: `(0, 0)` the
/// inputs' `S_uu`, `(3, 0)` `S_xu`, `(3, 3)` `S_xx`).
fn part(m: &SpectralMatrix, r0: usize, c0: usize) -> Vec<Matrix3<Complex64>> {
    (0..m.n_bins())
        .map(|f| Matrix3::from_fn(|i, j| m[(f, r0 + i, c0 + j)]))
        .collect()
}

/// The record's matrix of `channels` and, where the grid allows, its stretches' matrices from the
/// same segment transforms ([`WelchPlanner::welch_matrix_parts`]; else `None`: a second pass).
fn record_matrix(
    planner: &mut WelchPlanner,
    channels: &[&[f64]],
    sample_rate_hz: f64,
    settings: &WelchSettings,
) -> Result<(SpectralMatrix, Option<Vec<SpectralMatrix>>), SpectralError> {
    let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
    let n_stretches = stretch_count(n_segments);
    if n_stretches > 0 {
        planner.welch_matrix_parts(channels, sample_rate_hz, settings, n_stretches)
    } else {
        Ok((planner.welch_matrix(channels, sample_rate_hz, settings)?, None))
    }
}

/// The stretches from the groups' matrices of [`WelchPlanner::welch_matrix_parts`] (group `i` is
/// stretch `i`: the same segments as [`stretch_spectra`] takes).
fn stretches_of(
    parts: &[crate::spectral::SpectralMatrix],
    n_segments: usize,
    settings: &WelchSettings,
    sample_rate_hz: f64,
    window: &[f64],
) -> Vec<StretchSpectra> {
    let m = parts.len();
    let step = settings.step();
    parts
        .iter()
        .enumerate()
        .map(|(i, sm)| {
            let (first, last) = (i * n_segments / m, (i + 1) * n_segments / m);
            let (start, end) = (first * step, (last - 1) * step + settings.segment_len);
            stretch(sm, [start, end], sample_rate_hz, window, step)
        })
        .collect()
}

/// One stretch (samples `span[0]..span[1]`) from its un-padded 6x6 matrix of `[u; x]`.
fn stretch(
    sm: &crate::spectral::SpectralMatrix,
    span: [usize; 2],
    sample_rate_hz: f64,
    window: &[f64],
    step: usize,
) -> StretchSpectra {
    let block = |f: usize, r0: usize, c0: usize| Matrix3::from_fn(|a, b| sm[(f, r0 + a, c0 + b)]);
    let bins = sm.n_bins();
    StretchSpectra {
        span_s: span.map(|k| k as f64 / sample_rate_hz),
        s_uu: (0..bins).map(|f| block(f, 0, 0)).collect(),
        s_xu: (0..bins).map(|f| block(f, 3, 0)).collect(),
        s_xx: (0..bins).map(|f| block(f, 3, 3)).collect(),
        equivalent_averages: equivalent_averages(window, step, sm.n_averages),
        moments: None,
    }
}

/// The spectral matrices of each stretch ([`super::stretches`]) on the segment's native grid,
/// by a second Welch pass over each stretch.
fn stretch_spectra(
    planner: &mut WelchPlanner,
    channels: &[&[f64]],
    sample_rate_hz: f64,
    settings: &WelchSettings,
    window: &[f64],
) -> Result<Vec<StretchSpectra>, SpectralError> {
    let n_segments = settings.n_segments(channels.first().map_or(0, |c| c.len()));
    let m = stretch_count(n_segments);
    let native = WelchSettings {
        fft_len: None,
        ..*settings
    };
    let step = settings.step();
    (0..m)
        .map(|i| {
            let (first, last) = (i * n_segments / m, (i + 1) * n_segments / m);
            let (start, end) = (first * step, (last - 1) * step + settings.segment_len);
            let slices: Vec<&[f64]> = channels.iter().map(|c| &c[start..end]).collect();
            let sm = planner.welch_matrix(&slices, sample_rate_hz, &native)?;
            Ok(stretch(&sm, [start, end], sample_rate_hz, window, step))
        })
        .collect()
}

/// Variance inflation of a quantity that varies slowly across native bins, from the correlation
/// of neighbouring native bins of one windowed segment: `sum_d rho(d)`, `d` over all offsets,
/// `rho(d) = |sum_n w_n^2 e^(-2 pi i d n / L)|^2 / (sum_n w_n^2)^2` (the correlation of periodogram
/// ordinates `d` bins apart for a smooth spectrum). A fit that treats the native bins as
/// independent states a variance this many times too small. Rectangular window: 1; periodic
/// Hann: `1 + 2 (4/9 + 1/36) = 1.944`.
#[must_use]
pub fn bin_correlation(w: &[f64]) -> f64 {
    let l = w.len();
    let w2: Vec<f64> = w.iter().map(|v| v * v).collect();
    let energy: f64 = w2.iter().sum();
    if l == 0 || energy <= 0.0 {
        return 1.0;
    }
    let mut total = 1.0;
    for d in 1..l.min(16) {
        let (mut re, mut im) = (0.0, 0.0);
        for (n, v) in w2.iter().enumerate() {
            let phase = -2.0 * std::f64::consts::PI * (d * n % l) as f64 / l as f64;
            re += v * phase.cos();
            im += v * phase.sin();
        }
        total += 2.0 * (re * re + im * im) / (energy * energy);
    }
    total
}

/// The window's normalised overlap correlation at a shift of `shift` samples,
/// `sum_n w_n w_(n+shift) / sum_n w_n^2`: 0 from the window's length on, and for a window of no
/// energy.
#[must_use]
pub fn overlap_correlation(w: &[f64], shift: usize) -> f64 {
    let energy: f64 = w.iter().map(|v| v * v).sum();
    if energy <= 0.0 || shift >= w.len() {
        return 0.0;
    }
    w[shift..].iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / energy
}

/// Welch's equivalent number of averages for `k` segments of window `w` stepped by `step`:
/// `k / (1 + 2 sum_l (1 - l/k) rho(l)^2)`, with `rho(l)` the window's normalised overlap
/// correlation at a shift of `l` steps.
#[must_use]
pub fn equivalent_averages(w: &[f64], step: usize, k: usize) -> f64 {
    let energy: f64 = w.iter().map(|v| v * v).sum();
    if k == 0 || energy <= 0.0 || step == 0 {
        return k as f64;
    }
    let mut sum = 0.0;
    for l in 1..k {
        let shift = l * step;
        if shift >= w.len() {
            break;
        }
        let rho = overlap_correlation(w, shift);
        sum += (1.0 - l as f64 / k as f64) * rho * rho;
    }
    k as f64 / (1.0 + 2.0 * sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::Window;

    #[test]
    fn bin_correlation_of_known_windows() {
        assert!((bin_correlation(&vec![1.0; 256]) - 1.0).abs() < 1e-9);
        let hann = Window::Hann.coefficients(256);
        let closed = 1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0);
        assert!(
            (bin_correlation(&hann) - closed).abs() < 1e-3,
            "{}",
            bin_correlation(&hann)
        );
    }

    #[test]
    fn equivalent_averages_of_known_cases() {
        // No overlap: independent segments.
        let w = Window::Hann.coefficients(256);
        assert!((equivalent_averages(&w, 256, 10) - 10.0).abs() < 1e-12);
        // Hann at 50 % overlap: rho = 1/6 (closed form for the periodic window), so for many
        // segments the ratio tends to 1/(1 + 2/36) = 0.947.
        let ratio = equivalent_averages(&w, 128, 10_000) / 10_000.0;
        assert!((ratio - 1.0 / (1.0 + 2.0 / 36.0)).abs() < 1e-3, "{ratio}");
        // Rectangular at 50 %: rho = 1/2, ratio -> 1/1.5.
        let r = vec![1.0; 256];
        assert!((equivalent_averages(&r, 128, 10_000) / 10_000.0 - 2.0 / 3.0).abs() < 1e-3);
    }
}
