//! The stand's band limit as the diagnosis fits it ([`Effect::ReferenceBandLimit`]): the angle
//! measurement passed through a low-pass `H(s)` (a motion-capture reference interpolated from a
//! slower rate, a zero-phase band limit, a tracker's or an encoder's own filter), so every input
//! computed from the angles is `H u` and the block's outputs, `K e^(-tau s) u`, read as
//! `K e^(-tau s) u_measured / H(s)` against them. Both blocks see the same `H`; no sensor's own
//! response rises over its input with no phase of its own or with a filter's lead, so a rise of
//! these forms is the stand's.
//!
//! `1 / H` is searched in one of a few shapes, each with one time constant `T` (corner
//! `f_c = 1 / (2 pi T)`):
//! - [`BandLimitShape::ZeroPhase`] of order `m`: `sqrt(1 + (w T)^(2m))`, an inverse Butterworth
//!   magnitude with no phase (`m = 1` takes linear interpolation from a rate `f_r`, whose
//!   `1 / sinc^2(f / f_r)` is `1 + w^2 / (12 f_r^2)` at low frequency: `T = 1 / (sqrt(6) f_r)`;
//!   `m = 2, 4, 8` the steeper droops of splines and symmetric band limits);
//! - [`BandLimitShape::Causal2`]: `1 + sqrt(2) s T + (s T)^2`, the inverse of a causal
//!   second-order Butterworth: the angles lag the motion by its group delay `sqrt(2) T`, and the
//!   block's delay with it is the delay against the motion, that much later than the delay-only
//!   model's against the angles;
//! - [`BandLimitShape::Interpolated`]: `1 / sinc^2(f T)`, a reference sampled every `T` and
//!   interpolated linearly (order 1 is its approximation at low frequency, whose rise falls 13 %
//!   short at a fifth of the reference's rate: with a 100 Hz reference and a band to 20-40 Hz the
//!   difference went to a sensor's `g_sensitivity`).
//!
//! A first-order causal filter is a lag of the inputs, the lag candidate's
//! ([`Effect::ReferenceLag`] when both blocks share it). Each shape is a candidate of its own
//! (as each axis's resonance is) with one parameter, `T`; the causal one set aside where it beats
//! the shapes without phase by less than a parameter's worth (`without_needless_phase`).
//!
//! Units: `T` in s, `omega` in rad/s, frequencies in Hz. Non-finite or non-positive band tops
//! give no candidate.

use super::candidates::{Candidate, structural};
use super::design::WINDOW_ENBW;
use super::fit::{cheapest, cost_at, fit};
use super::state::State;
use crate::effect::Effect;
pub use crate::model::band_limit::BandLimitShape;

/// The rises at the band's top each shape's search starts from (the best of them).
const START_RISES: [f64; 3] = [0.005, 0.02, 0.08];

/// The candidates, one per shape: each from the best of a few starting points (by their rise at
/// the band's top), fitted. Each shape is a candidate of its own, so the search's look-elsewhere
/// cost counts every shape tried (`super::candidates::tried`, one set aside too; on perfect
/// simulated stands the best of the shapes, one parameter each, came within a few units of chi2
/// of the threshold on 2 of 54 runs when counted as one).
pub(super) fn band_limit_candidates(state: &State, band_hz: [f64; 2]) -> Vec<Candidate> {
    let current = &state.fitted;
    let top = band_hz[1];
    if !(top.is_finite() && top > 0.0) {
        return Vec::new();
    }
    let fitted = BandLimitShape::SHAPES
        .into_iter()
        .filter_map(|shape| {
            let mut s = current.structure.clone();
            s.band_limit = Some(shape);
            let starts = START_RISES.into_iter().map(|rise| {
                let mut theta = current.theta.clone();
                theta.band_limit_t_s = shape.t_for_rise(rise, top);
                theta.tau_s += shape.group_delay_s(theta.band_limit_t_s);
                theta
            });
            let start = cheapest(&state.design, &state.grams, &s, starts)?;
            structural(
                Effect::ReferenceBandLimit,
                state,
                fit(&state.design, &state.grams, &s, &start, band_hz),
            )
        })
        .collect();
    without_needless_phase(fitted, 3.0 * state.design.dof_per_channel())
}

/// The shapes fitted, the causal one set aside where it explains more than the best shape
/// without phase but not by `ln(dof)` (`dof` the band's real degrees of freedom: what the
/// diagnosis asks of a parameter). In the band a causal shape far above it is all but a delay,
/// its group delay traded for the block's: a band limit accepted on stands without one (a
/// helper's campaign: perfect, latency-only and coloured-noise stands, 296 blocks) fitted it on
/// 26-38 % of blocks, its corner at 130-230 Hz beside a 40 Hz top, and moved the delay by about
/// its group delay, 1.0-1.7 ms, on 83 of them. The shapes without phase claim no group delay; a
/// real causal filter near the band (a tracker's own) explains far more than they do. Here,
/// where the shapes become candidates, the diagnosis's rounds and an accepted effect's fit apply
/// the same rule (it sat in the latter alone until 30 Nov: the diagnosis could name a causal
/// shape that its acceptance then fitted without phase). A tie with the best shape without phase
/// sets the causal one aside too (the old rule's choice).
pub(super) fn without_needless_phase(candidates: Vec<Candidate>, dof: f64) -> Vec<Candidate> {
    let causal = |c: &Candidate| c.band_limit_shape().is_some_and(BandLimitShape::causal);
    let without_phase = candidates
        .iter()
        .filter(|c| !causal(c))
        .map(|c| c.delta_chi2)
        .fold(f64::NEG_INFINITY, f64::max);
    let margin = dof.max(1.0).ln();
    // One below the shapes without phase stays (the candidates' table lists it; they come first).
    candidates
        .into_iter()
        .filter(|c| !causal(c) || c.delta_chi2 < without_phase || c.delta_chi2 - margin > without_phase)
        .collect()
}

/// How much the band limit in one block's final model `own` (over the band searched, where it
/// was found) improves the other block's final model `other` (over its own band, with its own
/// findings), in `chi2`: the other
/// block sees the same angles, so the stand's band limit must not make its fit worse. The linear
/// parameters are re-solved and the delay searched again (a causal shape moves it by its group
/// delay), the other nonlinear parameters kept. `None` where `own` holds no band limit, the other
/// block holds one of its own (the two are compared in words, not refused), or no cost is finite.
pub(super) fn gain_on_other_block(own: &State, other: &State) -> Option<f64> {
    let shape = own.fitted.structure.band_limit?;
    let t = own.fitted.theta.band_limit_t_s;
    let current = &other.fitted;
    if current.structure.band_limit.is_some() {
        return None;
    }
    let mut structure = current.structure.clone();
    structure.band_limit = Some(shape);
    let mut theta = current.theta.clone();
    theta.band_limit_t_s = t;
    let start = current.theta.tau_s + shape.group_delay_s(t);
    let mut at_delay = |x: &[f64]| {
        let mut th = theta.clone();
        th.tau_s = x[0] * 1e-3;
        cost_at(&other.design, &other.grams, &structure, &th)
    };
    let (_, cost) = super::simplex::minimise(&mut at_delay, &[start * 1e3], &[0.05], 1e-7, 80);
    let gain = 2.0 * (current.profile.cost - cost) / WINDOW_ENBW;
    gain.is_finite().then_some(gain)
}
