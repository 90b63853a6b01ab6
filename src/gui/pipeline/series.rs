//! A uniformly sampled signal with a min/max pyramid, so a plot of any time range can be drawn
//! from at most a few thousand points whatever the run's length.
//!
//! The pyramid is built once in the worker: level 0 holds the minimum and maximum of every bucket
//! of [`FIRST_BUCKET`] samples, each next level merges pairs of buckets. Memory: about half the
//! signal's own. A query picks the finest level that still fits the requested point budget.

use std::sync::Arc;

use egui_plot::PlotPoint;

use crate::faults::Channel;
use crate::run::Run;

/// Samples per bucket on the finest pyramid level.
pub const FIRST_BUCKET: usize = 8;

/// One pyramid level: min and max of consecutive buckets of `bucket` samples.
#[derive(Debug)]
struct Level {
    bucket: usize,
    min: Vec<f64>,
    max: Vec<f64>,
}

/// Where a series' samples live: its own, or a column of the loaded run (shared with the core's
/// pipeline, not copied).
#[derive(Debug)]
pub enum Samples {
    /// Computed for display (e.g. rates by central differences).
    Owned(Vec<f64>),
    /// A measured column of the run.
    Run(Arc<Run>, Channel),
}

impl Samples {
    /// The samples.
    #[must_use]
    pub fn as_slice(&self) -> &[f64] {
        match self {
            Samples::Owned(v) => v,
            Samples::Run(run, channel) => channel.values(run).unwrap_or_default(),
        }
    }
}

/// A named signal sampled at `t0 + k dt`.
#[derive(Debug)]
pub struct Series {
    /// Channel name as the contract spells it (`roll`, `wx`, `gx`, ...).
    pub name: String,
    /// Time of the first sample, s.
    pub t0: f64,
    /// Sampling step, s.
    pub dt: f64,
    samples: Samples,
    levels: Vec<Level>,
}

impl Series {
    /// Builds the series and its pyramid (O(n)).
    #[must_use]
    pub fn new(name: impl Into<String>, t0: f64, dt: f64, values: Vec<f64>) -> Self {
        Self::of(name, t0, dt, Samples::Owned(values))
    }

    /// A measured column of `run`, shared (the pyramid is the only new memory).
    #[must_use]
    pub fn of_run(run: &Arc<Run>, channel: Channel) -> Self {
        let t0 = run.time_s.first().copied().unwrap_or(0.0);
        Self::of(channel.name(), t0, run.dt_s(), Samples::Run(run.clone(), channel))
    }

    /// The samples.
    #[must_use]
    pub fn values(&self) -> &[f64] {
        self.samples.as_slice()
    }

    fn of(name: impl Into<String>, t0: f64, dt: f64, samples: Samples) -> Self {
        let values = samples.as_slice();
        let mut levels: Vec<Level> = Vec::new();
        if values.len() > FIRST_BUCKET {
            let (min, max) = values
                .chunks(FIRST_BUCKET)
                .map(|c| {
                    c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                        (lo.min(v), hi.max(v))
                    })
                })
                .unzip();
            levels.push(Level {
                bucket: FIRST_BUCKET,
                min,
                max,
            });
        }
        while let Some(last) = levels.last()
            && last.min.len() > 1
        {
            let merge = |v: &[f64], f: fn(f64, f64) -> f64| -> Vec<f64> {
                v.chunks(2)
                    .map(|c| c.iter().copied().reduce(f).unwrap_or(f64::NAN))
                    .collect()
            };
            let next = Level {
                bucket: last.bucket * 2,
                min: merge(&last.min, f64::min),
                max: merge(&last.max, f64::max),
            };
            levels.push(next);
        }
        Self {
            name: name.into(),
            t0,
            dt,
            samples,
            levels,
        }
    }

    /// Time of the last sample, s.
    #[must_use]
    pub fn t_end(&self) -> f64 {
        self.t0 + self.values().len().saturating_sub(1) as f64 * self.dt
    }

    /// The sample nearest to time `t`, if `t` is inside the series.
    #[must_use]
    pub fn value_at(&self, t: f64) -> Option<f64> {
        let k = ((t - self.t0) / self.dt).round();
        if k < 0.0 {
            return None;
        }
        self.values().get(k as usize).copied()
    }

    /// Writes into `out` (cleared first) the points to draw `[t_min, t_max]` with about
    /// `max_points` points: the raw samples when they fit, else bucket minima and maxima
    /// (two points per bucket, at the bucket's centre, so the envelope is kept).
    pub fn decimate(&self, t_min: f64, t_max: f64, max_points: usize, out: &mut Vec<PlotPoint>) {
        out.clear();
        let n = self.values().len();
        if n == 0 || !(t_min.is_finite() && t_max.is_finite()) || t_max < t_min {
            return;
        }
        let index = |t: f64| (((t - self.t0) / self.dt).clamp(0.0, n as f64)) as usize;
        let i0 = index(t_min).saturating_sub(1);
        let i1 = (index(t_max) + 2).min(n);
        if i1 <= i0 {
            return;
        }
        let count = i1 - i0;
        let max_points = max_points.max(16);
        let wanted_bucket = count.div_ceil(max_points / 2);
        let level = self
            .levels
            .iter()
            .find(|l| l.bucket >= wanted_bucket)
            .or(self.levels.last());
        match level {
            Some(level) if count > max_points => {
                let b = level.bucket;
                let last = ((i1 - 1) / b).min(level.min.len() - 1);
                out.reserve(2 * (last + 1 - i0 / b));
                for k in i0 / b..=last {
                    let t = self.t0 + (k * b) as f64 * self.dt + 0.5 * (b - 1) as f64 * self.dt;
                    out.push(PlotPoint::new(t, level.min[k]));
                    out.push(PlotPoint::new(t, level.max[k]));
                }
            }
            _ => {
                out.extend(
                    self.values()[i0..i1]
                        .iter()
                        .enumerate()
                        .map(|(k, &v)| PlotPoint::new(self.t0 + (i0 + k) as f64 * self.dt, v)),
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Series;

    #[test]
    fn raw_when_it_fits_and_envelope_otherwise() {
        let values: Vec<f64> = (0..100_000).map(|k| (f64::from(k) * 0.01).sin()).collect();
        let s = Series::new("x", 10.0, 0.002, values);
        let mut out = Vec::new();
        s.decimate(10.0, 10.1, 2000, &mut out);
        assert!(out.len() <= 53 && out.len() >= 50, "{}", out.len());
        assert!(
            (out[0].x - 10.0).abs() < 1e-12,
            "one sample before the window at most"
        );
        s.decimate(f64::NEG_INFINITY, 1e9, 2000, &mut out);
        assert!(out.is_empty(), "infinite range is refused");
        s.decimate(0.0, 1e9, 2000, &mut out);
        assert!(out.len() <= 2000 && out.len() >= 500, "{}", out.len());
        let hi = out.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        let lo = out.iter().map(|p| p.y).fold(f64::MAX, f64::min);
        assert!(hi > 0.9999 && lo < -0.9999, "the envelope keeps the extremes");
    }

    #[test]
    fn any_window_of_a_long_run_costs_at_most_the_budget() {
        // The 1.8-million-sample benchmark size: the cost of a query is the points it returns.
        let n: u32 = 1_800_000;
        let values: Vec<f64> = (0..n).map(|k| f64::from((k % 1000) * 7919 % 1000)).collect();
        let s = Series::new("long", 0.0, 1.0 / 500.0, values);
        let mut out = Vec::new();
        for (lo, hi) in [(0.0, 3600.0), (100.0, 2000.0), (500.0, 530.0), (1000.0, 1000.5)] {
            s.decimate(lo, hi, 3200, &mut out);
            assert!(out.len() <= 3200 + 4, "{lo}..{hi}: {} points", out.len());
            // Within one bucket (at most twice the budget's bucket) of each edge.
            let tolerance = (hi - lo) / 1600.0 + 0.01;
            let (first, last) = (out.first().expect("points"), out.last().expect("points"));
            assert!(first.x <= lo + tolerance, "{lo}..{hi} starts at {}", first.x);
            assert!(
                last.x >= hi.min(3599.998) - tolerance,
                "{lo}..{hi} ends at {}",
                last.x
            );
        }
    }

    #[test]
    fn short_and_empty_series() {
        let mut out = Vec::new();
        Series::new("e", 0.0, 1.0, Vec::new()).decimate(0.0, 1.0, 100, &mut out);
        assert!(out.is_empty());
        let s = Series::new("s", 0.0, 1.0, vec![1.0, 2.0, 3.0]);
        s.decimate(-5.0, 5.0, 100, &mut out);
        assert_eq!(out.len(), 3);
        assert_eq!(s.value_at(1.2), Some(2.0));
        assert_eq!(s.value_at(-3.0), None);
    }
}
