//! The usable band: where a block's input estimate can be trusted, found from the data.
//!
//! The identifier regresses the block's outputs on inputs computed from the measured angles. Where
//! the angles carry no information about the motion (a reference's band limit, coloured angle
//! noise above the motion's spectrum), the input estimate is mostly noise: the regression's gain
//! is attenuated (errors in variables) and its phase is meaningless, and a fit over those bins
//! returns a wrong delay and orders that chase the error. Whether the cause is input noise or
//! output noise, it shows in the **multiple coherence** of each output with the three inputs,
//! `gamma_i^2 = (S_xu S_uu^-1 S_ux)_ii / S_xx,ii`: input noise of relative power `e` bounds it by
//! `1 / (1 + e)`, so a bin with `gamma^2 >= C` has at most `(1 - C) / C` of its input power from
//! noise, and the attenuation of its gain is at most `1 - C`. The bins where the output noise
//! dominates instead carry little weight in the fit (their weight is `gamma^2 / (1 - gamma^2)`),
//! so dropping them costs little precision.
//!
//! Rule ([`usable_band`]): on the Welch estimate's native bins inside the search limits, take the
//! median coherence of the three outputs (input noise on the angles reaches every output; one
//! output with little signal of its own, such as the vertical accelerometer channel, is output
//! noise and must not shrink the band of the other two), smooth it by a running median of [`MEDIAN_BINS`] bins (a
//! line a few bins wide, such as a vibration tone, does not split the band), and keep the longest
//! contiguous run of bins at or above [`MIN_COHERENCE`]. With `band_hz: "auto"` (the default)
//! the search limits are `[0.1 Hz, min(40 Hz, 0.4 fs)]`: the auto band is never wider than the
//! former fixed default. A band the user gives is kept as given, and the stretches inside it below
//! [`MIN_COHERENCE`] are reported ([`untrusted_ranges`]).
//!
//! Units: Hz. Non-finite or non-positive spectra give coherence 0 at that bin. An empty search
//! range, or one with fewer than [`MIN_BAND_BINS`] usable bins, gives `None`.

use std::fmt;

use nalgebra::Matrix3;
use num_complex::Complex64;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::settings::{serialize_values_or_auto, values_or_auto};
use super::spectra::BlockSpectra;

/// Smallest multiple coherence (median of the outputs) of a usable bin: at most 10 % of its
/// power unexplained by the inputs, so at most a 10 % attenuation of that bin's gain if all of it
/// were input noise, and a bin weight at least 9 times that of a bin at coherence 0.5.
pub const MIN_COHERENCE: f64 = 0.9;

/// Width of the running median over native bins.
pub const MEDIAN_BINS: usize = 9;

/// Fewest native bins of a usable band.
pub const MIN_BAND_BINS: usize = 8;

/// The default search limits of the auto band, Hz (the upper one is also capped at `0.4 fs`).
pub const AUTO_LIMITS_HZ: [f64; 2] = [0.1, 40.0];

/// The analysis band setting: found from the data, or given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BandSetting {
    /// The usable band ([`usable_band`]) within [`AUTO_LIMITS_HZ`].
    #[default]
    Auto,
    /// `[low, high]`, Hz, as given.
    Fixed([f64; 2]),
}

impl fmt::Display for BandSetting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BandSetting::Auto => write!(f, "auto"),
            BandSetting::Fixed([lo, hi]) => write!(f, "[{lo}, {hi}] Hz"),
        }
    }
}

impl BandSetting {
    /// The band to search: the user's as given, or the auto band's search limits.
    #[must_use]
    pub fn search_limits(self, sample_rate_hz: f64) -> [f64; 2] {
        match self {
            BandSetting::Fixed(given) => given,
            BandSetting::Auto => auto_limits(sample_rate_hz),
        }
    }
}

/// The search limits of the auto band for a run sampled at `sample_rate_hz`.
#[must_use]
pub fn auto_limits(sample_rate_hz: f64) -> [f64; 2] {
    [AUTO_LIMITS_HZ[0], AUTO_LIMITS_HZ[1].min(0.4 * sample_rate_hz)]
}

/// Indices of the native (un-padded) Welch bins of `spectra` inside `[low, high]`. The structural
/// fit and the model use these: the zero-padded grid (needed for the causal projection)
/// interpolates between them, and its neighbours are not independent, which would overstate the
/// evidence by the padding factor.
#[must_use]
pub fn native_bins(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Vec<usize> {
    let step = spectra.native_step();
    (0..spectra.frequency_hz.len())
        .step_by(step)
        .filter(|&k| spectra.frequency_hz[k] >= band_hz[0] && spectra.frequency_hz[k] <= band_hz[1])
        .collect()
}

/// Multiple coherence of each output with the three inputs at bin `k` (0 where undefined).
#[must_use]
pub fn multiple_coherence(spectra: &BlockSpectra, k: usize) -> [f64; 3] {
    coherence_of(&spectra.s_uu[k], &spectra.s_xu[k], &spectra.s_xx[k])
}

/// Multiple coherence of each output with the three inputs from one bin's spectral matrices
/// (0 where undefined: `S_uu` singular, an output without power).
#[must_use]
pub fn coherence_of(
    s_uu: &Matrix3<Complex64>,
    s_xu: &Matrix3<Complex64>,
    s_xx: &Matrix3<Complex64>,
) -> [f64; 3] {
    let Some((explained, _)) = super::explained::explained(s_uu, s_xu, 0.0) else {
        return [0.0; 3];
    };
    std::array::from_fn(|i| {
        let total = s_xx[(i, i)].re;
        let c = explained[(i, i)].re / total;
        if c.is_finite() && total > 0.0 {
            c.clamp(0.0, 1.0)
        } else {
            0.0
        }
    })
}

/// The median output coherence at each of `bins`, smoothed by a running median.
fn smoothed_coherence(spectra: &BlockSpectra, bins: &[usize]) -> Vec<f64> {
    let raw: Vec<f64> = bins
        .iter()
        .map(|&k| {
            let mut c = multiple_coherence(spectra, k);
            c.sort_by(f64::total_cmp);
            c[1]
        })
        .collect();
    let half = MEDIAN_BINS / 2;
    (0..raw.len())
        .map(|i| {
            let mut w: Vec<f64> = raw[i.saturating_sub(half)..(i + half + 1).min(raw.len())].to_vec();
            w.sort_by(f64::total_cmp);
            w[w.len() / 2]
        })
        .collect()
}

/// The usable band inside `limits_hz` (see the module docs), as `[first, last]` bin frequency.
#[must_use]
pub fn usable_band(spectra: &BlockSpectra, limits_hz: [f64; 2]) -> Option<[f64; 2]> {
    let bins = native_bins(spectra, limits_hz);
    let c = smoothed_coherence(spectra, &bins);
    let (mut best, mut start) = (None::<(usize, usize)>, None);
    for i in 0..=c.len() {
        let good = i < c.len() && c[i] >= MIN_COHERENCE;
        match (good, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if best.is_none_or(|(b0, b1)| i - s > b1 - b0) {
                    best = Some((s, i));
                }
                start = None;
            }
            _ => {}
        }
    }
    let (s, e) = best.filter(|(s, e)| e - s >= MIN_BAND_BINS)?;
    Some([spectra.frequency_hz[bins[s]], spectra.frequency_hz[bins[e - 1]]])
}

/// The best smoothed coherence inside `limits_hz` (for the message when no band is usable).
#[must_use]
pub fn best_coherence(spectra: &BlockSpectra, limits_hz: [f64; 2]) -> f64 {
    let bins = native_bins(spectra, limits_hz);
    smoothed_coherence(spectra, &bins).into_iter().fold(0.0, f64::max)
}

/// The stretches of `band_hz` whose smoothed coherence is below [`MIN_COHERENCE`], `[low, high]`
/// in Hz, ascending.
#[must_use]
pub fn untrusted_ranges(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Vec<[f64; 2]> {
    let bins = native_bins(spectra, band_hz);
    let c = smoothed_coherence(spectra, &bins);
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut open = false;
    for (i, &k) in bins.iter().enumerate() {
        let f = spectra.frequency_hz[k];
        if c[i] < MIN_COHERENCE {
            match out.last_mut() {
                Some(last) if open => last[1] = f,
                _ => out.push([f, f]),
            }
            open = true;
        } else {
            open = false;
        }
    }
    out
}

/// The untrusted range ([`untrusted_ranges`]) that reaches the top bin of `band_hz`: where, up to
/// the band's top, the block's outputs are not coherent with its inputs (the inputs from the
/// angles are their noise there, or the outputs the sensor's). `None` where the top is trusted.
#[must_use]
pub fn untrusted_to_top(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Option<[f64; 2]> {
    let top = spectra.frequency_hz[*native_bins(spectra, band_hz).last()?];
    untrusted_ranges(spectra, band_hz)
        .last()
        .copied()
        .filter(|r| r[1] >= top)
}

/// The last native bin of `band_hz` below `hz`, Hz: where the block's outputs are last coherent
/// with its inputs below [`untrusted_to_top`]'s range, with its start as `hz`. `None` where no bin
/// lies below.
#[must_use]
pub fn last_bin_below(spectra: &BlockSpectra, band_hz: [f64; 2], hz: f64) -> Option<f64> {
    native_bins(spectra, band_hz)
        .into_iter()
        .map(|k| spectra.frequency_hz[k])
        .take_while(|&f| f < hz)
        .last()
}

impl Serialize for BandSetting {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let values = match self {
            BandSetting::Fixed(v) => Some(v),
            BandSetting::Auto => None,
        };
        serialize_values_or_auto(values, s)
    }
}

impl<'de> Deserialize<'de> for BandSetting {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(values_or_auto(d, "band_hz must be [low, high] in Hz")?
            .map_or(BandSetting::Auto, BandSetting::Fixed))
    }
}

#[cfg(test)]
#[path = "band_tests.rs"]
mod tests;
