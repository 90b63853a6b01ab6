//! Glitches: isolated outliers of 1 to [`MAX_SAMPLES`] samples.
//!
//! The residual `r[i] = x[i] - (x[i-1] + x[i+1]) / 2` (half the second difference) of a smooth
//! signal is its noise; a glitch of size `A` at one sample makes `r` jump to `A` there and `-A/2`
//! beside it. Samples with `|r| > THRESHOLD sigma`, `sigma` the local scale of `r`
//! ([`super::robust::block_scales`], floored at the channel's quantum), are candidates; candidates
//! at most 2 samples apart form a cluster. A cluster is a glitch when bridging 1 to 3 samples by
//! the straight line between their neighbours explains it: the samples removed all lie on one side
//! of the line, more than `THRESHOLD sigma` from it and more than twice the step between the
//! neighbours (a spike, not a step), and after bridging no residual within [`ISOLATION`] samples
//! exceeds `ISOLATED sigma`. Impulsive events that ring for several samples (a tap on the sensor)
//! leave large residuals after any bridge and are not glitches. The first two and last two
//! samples cannot be judged.

use super::robust::{BLOCK, block_scales, quantum};

/// Candidate threshold, local robust standard deviations of `r`.
pub const THRESHOLD: f64 = 12.0;
/// Largest residual left near a bridged glitch, local robust standard deviations.
pub const ISOLATED: f64 = 5.0;
/// Samples checked on each side of a bridged glitch.
pub const ISOLATION: usize = 6;
/// Longest glitch, samples.
pub const MAX_SAMPLES: usize = 3;

/// A glitch found in one channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glitch {
    /// 0-based index of its first sample.
    pub start: usize,
    /// Number of samples (1 to [`MAX_SAMPLES`]).
    pub samples: usize,
    /// The largest departure from the bridging line, signed, channel units.
    pub size: f64,
}

/// The glitches of one channel, in time order.
#[must_use]
pub fn find_glitches(x: &[f64]) -> Vec<Glitch> {
    let n = x.len();
    if n < 2 * ISOLATION + MAX_SAMPLES + 4 {
        return Vec::new();
    }
    let mut r = vec![0.0; n];
    for i in 1..n - 1 {
        r[i] = x[i] - 0.5 * (x[i - 1] + x[i + 1]);
    }
    let scales = block_scales(&r, quantum(x).max(f64::MIN_POSITIVE));
    let sigma = |i: usize| scales[(i / BLOCK).min(scales.len() - 1)];
    let candidates: Vec<usize> = (1..n - 1)
        .filter(|&i| r[i].abs() > THRESHOLD * sigma(i))
        .collect();
    let mut found = Vec::new();
    let mut rest = candidates.as_slice();
    while let Some(&c0) = rest.first() {
        let len = rest.windows(2).take_while(|w| w[1] - w[0] <= 2).count() + 1;
        let c1 = rest[len - 1];
        rest = &rest[len..];
        if c1 - c0 <= MAX_SAMPLES + 1
            && let Some(g) = fit(x, c0, c1, &sigma)
        {
            found.push(g);
        }
    }
    found
}

/// The shortest bridge (then the one leaving the smallest residual) that explains the cluster
/// `c0..=c1`, if any.
fn fit(x: &[f64], c0: usize, c1: usize, sigma: &impl Fn(usize) -> f64) -> Option<Glitch> {
    (1..=MAX_SAMPLES).find_map(|k| {
        (c0.saturating_sub(k)..=c1 + 1)
            .filter(|&a| a + k >= c0 && a >= 2 && a + k + 2 <= x.len())
            .filter_map(|a| bridge(x, a, k, sigma))
            .min_by(|p, q| p.1.total_cmp(&q.1))
            .map(|(g, _)| g)
    })
}

/// Bridges `x[a..a+k]`; returns the glitch and the largest scaled residual left near it, when the
/// bridge makes a spike isolated.
fn bridge(x: &[f64], a: usize, k: usize, sigma: &impl Fn(usize) -> f64) -> Option<(Glitch, f64)> {
    let (left, right) = (x[a - 1], x[a + k]);
    let y = |j: usize| {
        if (a..a + k).contains(&j) {
            left + (right - left) * (j + 1 - a) as f64 / (k + 1) as f64
        } else {
            x[j]
        }
    };
    let size = (a..a + k)
        .map(|j| x[j] - y(j))
        .max_by(|p, q| p.abs().total_cmp(&q.abs()))?;
    let spike = (a..a + k).all(|j| (x[j] - y(j)) * size > 0.0)
        && size.abs() > THRESHOLD * sigma(a)
        && size.abs() > 2.0 * (right - left).abs();
    if !spike {
        return None;
    }
    let lo = a.saturating_sub(ISOLATION).max(1);
    let hi = (a + k + ISOLATION).min(x.len() - 2);
    let worst = (lo..=hi)
        .map(|j| (y(j) - 0.5 * (y(j - 1) + y(j + 1))).abs() / sigma(j))
        .fold(0.0, f64::max);
    (worst < ISOLATED).then_some((
        Glitch {
            start: a,
            samples: k,
            size,
        },
        worst,
    ))
}

/// Replaces each glitch's samples by the straight line between its neighbours (the identifier's
/// copy of a channel; the run itself is never changed). Glitches must come from
/// [`find_glitches`] on the same `x`.
pub fn bridge_glitches(x: &mut [f64], glitches: &[Glitch]) {
    for g in glitches {
        let (a, k) = (g.start, g.samples);
        if a == 0 || a + k >= x.len() {
            continue;
        }
        let (left, right) = (x[a - 1], x[a + k]);
        for j in a..a + k {
            x[j] = left + (right - left) * (j + 1 - a) as f64 / (k + 1) as f64;
        }
    }
}
