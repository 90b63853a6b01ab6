//! A step in the delay: the stretches ([`super::stretches`]) read one delay up to some time and
//! another after it, each group steady, and no line through them explains the change. A data
//! logger that loses or repeats samples in one of the two streams (the angles or the block's
//! outputs) makes exactly this: the streams slip against each other by whole samples, and one
//! delay no longer describes the record. A clock drift is a line, not a step; read as one (a
//! drift fitted through a one-sample slip of a real recording came out at 40-80 ppm), its rate
//! is an invention and re-timing the record for it does not mend it.
//!
//! The test, on the fitted stretches in time order: every split into a group before and a group
//! after, each of at least [`MIN_GROUP`] stretches, with at most one stretch between them left
//! out (the stretch that holds the step reads a mix of the two delays). A split is a step when
//! - the step is **material**: at least [`MATERIAL_SAMPLES`] of a sample period (a slip is a
//!   whole sample; the stretches' delays of a steady record agree to a small fraction of one);
//! - the groups are **steady**: each stretch lies within `1/`[`STEADY_RATIO`] of the step of its
//!   group's median, once the stretches' own deviations are added;
//! - a **line does not explain it**: the stretches' residuals about the step are less than half
//!   their residuals about the least-squares line (a drift's are the other way round).
//!
//! The largest such step is kept. Units: s, from the first sample of the analysed record.
//! Fewer than `2 MIN_GROUP` stretches give no step; non-finite delays are never read (a stretch
//! without a delay is not fitted).

use serde::{Deserialize, Serialize};

use super::stretches::StretchFit;
use super::warnings::IdentWarning;

/// Fewest stretches on each side of a step.
pub const MIN_GROUP: usize = 2;

/// The smallest step said, in sample periods.
pub const MATERIAL_SAMPLES: f64 = 0.25;

/// How many times the groups' own scatter (with the stretches' deviations) the step must be.
pub const STEADY_RATIO: f64 = 6.0;

/// A step in the stretches' delays.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayStep {
    /// The delay before the step (the median of the stretches before), s.
    pub before_s: f64,
    /// The delay after it, s.
    pub after_s: f64,
    /// Where the step lies: between the middles of the last stretch that reads the delay before
    /// and the first that reads the delay after, s from the first sample. (A steady stretch
    /// may hold a little of the other side: a simulated slip 3.6 s before a stretch's end, the
    /// stretch still read the delay before.)
    pub between_s: [f64; 2],
    /// The step in sample periods (`(after - before) * fs`).
    pub samples: f64,
}

impl DelayStep {
    /// Whether the step is a whole number of samples (within a tenth of one): a slip.
    #[must_use]
    pub fn whole_samples(&self) -> bool {
        (self.samples - self.samples.round()).abs() <= 0.1 && self.samples.round() != 0.0
    }

    /// The identification's warning of it.
    #[must_use]
    pub fn warning(&self) -> IdentWarning {
        IdentWarning::DelayStep {
            before_s: self.before_s,
            after_s: self.after_s,
            between_s: self.between_s,
            samples: self.samples,
        }
    }

    /// The diagnosis's words for `block`: the warning, and what it did to the search.
    #[must_use]
    pub fn diagnosis_words(&self, block: &str) -> String {
        format!(
            "{block} block: {}; no clock drift was searched (a drift's line through a step is an \
             invented rate), and the findings are of both sides mixed",
            self.warning()
        )
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Residuals of `y` about its least-squares line against `t`.
fn line_residuals(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len() as f64;
    let (tm, ym) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let stt: f64 = t.iter().map(|v| (v - tm).powi(2)).sum();
    let slope = if stt > 0.0 {
        t.iter().zip(y).map(|(a, b)| (a - tm) * (b - ym)).sum::<f64>() / stt
    } else {
        0.0
    };
    t.iter().zip(y).map(|(a, b)| b - ym - slope * (a - tm)).collect()
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    if n == 0 { 0.0 } else { (s / n as f64).sqrt() }
}

/// The largest step in `stretches`' delays (module docs), or `None`.
#[must_use]
pub fn delay_step(stretches: &[StretchFit], sample_rate_hz: f64) -> Option<DelayStep> {
    let m = stretches.len();
    if m < 2 * MIN_GROUP || sample_rate_hz.is_nan() || sample_rate_hz <= 0.0 {
        return None;
    }
    let t: Vec<f64> = stretches
        .iter()
        .map(|s| 0.5 * (s.span_s[0] + s.span_s[1]))
        .collect();
    let y: Vec<f64> = stretches.iter().map(|s| s.tau_s).collect();
    let line = line_residuals(&t, &y);
    let own = median(&mut stretches.iter().map(|s| s.tau_std_s).collect::<Vec<_>>());
    let own = if own.is_finite() { own } else { 0.0 };
    let mut best: Option<DelayStep> = None;
    for gap in 0..=1 {
        for split in MIN_GROUP..=m.saturating_sub(MIN_GROUP + gap) {
            let (before, after) = (&y[..split], &y[split + gap..]);
            let a = median(&mut before.to_vec());
            let b = median(&mut after.to_vec());
            let step = b - a;
            let scatter = before
                .iter()
                .map(|v| (v - a).abs())
                .chain(after.iter().map(|v| (v - b).abs()))
                .fold(0.0, f64::max);
            let kept = (0..m).filter(|&i| i < split || i >= split + gap);
            let about_step = rms(kept.clone().map(|i| y[i] - if i < split { a } else { b }));
            let about_line = rms(kept.map(|i| line[i]));
            let material = step.abs() * sample_rate_hz >= MATERIAL_SAMPLES;
            let steady = step.abs() >= STEADY_RATIO * (scatter + own);
            if material && steady && about_step < 0.5 * about_line {
                let found = DelayStep {
                    before_s: a,
                    after_s: b,
                    between_s: [t[split - 1], t[split + gap]],
                    samples: step * sample_rate_hz,
                };
                if best.is_none_or(|k| found.samples.abs() > k.samples.abs()) {
                    best = Some(found);
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fits(taus_ms: &[f64], std_ms: f64) -> Vec<StretchFit> {
        taus_ms
            .iter()
            .enumerate()
            .map(|(i, &tau)| {
                let a = 21.5 * i as f64;
                StretchFit {
                    span_s: [a, a + 25.0],
                    k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                    tau_s: tau * 1e-3,
                    tau_std_s: std_ms * 1e-3,
                }
            })
            .collect()
    }

    /// The stretches of a real recording (BROAD 07, 285.7 Hz) whose gyro slips one sample late
    /// at its middle: 4.15, 4.18, a mixed 4.70, then 7.70, 7.65 ms.
    const SLIP: [f64; 5] = [4.1485, 4.1839, 4.6978, 7.6951, 7.6452];

    #[test]
    fn a_one_sample_slip_is_a_step_of_one_sample_where_it_happened() {
        let s = delay_step(&fits(&SLIP, 0.011), 285.714).expect("a step");
        assert!((s.samples - 1.0).abs() < 0.05, "{s:?}");
        assert!(s.whole_samples());
        let words = s.diagnosis_words("gyro");
        assert!(
            words.contains("from 4.166 ms to 7.670 ms")
                && words.contains("1 whole sample: samples lost from the angles or repeated in the outputs")
                && words.contains("no clock drift was searched"),
            "{words}"
        );
        assert!(
            (s.before_s - 4.166e-3).abs() < 3e-5 && (s.after_s - 7.670e-3).abs() < 3e-5,
            "{s:?}"
        );
        // The mixed stretch [43, 68] is left out: the step lies between the second's middle
        // (34) and the fourth's (77).
        assert!(
            (s.between_s[0] - 34.0).abs() < 1e-9 && (s.between_s[1] - 77.0).abs() < 1e-9,
            "{s:?}"
        );
    }

    /// The same record unslipped (its stretches scatter by 0.04 ms, four of their own
    /// deviations): no step; nor in a drift of 6 ms over the run, a line.
    #[test]
    fn a_steady_record_and_a_drift_have_no_step() {
        let steady = [4.1487, 4.1836, 4.1558, 4.1881, 4.1702];
        assert_eq!(delay_step(&fits(&steady, 0.011), 285.714), None);
        let drift: Vec<f64> = (0..5).map(|i| 4.0 + 1.5 * f64::from(i)).collect();
        assert_eq!(delay_step(&fits(&drift, 0.011), 285.714), None);
        // Four stretches of a drift: the two groups of two are not steady.
        assert_eq!(delay_step(&fits(&drift[..4], 0.011), 285.714), None);
    }

    /// A step below a quarter sample is not said; a half-sample step is, not as whole samples;
    /// a step the stretches' own deviations swamp is not; three stretches are too few.
    #[test]
    fn the_step_must_be_material_steady_and_seen_on_both_sides() {
        let step = |d: f64| [4.0, 4.0, 4.0 + d, 4.0 + d, 4.0 + d];
        assert_eq!(delay_step(&fits(&step(0.8), 0.01), 285.714), None);
        let half = delay_step(&fits(&step(1.75), 0.01), 285.714).expect("a half-sample step");
        assert!(
            (half.samples - 0.5).abs() < 1e-6 && !half.whole_samples(),
            "{half:?}"
        );
        assert_eq!(delay_step(&fits(&step(3.5), 0.7), 285.714), None);
        assert_eq!(delay_step(&fits(&[4.0, 4.0, 7.5], 0.01), 285.714), None);
        // Back down: a step of -1 sample.
        let down = delay_step(&fits(&[7.5, 7.5, 7.5, 4.0, 4.0, 4.0], 0.01), 285.714).expect("a step");
        assert!(
            (down.samples + 1.0).abs() < 0.01 && down.whole_samples(),
            "{down:?}"
        );
    }
}
