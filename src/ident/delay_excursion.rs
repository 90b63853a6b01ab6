//! The excursion of [`super::delay_step`]: the delay steps and comes back to its level (a slip
//! and its reverse later). Every cut of the stretches into before, during and after is tried
//! (module docs there), so the search is quadratic in the number of stretches; each cut is
//! judged in constant time from prefix sums of the stretches' delays and times (and running
//! extremes for the largest residual), not by a least-squares fit of its own: a 30-minute run
//! at 1 kHz has over a hundred stretches, and fits per cut took 0.3 s there.
//!
//! The model on the kept stretches is `tau = a + step [during]`: its least-squares levels are the
//! two groups' means, its residuals the deviations from them, and the variance factor of `step`
//! is `1 / n_during + 1 / n_outside`. The line it must beat is the least-squares line through
//! the same stretches. Delays and times are centred on their means before the sums are taken,
//! so the sums of squares do not cancel. Units: s; NaN delays are the caller's to leave out
//! (none reach here: a stretch without a finite delay is not fitted).

use super::delay_step::{DelayStep, MATERIAL_SAMPLES, MIN_KEPT, STEADY_RATIO};

/// Fewest stretches the level outside an excursion rests on.
const MIN_OUTSIDE: usize = 3;
use super::stretches::StretchFit;

/// Sums over a set of stretches: count, `t`, `t^2`, `y`, `t y`, `y^2` (centred values).
#[derive(Clone, Copy, Default)]
struct Sums {
    n: f64,
    t: f64,
    tt: f64,
    y: f64,
    ty: f64,
    yy: f64,
}

impl Sums {
    fn of(t: f64, y: f64) -> Self {
        Self {
            n: 1.0,
            t,
            tt: t * t,
            y,
            ty: t * y,
            yy: y * y,
        }
    }

    fn add(self, o: Self) -> Self {
        Self {
            n: self.n + o.n,
            t: self.t + o.t,
            tt: self.tt + o.tt,
            y: self.y + o.y,
            ty: self.ty + o.ty,
            yy: self.yy + o.yy,
        }
    }

    fn sub(self, o: Self) -> Self {
        Self {
            n: self.n - o.n,
            t: self.t - o.t,
            tt: self.tt - o.tt,
            y: self.y - o.y,
            ty: self.ty - o.ty,
            yy: self.yy - o.yy,
        }
    }

    fn mean(&self) -> f64 {
        self.y / self.n
    }

    /// Sum of squares about the set's mean.
    fn about_mean(&self) -> f64 {
        (self.yy - self.y * self.y / self.n).max(0.0)
    }

    /// Sum of squares about the set's least-squares line in `t`.
    fn about_line(&self) -> f64 {
        let stt = self.tt - self.t * self.t / self.n;
        let sty = self.ty - self.t * self.y / self.n;
        let line = if stt > 0.0 { sty * sty / stt } else { 0.0 };
        (self.about_mean() - line).max(0.0)
    }
}

/// The excursion whose model fits best, or `None`. `t` are the stretches' middles, `own` their
/// median own deviation, s.
pub(super) fn excursion(
    stretches: &[StretchFit],
    t: &[f64],
    own: f64,
    sample_rate_hz: f64,
) -> Option<DelayStep> {
    let m = stretches.len();
    if m < MIN_KEPT {
        return None;
    }
    let y_mean = stretches.iter().map(|s| s.tau_s).sum::<f64>() / m as f64;
    let t_mean = t.iter().sum::<f64>() / m as f64;
    let y: Vec<f64> = stretches.iter().map(|s| s.tau_s - y_mean).collect();
    // prefix[i]: the sums over stretches 0..i.
    let mut prefix = vec![Sums::default(); m + 1];
    for i in 0..m {
        prefix[i + 1] = prefix[i].add(Sums::of(t[i] - t_mean, y[i]));
    }
    let over = |from: usize, to: usize| prefix[to].sub(prefix[from]);
    // Extremes of the delays before `i` and from `i` on.
    let mut head = vec![(f64::INFINITY, f64::NEG_INFINITY); m + 1];
    let mut tail = vec![(f64::INFINITY, f64::NEG_INFINITY); m + 1];
    for i in 0..m {
        head[i + 1] = (head[i].0.min(y[i]), head[i].1.max(y[i]));
        let j = m - 1 - i;
        tail[j] = (tail[j + 1].0.min(y[j]), tail[j + 1].1.max(y[j]));
    }
    let reach = |(lo, hi): (f64, f64), level: f64| {
        if lo > hi {
            0.0
        } else {
            (hi - level).max(level - lo)
        }
    };
    let mut best: Option<(f64, DelayStep)> = None;
    for (out_gap, back_gap) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        // Before: `..out`; during: `out + out_gap..back`; after: `back + back_gap..`.
        for out in 1..m {
            let first = out + out_gap;
            let mut during_range = (f64::INFINITY, f64::NEG_INFINITY);
            for back in first + 1..m.saturating_sub(back_gap) {
                during_range = (during_range.0.min(y[back - 1]), during_range.1.max(y[back - 1]));
                let after = back + back_gap;
                let (outside, during) = (over(0, out).add(over(after, m)), over(first, back));
                let kept = outside.add(during);
                // The level outside rests on at least `MIN_OUTSIDE` stretches, and a side of one
                // stretch has no left-out stretch beside it: else a smooth rise and fall (a clock
                // whose rate reverses) passed for an excursion at 5-8 stretches, its two ends the
                // "level" (a review's finding: a noiseless parabola did every time).
                let lone_side_left_out = (out == 1 && out_gap == 1) || (after == m - 1 && back_gap == 1);
                if (kept.n as usize) < MIN_KEPT || (outside.n as usize) < MIN_OUTSIDE || lone_side_left_out {
                    continue;
                }
                let (level, stepped) = (outside.mean(), during.mean());
                let step = stepped - level;
                let largest = reach(head[out], level)
                    .max(reach(tail[after], level))
                    .max(reach(during_range, stepped));
                let squares = outside.about_mean() + during.about_mean();
                let about_step = (squares / kept.n).sqrt();
                let about_line = (kept.about_line() / kept.n).sqrt();
                // An excursion of one stretch has no residual of its own: its own deviation joins
                // the bar.
                let own_bar = if back - first == 1 {
                    own.max(stretches[first].tau_std_s)
                } else {
                    own
                };
                // Written so that a NaN anywhere fails.
                let passes = step.abs() * sample_rate_hz >= MATERIAL_SAMPLES
                    && step.abs() >= STEADY_RATIO * (largest + own_bar)
                    && about_step < 0.5 * about_line;
                if !passes {
                    continue;
                }
                let var = (squares / (kept.n - 2.0)).max(own * own);
                let samples_std = (var * (1.0 / during.n + 1.0 / outside.n)).sqrt() * sample_rate_hz;
                // A group of one stretch may be a mix of the two delays (module docs there).
                let single = out == 1 || back - first == 1 || after == m - 1;
                let found = DelayStep {
                    before_s: level + y_mean,
                    after_s: stepped + y_mean,
                    between_s: [t[out - 1], t[first]],
                    samples: step * sample_rate_hz,
                    samples_std: if single {
                        samples_std.max(0.5 * step.abs() * sample_rate_hz)
                    } else {
                        samples_std
                    },
                    trend: None,
                    back_between_s: Some([t[back - 1], t[after]]),
                };
                if best.as_ref().is_none_or(|(r, _)| about_step < *r) {
                    best = Some((about_step, found));
                }
            }
        }
    }
    best.map(|(_, s)| s)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, DVector};

    use super::*;
    use crate::rng::Rng;

    /// The naive search: every cut fitted by least squares of its own (`tau = a + step [during]`
    /// and the line, through nalgebra's normal equations), the same tests.
    fn naive(stretches: &[StretchFit], t: &[f64], own: f64, fs: f64) -> Option<DelayStep> {
        let m = stretches.len();
        let fit = |x: &DMatrix<f64>, y: &[f64]| {
            let y = DVector::from_column_slice(y);
            let inv = (x.transpose() * x).try_inverse().expect("regular");
            let p = &inv * x.transpose() * &y;
            let r: Vec<f64> = (y - x * &p).iter().copied().collect();
            (p, r, inv)
        };
        let rms = |r: &[f64]| (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
        let mut best: Option<(f64, DelayStep)> = None;
        for (og, bg) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            for out in 1..m {
                for back in out + og + 1..m.saturating_sub(bg) {
                    let during = |i: usize| (out + og..back).contains(&i);
                    let kept: Vec<usize> = (0..m)
                        .filter(|&i| i < out || during(i) || i >= back + bg)
                        .collect();
                    let outside = kept.iter().filter(|&&i| !during(i)).count();
                    let lone_left_out = (out == 1 && og == 1) || (back + bg == m - 1 && bg == 1);
                    if kept.len() < MIN_KEPT || outside < MIN_OUTSIDE || lone_left_out {
                        continue;
                    }
                    let y: Vec<f64> = kept.iter().map(|&i| stretches[i].tau_s).collect();
                    let x = DMatrix::from_fn(kept.len(), 2, |r, c| {
                        if c == 0 {
                            1.0
                        } else {
                            f64::from(u8::from(during(kept[r])))
                        }
                    });
                    let line = DMatrix::from_fn(kept.len(), 2, |r, c| if c == 0 { 1.0 } else { t[kept[r]] });
                    let ((p, r, inv), (_, rl, _)) = (fit(&x, &y), fit(&line, &y));
                    let largest = r.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                    let own_bar = if back - (out + og) == 1 {
                        own.max(stretches[out + og].tau_std_s)
                    } else {
                        own
                    };
                    if p[1].abs() * fs < MATERIAL_SAMPLES
                        || p[1].abs() < STEADY_RATIO * (largest + own_bar)
                        || rms(&r) >= 0.5 * rms(&rl)
                    {
                        continue;
                    }
                    let var = (r.iter().map(|v| v * v).sum::<f64>() / (kept.len() - 2) as f64).max(own * own);
                    let sd = (var * inv[(1, 1)]).sqrt() * fs;
                    let single = out == 1 || back - (out + og) == 1 || back + bg == m - 1;
                    let found = DelayStep {
                        before_s: p[0],
                        after_s: p[0] + p[1],
                        between_s: [t[out - 1], t[out + og]],
                        samples: p[1] * fs,
                        samples_std: if single { sd.max(0.5 * p[1].abs() * fs) } else { sd },
                        trend: None,
                        back_between_s: Some([t[back - 1], t[back + bg]]),
                    };
                    if best.as_ref().is_none_or(|(b, _)| rms(&r) < *b) {
                        best = Some((rms(&r), found));
                    }
                }
            }
        }
        best.map(|(_, s)| s)
    }

    /// Seeded cases (3-30 stretches; steady, excursions of 1-2 samples up or down with mixed or
    /// clean edges, rises): the prefix sums give the naive search's result, to rounding.
    #[test]
    fn prefix_sums_give_the_naive_searchs_result() {
        let mut rng = Rng::new(2611);
        let (fs, mut found) = (500.0, 0);
        for case in 0..300 {
            let m = 3 + (rng.next_u64() % 28) as usize;
            let (out, back) = {
                let a = (rng.next_u64() % m as u64) as usize;
                let b = (rng.next_u64() % m as u64) as usize;
                (a.min(b), a.max(b))
            };
            let size = match case % 4 {
                0 => 0.0,
                1 => 2e-3,
                2 => -4e-3,
                _ => 1e-3 * rng.uniform_in(-1.0, 1.0),
            };
            let own = 1e-5 * rng.uniform_in(0.5, 3.0);
            let fits: Vec<StretchFit> = (0..m)
                .map(|i| {
                    let mixed = if i == out || i == back { rng.uniform() } else { 1.0 };
                    let level = if (out..=back).contains(&i) {
                        size * mixed
                    } else {
                        0.0
                    };
                    StretchFit {
                        span_s: [20.0 * i as f64, 20.0 * i as f64 + 25.0],
                        k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                        tau_s: 4e-3
                            + level
                            + own * rng.normal()
                            + if case % 7 == 0 { 1e-5 * i as f64 } else { 0.0 },
                        tau_std_s: own,
                    }
                })
                .collect();
            let t: Vec<f64> = fits.iter().map(|s| 0.5 * (s.span_s[0] + s.span_s[1])).collect();
            let (fast, slow) = (excursion(&fits, &t, own, fs), naive(&fits, &t, own, fs));
            match (fast, slow) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    found += 1;
                    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * y.abs().max(1e-6);
                    assert!(
                        close(a.before_s, b.before_s)
                            && close(a.after_s, b.after_s)
                            && close(a.samples, b.samples)
                            && close(a.samples_std, b.samples_std)
                            && a.between_s.map(f64::to_bits) == b.between_s.map(f64::to_bits)
                            && a.back_between_s.map(|x| x.map(f64::to_bits))
                                == b.back_between_s.map(|x| x.map(f64::to_bits)),
                        "case {case}: {a:?} against {b:?}"
                    );
                }
                (a, b) => panic!("case {case}: {a:?} against {b:?}"),
            }
        }
        assert!(
            found > 50,
            "only {found} of 300 cases had an excursion: the test says little"
        );
    }
}
