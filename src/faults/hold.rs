//! Held samples and clipping: values a logger or a sensor wrote again instead of measuring.
//!
//! **Held samples.** A repeat is a sample exactly equal to the previous one. Quantised channels
//! repeat by chance where the step between samples is within half a quantum of zero, so repeats
//! are only counted in [`BLOCK`]s whose median step is at least [`ELIGIBLE_STEPS`] quanta (the
//! channel moves there), and chance repeats are estimated from the same block: the steps of 1 and
//! 2 quanta (4 bins of one quantum, the density being nearly flat near 0 there) predict the zero
//! bin. A channel is reported when the repeats exceed that expectation by more than
//! [`HELD_FRACTION`] of the eligible samples, by 5 Poisson deviations and by a factor
//! [`HELD_RATIO`], or when one run of repeats reaches [`HELD_RUN`] samples and the step that ends
//! it exceeds [`RELEASE_QUANTA`] (a quantised channel near a turning point of its motion stays
//! within a quantum for many samples, then steps by one). A channel that never
//! moves is never reported here. Limits: held samples in a quantised channel whose steps are within
//! a few quanta (a slow stand's angles) cannot be told from chance and are not reported; a column
//! printed with a fixed number of significant digits whose values cross a power of ten (so its
//! resolution changes within the file) repeats more than its finest step predicts and can be.
//!
//! **Clipping.** At least [`CLIP_RUN`] consecutive samples exactly at the channel's maximum (or
//! minimum), in at least two separate flat tops; only for channels spanning at least
//! [`CLIP_MIN_QUANTA`] quanta (a channel that toggles between a few levels legitimately sits at its
//! extremes).

use super::robust::{BLOCK, median, quantum};

/// Median step, in quanta, from which a block's repeats are counted.
pub const ELIGIBLE_STEPS: f64 = 4.0;
/// Excess repeats, as a fraction of the eligible samples, that are reported.
pub const HELD_FRACTION: f64 = 0.005;
/// Repeats must also exceed this multiple of the chance expectation: the expectation assumes the
/// smallest step is the quantum, and a file printed with fewer digits than the quantum needs (7
/// significant digits of angles near pi: steps of 1e-6 rad from a 1.5e-6 rad quantum) has about
/// twice the repeats that predicts.
pub const HELD_RATIO: f64 = 3.0;
/// A run of this many repeats is reported on its own, where the step that ends it exceeds
/// [`RELEASE_QUANTA`].
pub const HELD_RUN: usize = 5;
/// Quanta the step ending a run of repeats must exceed for the run to count as held on its own
/// ([`HELD_RUN`]). A quantised angle near a turning point of its motion stays within one quantum
/// for many samples and then steps by one: on an independent simulator's calm runs (quantum 2e-5
/// rad, noise 3e-6, 400 Hz) runs of 9-11 repeats with the repeats at their chance count (4061
/// against 4190 expected) were reported as held and the axis called unreliable. A logger that
/// holds a moving channel's value steps by the motion of the whole run when it lets go (the
/// blocks counted move by at least [`ELIGIBLE_STEPS`] quanta a sample); one that holds at a
/// turning point hides nothing. Steps are whole quanta: 2.5 asks for three or more, with room for
/// the rounding of values printed in decimal (the same runs ended by two quanta now and then).
pub const RELEASE_QUANTA: f64 = 2.5;
/// Shortest flat top counted as clipping, samples.
pub const CLIP_RUN: usize = 3;
/// Smallest span of a channel, in quanta, in which flat tops are looked for.
pub const CLIP_MIN_QUANTA: f64 = 100.0;

/// Repeats beyond chance in one channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Held {
    /// Samples equal to their predecessor in the eligible blocks.
    pub held: usize,
    /// Repeats expected by chance there.
    pub expected: f64,
    /// Runs of consecutive repeats.
    pub runs: usize,
    /// The longest run, samples.
    pub longest: usize,
    /// 0-based index of the first repeated sample.
    pub first: usize,
}

/// The held samples of one channel, `None` when its repeats are explained by chance. Repeats of
/// a value in `clipped` (the levels of flat tops already reported) are not counted.
#[must_use]
pub fn find_held(x: &[f64], clipped: &[f64]) -> Option<Held> {
    let q = quantum(x);
    let steps: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let (mut held, mut expected, mut eligible) = (0usize, 0.0, 0usize);
    let (mut runs, mut longest, mut first, mut current) = (0usize, 0usize, None, 0usize);
    // The longest run the channel left by more than [`RELEASE_QUANTA`] (or never left).
    let mut longest_released = 0usize;
    let mut counted_last = false;
    let mut buf = Vec::with_capacity(BLOCK);
    for (b, block) in steps.chunks(BLOCK).enumerate() {
        buf.clear();
        buf.extend_from_slice(block);
        let typical = median(&mut buf);
        let counted = typical > 0.0 && typical >= ELIGIBLE_STEPS * q;
        counted_last = counted;
        if counted {
            eligible += block.len();
            expected += block.iter().filter(|&&d| d > 0.5 * q && d <= 2.5 * q).count() as f64 / 4.0;
        }
        for (i, &d) in block.iter().enumerate() {
            let at = b * BLOCK + i + 1;
            if d != 0.0 || clipped.iter().any(|c| c.to_bits() == x[at].to_bits()) {
                if counted && d > RELEASE_QUANTA * q {
                    longest_released = longest_released.max(current);
                }
                current = 0;
                continue;
            }
            current += 1;
            if counted {
                held += 1;
                first.get_or_insert(at);
                runs += usize::from(current == 1);
                longest = longest.max(current);
            }
        }
    }
    // A run still going at the record's end is left by no step at all.
    if counted_last {
        longest_released = longest_released.max(current);
    }
    let excess = held as f64 - expected;
    let pattern = excess > HELD_FRACTION * eligible as f64
        && held as f64 > HELD_RATIO * expected
        && excess > 5.0 * (expected + 1.0).sqrt();
    (pattern || longest_released >= HELD_RUN).then_some(Held {
        held,
        expected,
        runs,
        longest,
        first: first?,
    })
}

/// Flat tops at one extreme of a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    /// Whether at the maximum (else the minimum).
    pub at_max: bool,
    /// The extreme value, channel units.
    pub level: f64,
    /// Runs of at least [`CLIP_RUN`] samples at `level`.
    pub flat_tops: usize,
    /// Samples at `level`.
    pub samples: usize,
    /// 0-based index of the first sample at `level`.
    pub first: usize,
}

/// The clipped extremes of one channel (maximum first).
#[must_use]
#[expect(clippy::float_cmp, reason = "a clipped sample equals the extreme exactly")]
pub fn find_clipping(x: &[f64]) -> Vec<Clip> {
    let max = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = x.iter().copied().fold(f64::INFINITY, f64::min);
    let spans = max - min >= CLIP_MIN_QUANTA * quantum(x);
    if x.is_empty() || !spans || max <= min {
        return Vec::new();
    }
    [(true, max), (false, min)]
        .into_iter()
        .filter_map(|(at_max, level)| {
            let mut clip = Clip {
                at_max,
                level,
                flat_tops: 0,
                samples: 0,
                first: x.iter().position(|&v| v == level)?,
            };
            let mut run = 0;
            for &v in x.iter().chain([f64::NAN].iter()) {
                if v == level {
                    run += 1;
                    clip.samples += 1;
                } else {
                    clip.flat_tops += usize::from(run >= CLIP_RUN);
                    run = 0;
                }
            }
            (clip.flat_tops >= 2).then_some(clip)
        })
        .collect()
}
