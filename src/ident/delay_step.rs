//! A step in the delay: the stretches ([`super::stretches`]) read one delay up to some time and
//! another after it, and no line through them explains the change. A data logger that loses or
//! repeats samples in one of the two streams (the angles or the block's outputs) makes exactly
//! this: the streams slip against each other by whole samples, and one delay no longer describes
//! the record. A clock drift is a line, not a step; read as one (a drift fitted through a
//! one-sample slip of a real recording came out at 40-80 ppm), its rate is an invention and
//! re-timing the record for it does not mend it. A drift and a step can come together: the step
//! is fitted with a slope shared by both sides, and the drift judged on that slope.
//!
//! The test, on the fitted stretches in time order: every split into a group before and a group
//! after, each of at least one stretch, with at most one stretch between them left out (the
//! stretch that holds the step reads a mix of the two delays) and at least [`MIN_KEPT`] kept.
//! On the kept stretches `tau = a + step [after] + slope (t - t_mean)` is fitted by least squares
//! (the slope only on [`MIN_KEPT_FOR_SLOPE`] stretches or more; on fewer it is left out).
//! A split is a step when
//! - the step is **material**: at least [`MATERIAL_SAMPLES`] of a sample period (a slip is a
//!   whole sample; the stretches' delays of a steady record agree to a small fraction of one);
//! - the sides are **steady**: the step is at least [`STEADY_RATIO`] times the largest residual
//!   plus the stretches' median own deviation;
//! - a **line does not explain it**: the residuals' rms is less than half that about the
//!   least-squares line through the same stretches (a drift's are the other way round).
//!
//! A side of a single stretch (a step near the record's ends) is allowed, but that stretch may
//! hold the step itself: the size is then given with half of it as its deviation, and no cause
//! is named. Of the splits that pass, the one with the smallest residuals is kept (a largest-step rule
//! kept a mixed stretch and left out a clean one). Units: s, from the first sample of the
//! analysed record. Fewer than [`MIN_KEPT`] stretches, or no finite own deviation, give no step.
//!
//! Where no step passes, an **excursion** is looked for: the delay steps and comes back to where
//! it was (a slip and its reverse later; a 600 s simulated run whose gyro slipped for its middle
//! third came out at a delay between the two, 4.89 ms for 4.3 and 6.3, said by nothing). The
//! stretches in time order are cut into before, during and after, each of at least one stretch,
//! with at most one stretch left out at each edge, and `tau = a + step [during]` fitted on the
//! kept ones (no slope: a drift is a line, the excursion's two sides one level); the same three
//! tests, the line through the same stretches included. A during or a side of one stretch leaves
//! the size known to half, as above.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::stretches::StretchFit;
use super::warnings::IdentWarning;

/// Fewest stretches the step model is fitted on (its two levels leave two degrees of freedom).
pub const MIN_KEPT: usize = 4;

/// Fewest stretches the shared slope is fitted on (three degrees of freedom left): on fewer, three
/// parameters all but interpolate the stretches, and a real recording's slow run (five stretches
/// wandering by 0.2 sample about their mean) read as a step of that size.
pub const MIN_KEPT_FOR_SLOPE: usize = 6;

/// The smallest step said, in sample periods: the real recordings' stretches wander by up to a
/// fifth of one about their mean (their own deviations a fiftieth), a slip is a whole one.
pub const MATERIAL_SAMPLES: f64 = 0.25;

/// How many times the residuals' largest (with the stretches' deviation) the step must be.
pub const STEADY_RATIO: f64 = 6.0;

/// A step in the stretches' delays.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayStep {
    /// The delay just before the step (the fitted level there), s.
    pub before_s: f64,
    /// The delay just after it, s.
    pub after_s: f64,
    /// Where the step lies: between the middles of the last stretch that reads the delay before
    /// and the first that reads the delay after, s from the first sample analysed.
    pub between_s: [f64; 2],
    /// The step in sample periods (`(after - before) * fs`).
    pub samples: f64,
    /// Its standard deviation, sample periods (from the residuals, floored by the stretches' own
    /// deviations).
    pub samples_std: f64,
    /// The slope shared by both sides and its standard deviation, s per s: a clock drift beside
    /// the step (`None`: too few stretches to fit one, [`MIN_KEPT_FOR_SLOPE`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trend: Option<[f64; 2]>,
    /// Where the delay comes back to `before_s` when it does: a slip and its reverse later (a
    /// stream that loses a sample and later repeats one, or each stream losing one), s from the
    /// first sample analysed. `None`: it stays at `after_s` to the record's end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back_between_s: Option<[f64; 2]>,
}

/// The step's standard deviation (sample periods) below which its size tells a slip of whole
/// samples from a re-timing.
pub const DEFINITE_STD: f64 = 0.1;

/// Whether the size is known well enough ([`DEFINITE_STD`]) to tell a slip from a re-timing.
#[must_use]
pub fn definite(samples_std: f64) -> bool {
    samples_std < DEFINITE_STD
}

/// Whether `samples` is a whole number of samples (not zero), known well enough
/// ([`definite`]), within a tenth or 3 of its standard deviations where those are wider.
#[must_use]
pub fn whole_samples(samples: f64, samples_std: f64) -> bool {
    let n = samples.round();
    definite(samples_std) && n != 0.0 && (samples - n).abs() <= (3.0 * samples_std).max(0.1)
}

impl DelayStep {
    /// Whether the step is a whole number of samples: a slip ([`whole_samples`]).
    #[must_use]
    pub fn whole_samples(&self) -> bool {
        whole_samples(self.samples, self.samples_std)
    }

    /// The identification's warning of it.
    #[must_use]
    pub fn warning(&self) -> IdentWarning {
        IdentWarning::DelayStep {
            before_s: self.before_s,
            after_s: self.after_s,
            between_s: self.between_s,
            samples: self.samples,
            samples_std: self.samples_std,
            drift_fitted: self.trend.is_some(),
            back_between_s: self.back_between_s,
        }
    }

    /// The diagnosis's words for `block`: the warning, and what it did to the search.
    #[must_use]
    pub fn diagnosis_words(&self, block: &str) -> String {
        format!(
            "{block} block: {}; no clock drift was searched through it unless the stretches show \
             one beside it, and the findings are of both sides mixed",
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

/// Least squares of `y` on the columns of `x`: the parameters, the residuals and `(X^T X)^-1`.
/// `None` when singular.
fn least_squares(x: &DMatrix<f64>, y: &[f64]) -> Option<(DVector<f64>, Vec<f64>, DMatrix<f64>)> {
    let y = DVector::from_column_slice(y);
    let inv = (x.transpose() * x).try_inverse()?;
    let p = &inv * x.transpose() * &y;
    let residuals = (y - x * &p).iter().copied().collect();
    Some((p, residuals, inv))
}

fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
    }
}

/// The step in `stretches`' delays whose model fits best (module docs), or `None`.
#[must_use]
pub fn delay_step(stretches: &[StretchFit], sample_rate_hz: f64) -> Option<DelayStep> {
    let m = stretches.len();
    if m < MIN_KEPT || sample_rate_hz.is_nan() || sample_rate_hz <= 0.0 {
        return None;
    }
    let own: Vec<f64> = stretches
        .iter()
        .map(|s| s.tau_std_s)
        .filter(|v| v.is_finite())
        .collect();
    if own.is_empty() {
        return None;
    }
    let own = median(&mut own.clone());
    let t: Vec<f64> = stretches
        .iter()
        .map(|s| 0.5 * (s.span_s[0] + s.span_s[1]))
        .collect();
    let mut best: Option<(f64, DelayStep)> = None;
    for gap in 0..=1 {
        for split in 1..m.saturating_sub(gap) {
            let kept: Vec<usize> = (0..m).filter(|&i| i < split || i >= split + gap).collect();
            if kept.len() < MIN_KEPT {
                continue;
            }
            let yk: Vec<f64> = kept.iter().map(|&i| stretches[i].tau_s).collect();
            let t_mean = kept.iter().map(|&i| t[i]).sum::<f64>() / kept.len() as f64;
            let slope = kept.len() >= MIN_KEPT_FOR_SLOPE;
            let columns = if slope { 3 } else { 2 };
            let x = DMatrix::from_fn(kept.len(), columns, |r, c| match c {
                0 => 1.0,
                1 => f64::from(u8::from(kept[r] >= split)),
                _ => t[kept[r]] - t_mean,
            });
            let Some((p, residuals, inv)) = least_squares(&x, &yk) else {
                continue;
            };
            let trend = if slope { p[2] } else { 0.0 };
            let step = p[1];
            let about_step = rms(&residuals);
            let tk: Vec<f64> = kept.iter().map(|&i| t[i]).collect();
            // A side of one stretch has no residual of its own: its own deviation joins the bar,
            // as an excursion's of one does. A real recording cut to 30 s had its first stretch
            // (the stand at rest for most of it) at 5.26 +- 0.65 ms beside four at 4.15-4.20 ms
            // +- 0.03, and that was said as a slip of -0.31 samples.
            let mut own_bar = own;
            for (one, i) in [(split == 1, 0), (split + gap == m - 1, m - 1)] {
                // A NaN deviation is taken (and fails the tests).
                let sd = stretches[i].tau_std_s;
                if one && (sd > own_bar || sd.is_nan()) {
                    own_bar = sd;
                }
            }
            if !passes(step, &residuals, own_bar, about_line(&tk, &yk), sample_rate_hz) {
                continue;
            }
            // The residuals' variance (one degree of freedom or more), floored by the stretches'.
            let dof = (kept.len() - columns) as f64;
            let var = (residuals.iter().map(|r| r * r).sum::<f64>() / dof).max(own * own);
            // A side of one stretch may be that stretch mixed (the step inside it, near its far
            // end): its level is no measurement of the side, and the size is known to half.
            let one_sided = split == 1 || split + gap == m - 1;
            let samples_std = (var * inv[(1, 1)]).sqrt() * sample_rate_hz;
            let samples_std = if one_sided {
                samples_std.max(0.5 * step.abs() * sample_rate_hz)
            } else {
                samples_std
            };
            let found = DelayStep {
                before_s: p[0] + trend * (t[split - 1] - t_mean),
                after_s: p[0] + trend * (t[split - 1] - t_mean) + step,
                between_s: [t[split - 1], t[split + gap]],
                samples: step * sample_rate_hz,
                samples_std,
                trend: slope.then(|| [trend, (var * inv[(2, 2)]).sqrt()]),
                back_between_s: None,
            };
            if best.as_ref().is_none_or(|(r, _)| about_step < *r) {
                best = Some((about_step, found));
            }
        }
    }
    best.map(|(_, s)| s)
        .or_else(|| super::delay_excursion::excursion(stretches, &t, own, sample_rate_hz))
}

/// The three tests of the module docs on a fitted step: material, steady, not a line.
fn passes(step: f64, residuals: &[f64], own: f64, about_line: f64, sample_rate_hz: f64) -> bool {
    let largest = residuals.iter().fold(0.0, |a: f64, r| a.max(r.abs()));
    step.abs() * sample_rate_hz >= MATERIAL_SAMPLES
        && step.abs() >= STEADY_RATIO * (largest + own)
        && rms(residuals) < 0.5 * about_line
}

/// The rms of `y` about the least-squares line through `(t, y)`.
fn about_line(t: &[f64], y: &[f64]) -> f64 {
    let t_mean = t.iter().sum::<f64>() / t.len() as f64;
    let line = DMatrix::from_fn(t.len(), 2, |r, c| if c == 0 { 1.0 } else { t[r] - t_mean });
    least_squares(&line, y).map_or(0.0, |(_, r, _)| rms(&r))
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
        assert!(s.whole_samples() && s.back_between_s.is_none(), "{s:?}");
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

    /// BROAD 07 cut to its first 30 s: the first stretch, mostly the stand at rest, at 5.257 +-
    /// 0.647 ms beside four at 4.15-4.20 +- 0.03 ms. No slip: the first stretch's own deviation
    /// bars a step of 1.1 ms (it was said as -0.31 samples). The same first stretch held to the
    /// others' deviation is a step (the bar is its deviation, not its place).
    #[test]
    fn a_side_of_one_stretch_is_held_to_its_own_deviation() {
        let taus = [5.257, 4.149, 4.198, 4.154, 4.162];
        let mut cut = fits(&taus, 0.03);
        cut[0].tau_std_s = 0.647e-3;
        assert_eq!(delay_step(&cut, 285.714), None);
        let s = delay_step(&fits(&taus, 0.03), 285.714)
            .expect("a step with the first stretch as sure as the rest");
        assert!((s.samples + 0.31).abs() < 0.02, "{s:?}");
        // At the other end too, and a NaN deviation there fails.
        let mut reversed: Vec<StretchFit> = fits(&taus, 0.03);
        reversed.reverse();
        for (i, s) in reversed.iter_mut().enumerate() {
            s.span_s = [21.5 * i as f64, 21.5 * i as f64 + 25.0];
        }
        assert!(delay_step(&reversed, 285.714).is_some());
        reversed[4].tau_std_s = 0.647e-3;
        assert_eq!(delay_step(&reversed, 285.714), None);
        reversed[4].tau_std_s = f64::NAN;
        assert_eq!(delay_step(&reversed, 285.714), None);
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

    /// A step below a tenth of a sample is not said; a half-sample step is, not as whole
    /// samples; a step the stretches' own deviations swamp is not; three stretches are too few.
    #[test]
    fn the_step_must_be_material_steady_and_seen_on_both_sides() {
        let step = |d: f64| [4.0, 4.0, 4.0 + d, 4.0 + d, 4.0 + d];
        assert_eq!(delay_step(&fits(&step(0.3), 0.01), 285.714), None);
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
        // No finite deviation: nothing said.
        assert_eq!(delay_step(&fits(&step(3.5), f64::INFINITY), 285.714), None);
    }

    /// A slip in the last stretch but one, the last mixed: still a step, where it is.
    #[test]
    fn a_step_near_the_end_is_found() {
        let s = delay_step(&fits(&[4.15, 4.18, 4.16, 6.57, 7.65], 0.011), 285.714).expect("a step");
        assert!((s.samples - 1.0).abs() < 0.05, "{s:?}");
        // One stretch after it: the size is not definite, no cause named.
        assert!(!s.whole_samples() && s.samples_std >= 0.45, "{s:?}");
        assert!(
            (s.between_s[0] - 55.5).abs() < 1e-9 && (s.between_s[1] - 98.5).abs() < 1e-9,
            "{s:?}"
        );
        let s = delay_step(&fits(&[4.15, 4.18, 4.16, 4.17, 7.65], 0.011), 285.714).expect("a step");
        assert!((s.samples - 1.0).abs() < 0.05, "{s:?}");
    }

    /// A slip that comes back: found with both places, the level before and after one, the
    /// mixed stretches at the edges left out; in the words, the return and the reverse.
    #[test]
    fn a_slip_and_its_reverse_are_an_excursion() {
        let clean = [4.15, 4.18, 4.16, 7.65, 7.67, 7.64, 7.66, 4.17, 4.15, 4.16];
        let mixed = [4.15, 4.18, 5.90, 7.65, 7.67, 7.64, 5.50, 4.17, 4.15, 4.16];
        for (taus, between, back) in [
            (clean, [55.5, 77.0], [141.5, 163.0]),
            (mixed, [34.0, 77.0], [120.0, 163.0]),
        ] {
            let s = delay_step(&fits(&taus, 0.011), 285.714).expect("an excursion");
            assert!((s.samples - 1.0).abs() < 0.02 && s.whole_samples(), "{s:?}");
            assert!((s.before_s - 4.162e-3).abs() < 1e-5, "{s:?}");
            let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9;
            assert!(close(s.between_s, between), "{s:?}");
            assert!(s.back_between_s.is_some_and(|b| close(b, back)), "{s:?}");
            assert!(s.trend.is_none(), "{s:?}");
            let words = s.diagnosis_words("gyro");
            assert!(
                words.contains("and back to 4.162 ms between")
                    && words.contains("and the reverse where it comes back"),
                "{words}"
            );
        }
        // Down and back up: a step of -1 sample.
        let down = [7.65, 7.66, 7.64, 4.15, 4.18, 4.16, 7.66, 7.65];
        let s = delay_step(&fits(&down, 0.011), 285.714).expect("an excursion");
        assert!(
            (s.samples + 1.0).abs() < 0.02 && s.back_between_s.is_some(),
            "{s:?}"
        );
    }

    /// Not an excursion: a rise and fall (a line each way, not two levels), an excursion the
    /// stretches' own deviations swamp, one below a quarter of a sample, and a second level that
    /// does not come back to the first (two steps).
    #[test]
    fn an_excursion_must_come_back_to_a_steady_level() {
        let v = [4.0, 5.0, 6.0, 7.0, 6.0, 5.0, 4.0];
        assert_eq!(delay_step(&fits(&v, 0.011), 285.714), None);
        let out_and_back = |d: f64| [4.0, 4.0, 4.0, 4.0 + d, 4.0 + d, 4.0 + d, 4.0, 4.0, 4.0];
        assert_eq!(delay_step(&fits(&out_and_back(3.5), 0.7), 285.714), None);
        assert_eq!(delay_step(&fits(&out_and_back(0.7), 0.01), 285.714), None);
        assert!(delay_step(&fits(&out_and_back(3.5), 0.01), 285.714).is_some());
        // A smooth rise and fall (a clock whose rate reverses) at 5-8 stretches, one to four
        // samples high: no excursion (its two ends passed for the level).
        for m in 5..=8 {
            for samples in [0.5, 1.0, 2.0, 4.0] {
                let taus: Vec<f64> = (0..m)
                    .map(|i| {
                        let x = 2.0 * f64::from(i) / f64::from(m - 1) - 1.0;
                        4.0 + samples * 3.5 * (1.0 - x * x)
                    })
                    .collect();
                let s = delay_step(&fits(&taus, 0.011), 285.714);
                assert!(
                    s.is_none_or(|s| s.back_between_s.is_none()),
                    "{m} stretches, {samples}: {s:?}"
                );
            }
        }
        // One stretch half a sample off whose own deviation is wide: not an excursion.
        let mut one = fits(
            &[4.15, 4.17, 4.16, 4.15, 4.16, 5.9, 4.17, 4.15, 4.16, 4.16],
            0.011,
        );
        one[5].tau_std_s = 0.4e-3;
        assert_eq!(delay_step(&one, 285.714), None);
        let stairs = [4.0, 4.0, 4.0, 7.5, 7.5, 7.5, 11.0, 11.0, 11.0];
        assert!(
            delay_step(&fits(&stairs, 0.01), 285.714).is_none_or(|s| s.back_between_s.is_none()),
            "two steps up are no excursion"
        );
    }

    /// A drift of 2 ms over the run and a slip at its middle: the step, and the slope beside it
    /// at the drift's rate.
    #[test]
    fn a_step_beside_a_drift_keeps_the_drift() {
        let rate = 0.4 / 21.5; // ms per s
        let taus: Vec<f64> = (0..6)
            .map(|i| 4.0 + 0.4 * f64::from(i) + if i >= 3 { 3.5 } else { 0.0 })
            .collect();
        let s = delay_step(&fits(&taus, 0.011), 285.714).expect("a step");
        assert!((s.samples - 1.0).abs() < 0.01, "{s:?}");
        let [trend, trend_std] = s.trend.expect("six stretches carry a slope");
        assert!((trend * 1e3 / rate - 1.0).abs() < 0.01, "{s:?}");
        assert!(trend.abs() > 10.0 * trend_std, "{s:?}");
    }
}
