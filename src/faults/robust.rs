//! Robust statistics shared by the detectors: a channel's quantum and local, block-wise scales.
//!
//! Empty or one-sample inputs give a quantum of 0 and no blocks; every value is finite (the loader
//! guarantees finite columns).

/// Length of the blocks the local scales are taken over, samples.
pub const BLOCK: usize = 512;

/// The channel's resolution: the smallest positive step `|x[i] - x[i-1]|`, ignoring steps below
/// 1e-9 of the median positive step (floating-point dust from a rotation applied to quantised
/// values). 0 when the channel never changes.
#[must_use]
pub fn quantum(x: &[f64]) -> f64 {
    let mut steps: Vec<f64> = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .collect();
    if steps.is_empty() {
        return 0.0;
    }
    let median = median(&mut steps);
    steps
        .into_iter()
        .filter(|d| *d >= 1e-9 * median)
        .fold(f64::INFINITY, f64::min)
}

/// The median of `v` (reordered in place); 0 for an empty slice.
pub fn median(v: &mut [f64]) -> f64 {
    quantile(v, 0.5)
}

/// The `p`-quantile of `v` (the element of rank `floor(p (len - 1))`, reordered in place); 0 for
/// an empty slice.
pub fn quantile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let k = ((v.len() - 1) as f64 * p) as usize;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// One scale per [`BLOCK`] of `r`: the 90th percentile of `|r - median r|` over 1.645 (the
/// standard deviation for Gaussian `r`, and not deflated where many `r` are exactly 0, as the
/// median absolute deviation is in quantised or resampled data), then the median over the block
/// and its two neighbours, and at least `floor`.
#[must_use]
pub fn block_scales(r: &[f64], floor: f64) -> Vec<f64> {
    let mut buf = Vec::with_capacity(BLOCK);
    let raw: Vec<f64> = r
        .chunks(BLOCK)
        .map(|block| {
            buf.clear();
            buf.extend_from_slice(block);
            let centre = median(&mut buf);
            for v in &mut buf {
                *v = (*v - centre).abs();
            }
            quantile(&mut buf, 0.9) / 1.645
        })
        .collect();
    (0..raw.len())
        .map(|b| {
            let mut near: Vec<f64> = raw[b.saturating_sub(1)..(b + 2).min(raw.len())].to_vec();
            median(&mut near).max(floor)
        })
        .collect()
}
