//! Stationarity: the block identified on consecutive stretches of the record.
//!
//! The record is cut into `M` stretches of whole Welch segments ([`stretch_count`]: at least
//! [`MIN_SEGMENTS`] segments each, at most [`MAX_STRETCHES`] stretches, none when fewer than
//! [`MIN_STRETCHES`] fit). Each stretch gets its own spectral matrices on the segment's native grid
//! (no zero-padding: they only feed an order-0 fit) and its own `K e^(-tau s)`, fitted to the H1
//! estimate `S_xu S_uu^-1` over the block's band with the stretch's own residual weights (as given:
//! not narrowed to the stretch's scatter, `structural::scatter`, since they are floors), each
//! bin compared where the stretch's own inputs' power lies (its moments' centroids and offset
//! matrices, [`compared_at`]: a stepped sine programme's lines differ from stretch to stretch).
//!
//! What they are for:
//! - **Honest uncertainty**: the spread of the stretches' `K` and `tau` is a measurement of the
//!   estimate's variance that does not rest on the noise model (coloured reference noise, bins
//!   that are not independent, a misfit the weights do not know): the standard deviation of the
//!   whole record's estimate is at least `sd(stretches) / sqrt(M)`.
//! - **A stationarity check**: a delay that drifts through the record (the block and the stand
//!   logging on separate clocks) shows as a trend of the stretches' delays; a gain that changes
//!   (temperature, a loose mount) as a spread well beyond the stretches' own uncertainties.
//!
//! A record too short for [`MIN_STRETCHES`] stretches at the settings' segment is cut into
//! stretches of a shorter segment for this check ([`finer_segment_len`], [`FinerStretches`]).
//!
//! Units: s, Hz, `K` in block units over input units. A stretch whose fit fails is left out, and
//! so is one whose best delay is the scan's end, which is named ([`Stationarity::no_delay_s`]);
//! fewer than [`MIN_STRETCHES`] fitted stretches (one fewer when some were named), or a record
//! too short even on the shortest segment, give no summary.

use serde::{Deserialize, Serialize};

use super::delay_step::DelayStep;
use super::explained::InputEigen;

use super::band::native_bins;
use super::spectra::BlockSpectra;
use super::structural::{OrderChoice, ResponseEstimate, StructuralSettings, Weights, fit_structure};
use crate::spectral::centroid::InputMoments;
use nalgebra::Matrix3;
use num_complex::Complex64;

/// Fewest Welch segments per stretch.
pub const MIN_SEGMENTS: usize = 6;
/// Most stretches.
pub const MAX_STRETCHES: usize = 24;
/// Fewest stretches for a summary.
pub const MIN_STRETCHES: usize = 4;

/// One stretch's spectral matrices on the segment's native grid.
#[derive(Clone, Debug)]
pub struct StretchSpectra {
    /// Start and end of the stretch, s from the first sample.
    pub span_s: [f64; 2],
    /// Input spectral matrix per native bin.
    pub s_uu: Vec<Matrix3<Complex64>>,
    /// Output-input cross-spectral matrix per native bin.
    pub s_xu: Vec<Matrix3<Complex64>>,
    /// Output spectral matrix per native bin.
    pub s_xx: Vec<Matrix3<Complex64>>,
    /// Equivalent number of averages.
    pub equivalent_averages: f64,
    /// The inputs' moments over the stretch's segments (`spectral::centroid`): where its own
    /// `H1` columns lie. `None`: compared at the bin centres (a window open at its ends, the
    /// finer stretches).
    pub moments: Option<InputMoments>,
}

/// How many stretches a record of `n_segments` Welch segments (`step` apart) is cut into: up to
/// [`MAX_STRETCHES`] of at least [`MIN_SEGMENTS`] segments each; a record too short for
/// [`MIN_STRETCHES`] of them is cut into its two halves when each has [`MIN_SEGMENTS`] (the
/// held-out validation of the order, [`super::holdout`], needs only those; the stationarity check
/// is then made on a shorter segment, [`finer_segment_len`]), and not at all when shorter still.
#[must_use]
pub fn stretch_count(n_segments: usize) -> usize {
    let m = (n_segments / MIN_SEGMENTS).min(MAX_STRETCHES);
    if m >= MIN_STRETCHES {
        m
    } else if m >= 2 {
        2
    } else {
        0
    }
}

/// Stretches cut on a shorter Welch segment than the settings' (each on its own native grid,
/// `k fs / segment_len`): the stationarity check of a record too short for [`MIN_STRETCHES`]
/// stretches of [`MIN_SEGMENTS`] segments at the settings' segment.
#[derive(Clone, Debug)]
pub struct FinerStretches {
    /// Their segment length, samples.
    pub segment_len: usize,
    /// The stretches, in time order.
    pub stretches: Vec<StretchSpectra>,
}

/// Shortest segment the stationarity check falls back to, as a divisor of the settings' segment
/// (a quarter: the stretches' bins are then 4x wider, still many across a band of a few Hz, and
/// the order-0 fit they feed needs no fine resolution).
const FINER_SEGMENT_DIVISOR: usize = 4;
/// Shortest segment the stationarity check falls back to, samples.
const FINER_SEGMENT_MIN: usize = 256;

/// The longest segment, halving the settings' down to a quarter of it (and not below
/// [`FINER_SEGMENT_MIN`] samples), that cuts a record of `n_samples` into [`MIN_STRETCHES`]
/// stretches of [`MIN_SEGMENTS`] segments; `None` when the settings' own segment already does,
/// or none does.
///
/// Why: without stretches a record's standard deviations rest on the noise model alone, and on
/// a short real record (132 s at 286 Hz with the default 4096-sample segment: 17 segments) that
/// model's errors go unchecked; the spread of the stretches' estimates on a shorter segment is
/// a floor on the whole record's variance that does not rest on it (the longer segment's
/// estimate is no less variable than that spread implies, since the delay and the gain are
/// carried by the band's many bins, not by its finest resolution).
#[must_use]
pub fn finer_segment_len(settings: &crate::spectral::WelchSettings, n_samples: usize) -> Option<usize> {
    if stretch_count(settings.n_segments(n_samples)) >= MIN_STRETCHES {
        return None;
    }
    let shortest = (settings.segment_len / FINER_SEGMENT_DIVISOR).max(FINER_SEGMENT_MIN);
    let mut len = settings.segment_len / 2;
    while len >= shortest && len.is_multiple_of(2) {
        let finer = crate::spectral::WelchSettings {
            segment_len: len,
            ..*settings
        };
        if stretch_count(finer.n_segments(n_samples)) >= MIN_STRETCHES {
            return Some(len);
        }
        len /= 2;
    }
    None
}

/// One stretch's order-0 fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StretchFit {
    /// Start and end, s from the first sample.
    pub span_s: [f64; 2],
    /// Static gain.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Delay, s.
    pub tau_s: f64,
    /// Its standard deviation (from the stretch's own fit), s.
    pub tau_std_s: f64,
}

/// The stretches' fits and what they say about the whole record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stationarity {
    /// Every fitted stretch, in time order.
    pub stretches: Vec<StretchFit>,
    /// `sd(K_m) / sqrt(M)` per element: the standard deviation of the whole record's `K` that
    /// the stretches' spread implies.
    #[serde(rename = "K_spread_std")]
    pub k_spread_std: [[f64; 3]; 3],
    /// `sd(tau_m) / sqrt(M)`, s.
    pub tau_spread_std_s: f64,
    /// The stretches' Welch segment, samples, when it is shorter than the settings' (a record too
    /// short for [`MIN_STRETCHES`] stretches at the settings' segment, [`FinerStretches`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segment_len: Option<usize>,
    /// Least-squares slope of the stretches' delays against time, s per s (the delay grows by
    /// this much each second; 1e-6 is 1 ppm of clock rate).
    pub tau_trend: f64,
    /// Its standard deviation: from the residuals about the line, never below what the stretches'
    /// own delay deviations give the slope (`line_slope`).
    pub tau_trend_std: f64,
    /// The spans (s) of the stretches left out because their best delay was the scan's end
    /// ([`STRETCH_DELAY_REACH_S`]): there the block's response is not the record's (a fault, a
    /// clock jump, motion folded about Nyquist). Said as a warning.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub no_delay_s: Vec<[f64; 2]>,
    /// A step in the stretches' delays ([`super::delay_step`]): the streams slipped against
    /// each other. Said as a warning, in place of a drift.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay_step: Option<super::delay_step::DelayStep>,
}

impl Stationarity {
    /// Whether the delay's trend is significant (beyond 4 of its standard deviations) and
    /// material (over the record it moves the delay by more than 3 standard deviations of a
    /// stretch's delay); where the delays step, the slope is the one both sides of the step
    /// share ([`Self::drift`]: a line through a step is no drift).
    #[must_use]
    pub fn drifts(&self) -> bool {
        let (trend, trend_std) = self.drift();
        let (Some(first), Some(last)) = (self.stretches.first(), self.stretches.last()) else {
            return false;
        };
        let duration = last.span_s[1] - first.span_s[0];
        let median_std = {
            let mut s: Vec<f64> = self.stretches.iter().map(|s| s.tau_std_s).collect();
            s.sort_by(f64::total_cmp);
            s[s.len() / 2]
        };
        trend.abs() > 4.0 * trend_std && (trend * duration).abs() > 3.0 * median_std
    }

    /// The delay's slope against time and its standard deviation, s per s: the line's, or where
    /// the delay steps the slope the step's two sides share ([`super::delay_step`]).
    #[must_use]
    pub fn drift(&self) -> (f64, f64) {
        match self.delay_step {
            None => (self.tau_trend, self.tau_trend_std),
            Some(DelayStep {
                trend: Some([t, sd]), ..
            }) => (t, sd),
            // Too few stretches beside the step for a slope: no drift can be told.
            Some(_) => (0.0, f64::INFINITY),
        }
    }
}

/// How far from zero a stretch's delay is searched, s: wider than the whole record's range,
/// since with drifting clocks a stretch's delay moves far from the record's (200 ppm over 25
/// minutes is 0.3 s); a range that cut it off would flatten the very trend the check measures.
pub const STRETCH_DELAY_REACH_S: f64 = 0.3;

/// Fits every stretch of `spectra` over `band_hz` and summarises them; `None` without stretches
/// or with too few fitted ([`summarise`]).
#[must_use]
pub fn stationarity(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Option<Stationarity> {
    let (stretches, segment_len) = if spectra.stretches.len() >= MIN_STRETCHES {
        let native = native_bins(spectra, band_hz);
        let centres: Vec<f64> = native.iter().map(|&k| spectra.frequency_hz[k]).collect();
        let fits: Vec<Outcome> = spectra
            .stretches
            .iter()
            .map(|s| {
                let (frequency_hz, offsets) = compared_at(spectra, s, &native, &centres);
                let at = At {
                    frequency_hz: &frequency_hz,
                    offset_hz: offsets.as_deref(),
                    aligned_s: spectra.aligned_s(),
                };
                fit_stretch(s, &native, spectra.native_step(), at)
            })
            .collect();
        (fits, None)
    } else {
        // The finer stretches' own native grid: bin `k` at `k fs / segment_len`.
        let finer = spectra.finer_stretches.as_ref()?;
        let bin_hz = |k: usize| k as f64 * spectra.sample_rate_hz / finer.segment_len as f64;
        let native: Vec<usize> = (0..=finer.segment_len / 2)
            .filter(|&k| (band_hz[0]..=band_hz[1]).contains(&bin_hz(k)))
            .collect();
        let frequency_hz: Vec<f64> = native.iter().map(|&k| bin_hz(k)).collect();
        let at = At {
            frequency_hz: &frequency_hz,
            offset_hz: None,
            aligned_s: spectra.aligned_s(),
        };
        let fits = finer
            .stretches
            .iter()
            .map(|s| fit_stretch(s, &native, 1, at))
            .collect();
        (fits, Some(finer.segment_len))
    };
    summarise(stretches, segment_len, spectra.sample_rate_hz)
}

/// What the fit of one stretch gave.
#[derive(Debug)]
enum Outcome {
    /// Fitted.
    Fitted(StretchFit),
    /// The best delay is the scan's end ([`STRETCH_DELAY_REACH_S`]): the stretch's response is
    /// not the record's (its span, s).
    NoDelay([f64; 2]),
    /// The fit failed (a singular input spectrum, too few bins).
    Failed,
}

/// The summary of the stretches' outcomes ([`stationarity`]): `None` with fewer than
/// [`MIN_STRETCHES`] fitted, or one fewer when stretches with no delay were left out (the check
/// is then made on the others and the warning names them: an independent simulator's run lost it
/// to one stretch of four).
fn summarise(
    outcomes: Vec<Outcome>,
    segment_len: Option<usize>,
    sample_rate_hz: f64,
) -> Option<Stationarity> {
    let mut stretches = Vec::with_capacity(outcomes.len());
    let mut no_delay_s = Vec::new();
    for outcome in outcomes {
        match outcome {
            Outcome::Fitted(fit) => stretches.push(fit),
            Outcome::NoDelay(span) => no_delay_s.push(span),
            Outcome::Failed => {}
        }
    }
    let m = stretches.len();
    let fewest = if no_delay_s.is_empty() {
        MIN_STRETCHES
    } else {
        MIN_STRETCHES - 1
    };
    if m < fewest {
        return None;
    }
    let spread = |values: &dyn Fn(&StretchFit) -> f64| {
        let mean = stretches.iter().map(values).sum::<f64>() / m as f64;
        let var = stretches.iter().map(|s| (values(s) - mean).powi(2)).sum::<f64>() / (m - 1) as f64;
        (var / m as f64).sqrt()
    };
    let k_spread_std = std::array::from_fn(|i| std::array::from_fn(|j| spread(&|s: &StretchFit| s.k[i][j])));
    let tau_spread_std_s = spread(&|s: &StretchFit| s.tau_s);
    let t: Vec<f64> = stretches
        .iter()
        .map(|s| 0.5 * (s.span_s[0] + s.span_s[1]))
        .collect();
    let y: Vec<f64> = stretches.iter().map(|s| s.tau_s).collect();
    let own_std: Vec<f64> = stretches.iter().map(|s| s.tau_std_s).collect();
    let (tau_trend, tau_trend_std) = line_slope(&t, &y, &own_std);
    let delay_step = super::delay_step::delay_step(&stretches, sample_rate_hz);
    Some(Stationarity {
        stretches,
        k_spread_std,
        tau_spread_std_s,
        segment_len,
        tau_trend,
        tau_trend_std,
        no_delay_s,
        delay_step,
    })
}

/// Ordinary least-squares slope of `y` on `t` and its standard deviation: from the residuals
/// about the line, floored by what the points' own standard deviations `y_std` give the slope
/// (`sqrt(sum (t - t_mean)^2 y_std^2) / sum (t - t_mean)^2`). A record gives as few as four
/// stretches: two degrees of freedom for the residuals, whose estimate is then often far too small
/// (four delays that happen to fall near a line), and an independent simulator's clean 120 s runs
/// were warned of a drift of 3 us where the stretches' own errors were 0.9 us each.
fn line_slope(t: &[f64], y: &[f64], y_std: &[f64]) -> (f64, f64) {
    let n = t.len() as f64;
    let (tm, ym) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let stt: f64 = t.iter().map(|v| (v - tm).powi(2)).sum();
    if stt <= 0.0 || n < 3.0 {
        return (0.0, f64::INFINITY);
    }
    let slope = t.iter().zip(y).map(|(a, b)| (a - tm) * (b - ym)).sum::<f64>() / stt;
    let rss: f64 = t
        .iter()
        .zip(y)
        .map(|(a, b)| (b - ym - slope * (a - tm)).powi(2))
        .sum();
    let from_residuals = (rss / (n - 2.0) / stt).sqrt();
    // A point whose own deviation is not finite adds nothing to the floor (the residuals still
    // count it).
    let from_own: f64 = t
        .iter()
        .zip(y_std)
        .filter(|(_, s)| s.is_finite())
        .map(|(a, s)| ((a - tm) * s).powi(2))
        .sum::<f64>()
        .sqrt()
        / stt;
    (slope, from_residuals.max(from_own))
}

/// Where stretch `s`'s `H1` at the native band bins `native` (indices into `spectra`'s padded
/// grid) is compared with the model: its own inputs' centroids and offset matrices
/// ([`StretchSpectra::moments`]; a stretch's lines are its own, a stepped sine programme's differ
/// from stretch to stretch) on a grid a whole multiple of the segment, else `centres` without
/// offsets; `None` for the offsets when every one is zero.
#[must_use]
pub fn compared_at(
    spectra: &BlockSpectra,
    s: &StretchSpectra,
    native: &[usize],
    centres: &[f64],
) -> (Vec<f64>, Option<Vec<Matrix3<Complex64>>>) {
    let Some(moments) = s.moments.as_ref() else {
        return (centres.to_vec(), None);
    };
    // The band's bins alone: each bin's centroid and offsets are its own moments'.
    let (frequency_hz, offsets): (Vec<f64>, Vec<Matrix3<Complex64>>) = native
        .iter()
        .zip(centres)
        .map(|(&k, &f)| {
            spectra
                .native_index(k)
                .and_then(|b| moments.centroid_at(b))
                .unwrap_or((f, Matrix3::zeros()))
        })
        .unzip();
    let any = offsets.iter().any(|g| g.iter().any(|z| z.norm() > 0.0));
    (frequency_hz, any.then_some(offsets))
}

/// Where a stretch's bins are compared with the model: their frequencies and offset matrices
/// (`ResponseEstimate`'s).
#[derive(Clone, Copy)]
struct At<'a> {
    frequency_hz: &'a [f64],
    offset_hz: Option<&'a [Matrix3<Complex64>]>,
    /// `StructuralSettings::aligned_s`.
    aligned_s: f64,
}

/// The order-0 fit of one stretch over the native band bins (`native` indexes the padded grid,
/// `step` apart; the stretch holds every native bin).
fn fit_stretch(s: &StretchSpectra, native: &[usize], step: usize, at: At) -> Outcome {
    let Some((response, weights)) = h1_estimate(s, native, step) else {
        return Outcome::Failed;
    };
    let input = ResponseEstimate {
        frequency_hz: at.frequency_hz,
        response: &response,
        weights: Weights::RowWeight(&weights),
        offset_hz: at.offset_hz,
    };
    // The stretches' deviations floor the record's and judge its drift: their weights stay as
    // given (`structural::scatter` would narrow them to each stretch's own scatter).
    let reach = StructuralSettings {
        tau_min_s: -STRETCH_DELAY_REACH_S,
        tau_max_s: STRETCH_DELAY_REACH_S,
        narrow_to_scatter: false,
        aligned_s: at.aligned_s,
        ..StructuralSettings::default()
    };
    let Ok(fit) = fit_structure(&input, OrderChoice::Fixed(0), &reach) else {
        return Outcome::Failed;
    };
    // A delay at the scan's end is no maximum of the fit's objective, only the best the range
    // allowed: not a measurement of this stretch. An independent simulator's run whose motion
    // folds about Nyquist gave one stretch of four tau = -0.3 s and K = -0.8 times a rotation
    // beside three at 3.000 ms, and its spread put K's deviations at 0.45 with a false "too
    // little motion". Such a stretch is left out and named (`Stationarity::no_delay_s`). (A refit
    // over a narrower range was tried and not kept: a window of tens of milliseconds holds a side
    // lobe of any band's delay scan, whose K would be counted as a measurement.)
    if fit.tau_s <= reach.tau_min_s + 1e-12 || fit.tau_s >= reach.tau_max_s - 1e-12 {
        return Outcome::NoDelay(s.span_s);
    }
    Outcome::Fitted(StretchFit {
        span_s: s.span_s,
        k: fit.k,
        tau_s: fit.tau_s,
        tau_std_s: fit.tau_std_s,
    })
}

/// An `H1` estimate over the band's native bins and each bin's three row weights.
pub(super) type H1Estimate = (Vec<Matrix3<Complex64>>, Vec<[Matrix3<Complex64>; 3]>);

/// The `H1` estimate `S_xu S_uu^-1` of a stretch (or of any run of stretches merged) at the native
/// band bins (`native` indexes the padded grid, `step` apart), with the generalised least-squares
/// row weights of its residual; `None` when a bin is missing or `S_uu` singular there.
pub(super) fn h1_estimate(s: &StretchSpectra, native: &[usize], step: usize) -> Option<H1Estimate> {
    let dof = (s.equivalent_averages - 3.0).max(1.0);
    let mut response = Vec::with_capacity(native.len());
    let mut weights = Vec::with_capacity(native.len());
    for &k in native {
        let b = k / step;
        let s_uu = (s.s_uu.get(b)? + s.s_uu.get(b)?.adjoint()) * Complex64::from(0.5);
        let eig = InputEigen::new(&s_uu, 0.0)?;
        let residual = eig.residual(&s.s_xx[b], &s.s_xu[b])?;
        response.push(s.s_xu[b] * eig.inverse());
        weights.push(super::identify::row_weights(&s_uu, &residual, dof));
    }
    Some((response, weights))
}

/// Widens `fit`'s standard deviations of `K` and `tau` (and their ppm and mrad) to at least what
/// the stretches' spread implies.
pub fn widen(fit: &mut super::structural::StructuralFit, st: &Stationarity) {
    for i in 0..3 {
        for j in 0..3 {
            fit.set_k_std(i, j, fit.k_std[i][j].max(st.k_spread_std[i][j]));
        }
    }
    fit.tau_std_s = fit.tau_std_s.max(st.tau_spread_std_s);
}

/// The stationarity of a block's spectra for the last band asked, kept with the spectra: it does
/// not depend on A, Lambda or the order, so a retune reuses it.
pub type StationarityCache = super::band_cache::BandCache<Stationarity>;

/// [`stationarity`], cached in `spectra` per band.
#[must_use]
pub fn cached_stationarity(
    spectra: &BlockSpectra,
    band_hz: [f64; 2],
) -> Option<std::sync::Arc<Stationarity>> {
    spectra
        .stationarity_cache
        .get_or(band_hz, || stationarity(spectra, band_hz))
}

#[cfg(test)]
#[path = "stretches_tests.rs"]
mod tests;
