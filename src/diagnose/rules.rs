//! The rules a significant candidate must pass to be named (the search's rounds,
//! [`super::workflow`]): a mode within reach of the band's data (also asked of an accepted
//! mode, [`super::extend`]), and a fit that closes part of the gap and opens it nowhere (also
//! asked of an effect the identified model is suspected of, and of its rival, [`super::suspect`]).
//! A candidate that fails one is said with the reason ([`super::not_named`]).

use std::cmp::Ordering;

use super::candidates::{Candidate, Extension};
use super::not_named::Reason;
use super::state::State;
use crate::effect::Effect;

/// Highest damping ratio of a resonance reported as a finding: 0.5, where the mode's gain at its
/// own frequency, `1 / (2 zeta)`, is 1. A mode damped more attenuates even there (its peak, if
/// any, under 1.25 dB, none beyond 0.707): the data cannot tell it from a gentle roll-off (a lag,
/// the stand's band limit), and its phase lag trades with the channels' delays. A real
/// recording with one gyro channel delayed 3 ms had its skew found right, then "resonances" of
/// damping 0.57-0.60 at 22-28 Hz added, each taking 6.5-8.8 ms from its channel's delay: the
/// skew reported with a channel at -2.5 ms, -7.1 ms on another run. The catalogue's weakest
/// simulated resonance has damping 0.4 (`sim::block`).
pub(super) const MAX_RESONANCE_DAMPING: f64 = 0.5;
/// How close to a band edge (relative) a resonance may sit and still be a finding.
pub(super) const EDGE_MARGIN: f64 = 0.03;

/// Why a candidate's size is outside what the data can show, if it is: a resonance at a band
/// edge (within [`EDGE_MARGIN`], where the fit parks a mode that explains a misfit beyond the
/// band) or damped above [`MAX_RESONANCE_DAMPING`]. (A lag whose corner lies beyond the band is
/// still seen by its droop: a 1.2 ms lag takes 4 % off the gain at 40 Hz.)
pub(super) fn out_of_reach(c: &Candidate, band: [f64; 2]) -> Option<Reason> {
    let (Extension::Structural(fitted), Effect::PlatformResonance) = (&c.extension, c.effect) else {
        return None;
    };
    // A resonance candidate always carries its mode; one without is no fit of a mode.
    let Some(&(f, zeta)) = fitted.theta.resonances.last() else {
        return Some(Reason::FitFailed);
    };
    (!within_reach(f, zeta, band)).then_some(Reason::OutOfReach {
        frequency_hz: f,
        damping: zeta,
    })
}

/// Whether a mode at `f_hz` lies inside `band`, away from its edges by [`EDGE_MARGIN`] (a mode
/// at an edge is pinned there by the fit); a NaN frequency does not.
#[must_use]
pub(super) fn inside_edges(f_hz: f64, band: [f64; 2]) -> bool {
    f_hz > band[0] * (1.0 + EDGE_MARGIN) && f_hz < band[1] * (1.0 - EDGE_MARGIN)
}

/// Whether a mode of frequency `f_hz` and damping `zeta` is one the data over `band` can show:
/// inside its edges and damped at most [`MAX_RESONANCE_DAMPING`]; a NaN frequency or damping is
/// not.
#[must_use]
pub(super) fn within_reach(f_hz: f64, zeta: f64, band: [f64; 2]) -> bool {
    inside_edges(f_hz, band) && zeta <= MAX_RESONANCE_DAMPING
}

/// Whether the candidate is a tone above the fit's band: it leaves the band's gap as it is
/// (what it explains is its own line, measured against the local continuum there).
pub(super) fn above_band(c: &Candidate) -> bool {
    matches!(&c.extension, Extension::Tone(t) if t.upper)
}

/// Numerical tolerance of "a channel's gap does not grow", dB: refitting every parameter moves
/// the gap of a channel the effect does not touch by a few ten-thousandths of a dB either way.
const GAP_TOLERANCE_DB: f64 = 0.005;

/// Why `next` does not close part of `state`'s gap and open it nowhere, if it does not: the
/// total (all channels) must shrink, and no channel's gap (the worst's included) grow beyond
/// [`GAP_TOLERANCE_DB`]. A skew of 0.1 ms between channels closes the gap of the channels it
/// delays and leaves the worst channel's as it was, to 0.0004 dB.
pub(super) fn opens_gap(state: &State, next: &State, outputs: [&str; 3]) -> Option<Reason> {
    let (total_before, total_after) = (state.total_gap_db(), next.total_gap_db());
    // (The gaps are floored at -300 dB, never NaN; were one NaN, nothing would shrink and every
    // channel open.)
    if total_after.partial_cmp(&total_before) != Some(Ordering::Less) {
        return Some(Reason::TotalGrows {
            before_db: total_before,
            after_db: total_after,
        });
    }
    let (before, after) = (state.gap_db(), next.gap_db());
    let opened = |i: usize| {
        !matches!(
            after[i].partial_cmp(&(before[i] + GAP_TOLERANCE_DB)),
            Some(Ordering::Less | Ordering::Equal)
        )
    };
    let channel = (0..3)
        .filter(|&i| opened(i))
        .max_by(|&i, &j| (after[i] - before[i]).total_cmp(&(after[j] - before[j])))?;
    Some(Reason::OpensGap {
        channel: outputs[channel].to_owned(),
        before_db: before[channel],
        after_db: after[channel],
        worst_before_db: state.worst_gap_db(),
        worst_after_db: next.worst_gap_db(),
    })
}
