//! What the tone search could have seen: per frequency and output channel, the amplitude of a
//! constant vibration tone in one output whose evidence against that output's own background
//! just reaches the criterion a tone must pass
//! (BIC's `ln n` for each of its seven parameters plus the look-elsewhere cost of the last
//! round, `diagnose::workflow`). A tone in one output at 1.5 times it is named (80 of 80 at
//! 7-57 Hz in a campaign, 29 Nov; 7 of 8 at 2 Hz; the channels' correlation only adds to its
//! evidence); at the limit about two times in three, at 0.6 times or below never (80 tones). A
//! search that ended without a tone says that nothing above this curve was there. Where the rounds
//! ended on their count (every round named an effect) no tone could have been named, and no
//! limit is given.
//!
//! The evidence of a tone of amplitude `A` on channel `i` alone, against the background's
//! covariance `C` around it ([`super::tone`]): `2 A^2 E_i (C^-1)_ii / ENBW`, `E_i` the
//! channel's basis energy per unit amplitude (the mean of its weighted Gram matrix's diagonal).
//! The limit takes the channel's own background level instead, `1 / C_ii <= (C^-1)_ii`:
//! `A_min = sqrt(chi2_needed ENBW C_ii / (2 E_i))`. The search ranks lines by their plain power
//! over the continuum before it weighs any evidence, and that ranking sees a tone against its
//! own output's level: where the background is shared (above a reference's band limit the
//! motion the angles no longer carry is in every output), a one-output tone's evidence is far
//! above the criterion (274 times at 2.5 times this limit, measured), yet below the limit the
//! ranking does not reach it (not named at 0.4 times, the same run): with `(C^-1)_ii` the limit
//! read 16 times lower there and a tone at 2.5 times it was not named
//! (`tests/diagnose_tone_limit.rs`). So the limit is conservative: a tone above it in one
//! output is named. A tone in several outputs at once, along the direction their background
//! shares, needs more (by design: `super::tone`).
//!
//! The background is the record's own residual after every finding, so the limit rises where
//! the model leaves more unexplained (on a real stand above the reference's band limit, where
//! the angles no longer carry the motion) and a lab sees how much.
//!
//! Below the frequency where the expected disturbance level's running median is whole
//! (`PreparedBlock::full_level_hz`, 16 native Welch bins: about 2 Hz at 500 Hz with segments of
//! 4096) the level follows a line's own power and a tone there may go unnamed at any size (a
//! campaign, 29 Nov: one-output tones at 0.3 Hz not named at 300 times the limit read there,
//! at 0.6-0.9 Hz named 2-7 times in 8 at 4 times); no limit is stated there.
//!
//! Units: amplitudes in the block's output units (rad/s, m/s^2), frequencies in Hz. Evaluated
//! every [`STRIDE`] bins of the bins the search looks at ([`super::tone::searched_peaks`]); a
//! range too narrow for a line gives no points. NaN cannot arise from finite input; a channel
//! without basis energy gives an infinite limit, and the point is left out.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::design::{Design, WINDOW_ENBW};
use super::tone::{
    HALF_WINDOW, channel_covariance, input_lines_hz, projections, searched_peaks, sinusoid_dft,
};
use crate::block::Block;

/// Bins between two evaluations of the limit (the background's window is 120 bins wide, so the
/// curve changes slowly on this scale).
const STRIDE: usize = 8;

/// The tone search's detection limit of one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToneLimit {
    /// The evidence (chi2) a constant tone needs to be named.
    pub chi2_needed: f64,
    /// Frequencies, Hz, ascending.
    pub frequency_hz: Vec<f64>,
    /// Per frequency, per output channel, the amplitude at which a tone's expected evidence
    /// reaches [`Self::chi2_needed`], output units.
    pub amplitude: Vec<[f64; 3]>,
    /// Frequencies, Hz, where the inputs carry a line of their own (a stand programme's sine):
    /// no tone is named there, whatever its size (`super::tone`: a misfit of the model there and
    /// a tone cannot be told apart). Absent when there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub input_lines_hz: Vec<f64>,
}

impl ToneLimit {
    /// The limit at the point nearest `f_hz`, per channel (`None` outside the searched range:
    /// below its first point or above its last).
    #[must_use]
    pub fn at(&self, f_hz: f64) -> Option<[f64; 3]> {
        let (first, last) = (self.frequency_hz.first()?, self.frequency_hz.last()?);
        if !(*first..=*last).contains(&f_hz) {
            return None;
        }
        let nearest = self
            .frequency_hz
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - f_hz).abs().total_cmp(&(b.1 - f_hz).abs()))?;
        self.amplitude.get(nearest.0).copied()
    }

    /// The limit in words for `block`: the median over the searched range and the outputs, the
    /// largest (where the search is least sensitive: its frequency, and how many times the
    /// median), and the top of the range.
    #[must_use]
    pub fn words(&self, block: Block) -> String {
        let mut all: Vec<f64> = self.amplitude.iter().flatten().copied().collect();
        all.sort_by(f64::total_cmp);
        let (Some(first), Some(last), Some(&median)) = (
            self.frequency_hz.first(),
            self.frequency_hz.last(),
            all.get(all.len() / 2),
        ) else {
            return format!("{block} block: no tone searched (too few bins)");
        };
        let (worst_hz, worst) = self
            .frequency_hz
            .iter()
            .zip(&self.amplitude)
            .map(|(f, a)| (*f, a.iter().copied().fold(0.0, f64::max)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((*first, median));
        let unit = block.output_unit();
        let lines = if self.input_lines_hz.is_empty() {
            String::new()
        } else {
            let list: Vec<String> = self.input_lines_hz.iter().map(|f| format!("{f:.2}")).collect();
            format!(
                "; none named at the inputs' own lines ({} Hz: e.g. a stand programme's sines, their harmonics and sums), where a misfit of the \
                 model and a tone cannot be told apart",
                list.join(", ")
            )
        };
        format!(
            "{block} block: the tone search's limit (a constant tone in one output; chi2 {:.1} needed) is \
             {median:.2e} {unit} (the median over {first:.2}-{last:.2} Hz and the outputs), {worst:.2e} {unit} \
             at {worst_hz:.1} Hz ({:.0} times the median); none stated below {first:.2} Hz (the level a line \
             is measured against follows the line there), no tone searched above {last:.1} Hz{lines}",
            self.chi2_needed,
            worst / median
        )
    }
}

/// The limit over one searched range (`design`'s band bins, `residual` the residual there) from
/// `from_hz` up, appended to `out` (points in ascending frequency, none at or below its last).
pub(super) fn detection_limit(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    (chi2_needed, from_hz): (f64, f64),
    out: &mut ToneLimit,
) {
    let Some(peaks) = searched_peaks(design.n_bins()) else {
        return;
    };
    let plain = |i: usize, k: usize| residual[i][k];
    // Above the band the upper range starts below its top (`super::prepared`): a frequency the
    // band's range already has is not given twice.
    let after = out.frequency_hz.last().copied().unwrap_or(f64::NEG_INFINITY);
    for peak in peaks.step_by(STRIDE) {
        let f = design.frequency_hz[peak];
        if f <= after || f < from_hz {
            continue;
        }
        let range = peak - HALF_WINDOW..peak + HALF_WINDOW + 1;
        let (c, s) = sinusoid_dft(design, f, range.clone());
        let background = channel_covariance(design, peak, plain);
        let amplitude = [0, 1, 2].map(|i| {
            let [a, _, d, _, _] = projections(design, residual, (&c, &s), &range, i);
            let information = 2.0 * 0.5 * (a + d) / background[(i, i)] / WINDOW_ENBW;
            (chi2_needed / information).sqrt()
        });
        if amplitude.iter().all(|a| a.is_finite()) {
            out.frequency_hz.push(f);
            out.amplitude.push(amplitude);
        }
    }
    // A line the range below listed (the upper range starts below its top) is not listed again.
    let df = design.sample_rate_hz / design.fft_len as f64;
    let listed = out.input_lines_hz.last().copied();
    let new = |f: f64| f > after && f >= from_hz && listed.is_none_or(|l| f - l > HALF_WINDOW as f64 * df);
    out.input_lines_hz
        .extend(input_lines_hz(design).into_iter().filter(|&f| new(f)));
}

#[cfg(test)]
#[path = "tone_limit_tests.rs"]
mod tests;
