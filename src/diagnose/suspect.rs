//! Effects the paper's model takes in without a word (issue 13): tested on every identified
//! model, said as [`IdentWarning::EffectSuspected`] ([`Suspicion`]).
//!
//! A gyro's g-sensitivity `G f` follows the specific force, whose gravity part the attitude ties
//! to the angles: a linear filter of the rate (about `g / (j w)` across axes). Bin by bin it is
//! collinear with the input, so the identifier's per-bin estimate takes it into `W_u`, the
//! structural fit turns it into `K` and the delay, and the noise model takes the rest's colour:
//! chi2/dof, the residual's whiteness and the deviations see nothing (a campaign on 1 Dec, 24
//! runs: with the catalogue's g-sensitivity the delay came out 4-25 us early, up to 13.6 of its
//! deviations, and no warning). Only a fit across frequency of `K e^(-tau s) + G f` tells them
//! apart: the diagnosis's candidate ([`super::candidates`]), fitted here on the model's own band
//! from the whole-record design ([`super::prepared::block_design`]). So is an accelerometer's
//! lever-arm error (its tangential part a filter of the rate), and on both blocks channel delays
//! and a quadratic scale factor, which the identifier's own tests see less well ([`tested`]).
//!
//! The evidence is the `chi2` an effect removes against BIC's `ln n` per added parameter (`n`
//! the band's real degrees of freedom) plus the diagnosis's look-elsewhere cost ([`threshold`]);
//! as in the diagnosis, the effect must also close part of the gap between model and outputs and
//! open it nowhere (a `chi2` gain that rests on the noise weights is no evidence), and it is said
//! only where it moves the model's figures beyond their deviations ([`MATERIAL_SIGMAS`]). On the
//! three real recordings the gyro's g-sensitivity removes chi2 11-24 against about 85-95 needed.
//!
//! Units: SI (the shifts in s and relative to `K`). A block whose design cannot be built (too
//! few bins in its band) or whose fit fails is not tested; nothing here fails the
//! identification. Nothing reads a simulated run's answer key.

use std::ops::Range;

use rayon::prelude::*;

use super::candidates::{Candidate, Extension, candidates_among};
use super::prepared::block_design;
use super::report::{gain as gain_of, gain_of_beta};
use super::rules::opens_gap;
use super::state::State;
use super::structure::LagShape;
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::identify::{BlockIdentification, RunIdentification};
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::ident::signals::channel_names;
use crate::ident::suspicion::{Suspicion, input_noise_reads_as};
use crate::ident::warnings::{ElementChange, IdentWarning};
use crate::model::band_limit::BandLimitShape;
use crate::model::{BlockModel, Model};
use crate::run::Run;
use crate::stand::observer::NoiseColour;

/// The effects tested on each block: those a per-bin estimate takes in without a misfit (a
/// gyro's g-sensitivity, an accelerometer's lever-arm error), and those the identifier's own
/// tests see less well than a fit across frequency (channel delays, whose `K` was 7 of its
/// deviations off on a campaign's run without a word; a quadratic scale factor, 4 deviations,
/// `gain_depends_on_amplitude` not said).
#[must_use]
pub fn tested(block: Block) -> [Effect; 3] {
    let own = match block {
        Block::Gyro => Effect::GSensitivity,
        Block::Accel => Effect::LeverArmError,
    };
    [own, Effect::AxisTimeSkew, Effect::ScaleNonlinearity]
}

/// The [`IdentWarning::EffectSuspected`] of each block of `model` (made from `id`, the
/// identification of `session`'s run under `settings`) whose outputs hold one of [`tested`]'s
/// effects. Not tested: a block whose model says it does not explain the data
/// ([`says_misfit`]). A block's model later extended by accepted effects drops them
/// (`Model::set_effects`): it is judged on its own joint fit.
#[must_use]
pub fn suspicions(
    model: &Model,
    session: &Session,
    settings: &Settings,
    id: &RunIdentification,
) -> Vec<(Block, IdentWarning)> {
    let Ok(span) = session.span(settings) else {
        return Vec::new();
    };
    let run = session.run();
    // No sound gyro: the angle noise was taken white, and a suspicion of an effect that inputs
    // holding a coloured one may read as says so.
    let angle_noise_taken_white = id.motion.noise_colour == NoiseColour::White;
    let tests: Vec<(&BlockIdentification, &BlockModel)> = id
        .blocks
        .iter()
        .filter_map(|b| Some((b, model.blocks.get(b.block.name())?)))
        .filter(|(_, entry)| !says_misfit(entry))
        .collect();
    // The blocks in parallel: each is a whole-record design and a few fits.
    tests
        .par_iter()
        .filter_map(|(b, entry)| {
            let s = suspicion(run, id, b, &span, entry)?;
            Some((
                b.block,
                IdentWarning::EffectSuspected(Suspicion {
                    angle_noise_taken_white: angle_noise_taken_white && input_noise_reads_as(s.effect),
                    ..s
                }),
            ))
        })
        .collect()
}

/// Adds `found` ([`suspicions`]) to the fit warnings of `model`'s blocks.
pub fn attach(model: &mut Model, found: Vec<(Block, IdentWarning)>) {
    for (block, w) in found {
        if let Some(entry) = model.blocks.get_mut(block.name()) {
            entry.fit.warnings.push(w);
        }
    }
}

/// Whether `entry` says it does not explain the data, or that its inputs cannot be trusted in
/// part of its band (a user's band). Such a model already sends the reader to the diagnosis,
/// which searches the whole band: over the model's band a misfit from above it may take any
/// shape (an accelerometer's mount mode at 27 Hz beyond a band ended at 20 Hz, its resonance out
/// of the rivals' reach there, was suspected as a lever-arm error moving `K` by 18 %; the
/// diagnosis names the mode), and inputs that are not the motion misfit in any shape too.
fn says_misfit(entry: &BlockModel) -> bool {
    entry.fit.warnings.iter().any(|w| {
        matches!(
            w,
            IdentWarning::PoorFit { .. }
                | IdentWarning::BandTopMisfit { .. }
                | IdentWarning::UntrustedBand { .. }
        )
    })
}

/// The smooth effects that may take the misfit a tested one would (measured on 1 Dec: without
/// them, a gyro's first-order lag was suspected as g-sensitivity on four runs of four, and an
/// accelerometer's channel skews and mount resonance as a lever-arm error on seven of eight;
/// the tested effects are each other's rivals too). Not a tone (a line) nor a clock drift (its
/// test re-times the record). A lag is not tested itself: the delay of the paper's model is the
/// block's whole low-frequency lag, the identifier's order selection fits a lag it can tell.
const RIVALS: [Effect; 3] = [
    Effect::SensorLag,
    Effect::PlatformResonance,
    Effect::ReferenceBandLimit,
];

/// The suspicion for one block, if its outputs hold one of [`tested`]'s effects over the
/// model's band: tried in the order of their gains alone, the first that removes more `chi2`
/// than it must ([`threshold`]) beside the paper's model and, where a rival gains on its own too
/// (and passes the diagnosis's rule itself), beside the paper's model with the rival that gains
/// most, that closes part of the gap and opens it nowhere ([`opens_gap`]), and that moves the
/// model's figures ([`material`]). A quadratic scale factor is not tested where the model already says its gain
/// depends on the amplitude (it stays a rival). The figures are of the paper's model fitted on
/// the whole record over the band, with the rival where it gains more than the effect alone.
fn suspicion(
    run: &Run,
    id: &RunIdentification,
    b: &BlockIdentification,
    span: &Range<usize>,
    entry: &BlockModel,
) -> Option<Suspicion> {
    let band = b.band_hz;
    let (design, _) = block_design(run, &id.motion.euler, b, (band, false), span)?;
    let per_parameter = (3.0 * design.dof_per_channel()).ln();
    let gain = |c: &Candidate| c.delta_chi2 - threshold(c.added_params, per_parameter);
    let base = State::base(design, b.structural.tau_s, band)?;
    let odd = entry
        .fit
        .warnings
        .iter()
        .any(|w| matches!(w, IdentWarning::GainDependsOnAmplitude { .. }));
    let all = tested(b.block);
    // Each tested effect fitted once: a candidate in its own right and a rival of the others.
    let fitted = candidates_among(&base, band, &|e| all.contains(&e));
    let mut alone: Vec<&Candidate> = fitted
        .iter()
        .filter(|c| gain(c) > 0.0 && !(odd && c.effect == Effect::ScaleNonlinearity))
        .collect();
    // Most models end here: the rivals are fitted only where a tested effect gains alone.
    if alone.is_empty() {
        return None;
    }
    alone.sort_by(|x, y| gain(y).total_cmp(&gain(x)));
    let outputs = channel_names(b.block).1;
    // A rival counts where it gains and passes the diagnosis's rule (`rules::opens_gap`) itself:
    // one the diagnosis would refuse is no starting point (a g-sensitivity refused at a clean
    // run's large sines would otherwise have been the channel delays' rival, "fitted first").
    // Each rival's state is kept: the one chosen below is fitted from it.
    let rivals: Vec<(Candidate, State)> = candidates_among(&base, band, &|e| RIVALS.contains(&e))
        .into_iter()
        .chain(fitted.iter().cloned())
        .filter(|r| gain(r) > 0.0)
        .filter_map(|r| {
            let next = base.with(&r, band)?;
            opens_gap(&base, &next, outputs).is_none().then_some((r, next))
        })
        .collect();
    alone.into_iter().find_map(|c| {
        let rival = rivals
            .iter()
            .filter(|(r, _)| r.effect != c.effect)
            .max_by(|(x, _), (y, _)| gain(x).total_cmp(&gain(y)));
        // Beside the rival that gains most it must gain too (a fit beside it that fails
        // clears nothing: not said); its figures are of the model beside the rival only where
        // the rival gains more than it does alone (a gyro's lag beside its g-sensitivity), else
        // of the paper's model alone, which the identified model is (fitted beside channel
        // delays that gained a little, a g-sensitivity moved a delay 5.4 us early by a further
        // 5.2 us: the channel delays' mean is another delay).
        let (from, candidate, beside) = match rival {
            None => (&base, c.clone(), None),
            Some((r, next)) => {
                let beside_r = candidates_among(next, band, &|e| e == c.effect)
                    .into_iter()
                    .next()?;
                (gain(&beside_r) > 0.0).then_some(())?;
                if gain(r) > gain(c) {
                    (next, beside_r, Some(r.effect))
                } else {
                    (&base, c.clone(), None)
                }
            }
        };
        // The diagnosis's rule too: an effect must close part of the gap and open it nowhere
        // (`rules::opens_gap`). On a perfect stand's run with the programme's large sines
        // (20 and 10 degrees at 0.8 and 0.5 Hz) a g-sensitivity removed chi2 140-551 at their
        // lines while the residual's power grew: said, with the delay 4.8-6.9 us "earlier", 13-18
        // of its deviations, on a delay that was right; the diagnosis refused it (`total_grows`).
        let next = from.with(&candidate, band)?;
        if opens_gap(from, &next, outputs).is_some() {
            return None;
        }
        figures(b.block, band, (from, &candidate, beside), entry, per_parameter)
    })
}

/// The suspicion of `candidate` fitted from `from` (beside the rival `beside`) over `band`, if
/// it moves the model's figures.
fn figures(
    block: Block,
    band: [f64; 2],
    (from, candidate, beside): (&State, &Candidate, Option<Effect>),
    entry: &BlockModel,
    per_parameter: f64,
) -> Option<Suspicion> {
    let Extension::Structural(fitted) = &candidate.extension else {
        return None;
    };
    let k_before = gain_of(from);
    let k_after = gain_of_beta(&fitted.profile.beta);
    let tau_std = entry.fit.tau_std_s.filter(|s| *s > 0.0);
    let shift = fitted.theta.tau_s - from.fitted.theta.tau_s;
    // Channel delays: each channel's delay against the model's (the fitted delay is their plain
    // mean, the model's one weighted by the channels' information: that shift is a gauge).
    let channels = (candidate.effect == Effect::AxisTimeSkew).then(|| {
        fitted
            .theta
            .channel_skew_s()
            .map(|d| fitted.theta.tau_s + d - from.fitted.theta.tau_s)
    });
    // One channel's delay holds about a third of the block's information: its deviation is
    // about sqrt(3) times the model's delay deviation.
    let delay_shift_sigmas = tau_std.map(|s| match channels {
        Some(c) => c.iter().fold(0.0_f64, |m, d| m.max(d.abs())) / (3.0_f64.sqrt() * s),
        None => shift.abs() / s,
    });
    let k_shift = furthest_element(block, &k_before, &k_after, &entry.fit.k_std);
    material(delay_shift_sigmas, k_shift.as_ref().map(|e| e.sigmas)).then(|| Suspicion {
        effect: candidate.effect,
        delta_chi2: candidate.delta_chi2,
        threshold: threshold(candidate.added_params, per_parameter),
        band_hz: band,
        beside,
        delay_shift_s: shift,
        delay_shift_sigmas,
        channel_delays_s: channels,
        k_shift,
        k_shift_relative: largest_relative_move(&k_before, &k_after),
        // The run's, set by `suspicions`.
        angle_noise_taken_white: false,
    })
}

/// How many candidates the test may fit on a block: the tested effects, and the rivals as the
/// diagnosis counts them (each lag shape, each resonant axis, each band-limit shape).
const TRIED: usize = 3 + LagShape::SHAPES.len() + 3 + BandLimitShape::SHAPES.len();

/// The `chi2` an effect of `added` parameters must remove: BIC's `ln n` each (`per_parameter`)
/// and the diagnosis's look-elsewhere cost of the best of [`TRIED`] candidates, so that the
/// command line says no more than the diagnosis's first round would name (without it, channel
/// delays that took a small g-sensitivity's misfit, chi2 22.6 against 19.7, were said; the
/// diagnosis does not name them).
fn threshold(added: usize, per_parameter: f64) -> f64 {
    added as f64 * per_parameter + 2.0 * (TRIED as f64).ln()
}

/// Whether an effect moves the model's delay or an element of `K` by more than
/// [`MATERIAL_SIGMAS`] of its own deviation (with no deviation known, it cannot be judged: not
/// said).
fn material(delay_sigmas: Option<f64>, k_sigmas: Option<f64>) -> bool {
    [delay_sigmas, k_sigmas]
        .into_iter()
        .flatten()
        .any(|z| z > MATERIAL_SIGMAS)
}

/// How many of its own deviations an effect must move the model's delay or an element of `K`
/// for its suspicion to be said: an effect the data hold that moves neither beyond its
/// deviation leaves the model's figures honest (the diagnosis still names and sizes it).
pub const MATERIAL_SIGMAS: f64 = 1.0;

/// The element of `K` that moves furthest against its own deviation (`None`: no element has one).
fn furthest_element(
    block: Block,
    before: &[[f64; 3]; 3],
    after: &[[f64; 3]; 3],
    k_std: &[[Option<f64>; 3]; 3],
) -> Option<ElementChange> {
    let (inputs, outputs) = channel_names(block);
    (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter_map(|(i, j)| {
            let s = k_std[i][j].filter(|s| *s > 0.0)?;
            Some(((after[i][j] - before[i][j]).abs() / s, i, j))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(sigmas, i, j)| ElementChange {
            output: outputs[i].to_owned(),
            input: inputs[j].to_owned(),
            sigmas,
        })
}

/// The largest move of an element of `K` over the largest element's size (0 for a zero `K`).
fn largest_relative_move(before: &[[f64; 3]; 3], after: &[[f64; 3]; 3]) -> f64 {
    let size = before.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let moved = (0..9).fold(0.0_f64, |m, k| {
        m.max((after[k / 3][k % 3] - before[k / 3][k % 3]).abs())
    });
    if size > 0.0 { moved / size } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::{furthest_element, largest_relative_move};
    use crate::block::Block;

    const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn the_element_moved_furthest_against_its_own_deviation_is_named() {
        let mut after = IDENTITY;
        after[0][0] += 3e-3; // 3 deviations of 1e-3
        after[2][1] += 1e-3; // 10 deviations of 1e-4: the furthest
        let mut std = [[Some(1e-3); 3]; 3];
        std[2][1] = Some(1e-4);
        let e = furthest_element(Block::Gyro, &IDENTITY, &after, &std).expect("an element");
        assert_eq!((e.output.as_str(), e.input.as_str()), ("gz", "wy"));
        assert!((e.sigmas - 10.0).abs() < 1e-9, "{}", e.sigmas);
        // Largest move 3e-3 over the largest element 1.
        assert!((largest_relative_move(&IDENTITY, &after) - 3e-3).abs() < 1e-15);
        // Without deviations no element is named; a zero gain has no relative move.
        assert!(furthest_element(Block::Accel, &IDENTITY, &after, &[[None; 3]; 3]).is_none());
        assert!(largest_relative_move(&[[0.0; 3]; 3], &after).abs() < f64::MIN_POSITIVE);
    }
}
