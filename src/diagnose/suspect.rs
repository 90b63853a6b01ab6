//! Effects the paper's model takes in without a word (issue 13): tested on every identified
//! model, said as [`IdentWarning::EffectSuspected`].
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
//! lever-arm error (its tangential part a filter of the rate) tested.
//!
//! The evidence is the `chi2` the effect removes against BIC's `ln n` per added parameter (`n`
//! the band's real degrees of freedom); one effect is tested per block, so without the
//! diagnosis's look-elsewhere term. On the three real recordings the gyro's g-sensitivity removes
//! chi2 11-24 against about 85-95 needed.
//!
//! Units: SI (the shifts in s and relative to `K`). A block whose design cannot be built (too
//! few bins in its band) or whose fit fails is not tested; nothing here fails the
//! identification. Nothing reads a simulated run's answer key.

use std::ops::Range;

use rayon::prelude::*;

use super::candidates::{Candidate, Extension, candidates_among};
use super::prepared::block_design;
use super::report::gain as gain_of;
use super::state::State;
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::identify::{BlockIdentification, RunIdentification};
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::ident::signals::channel_names;
use crate::ident::warnings::{ElementChange, IdentWarning};
use crate::model::{BlockModel, Model};
use crate::run::Run;

/// The effect tested on each block: the one a per-bin estimate takes in without a misfit.
#[must_use]
pub fn tested(block: Block) -> Effect {
    match block {
        Block::Gyro => Effect::GSensitivity,
        Block::Accel => Effect::LeverArmError,
    }
}

/// Adds [`IdentWarning::EffectSuspected`] to each block of `model` (made from `id`, the
/// identification of `session`'s run under `settings`) whose outputs hold [`tested`]'s effect;
/// a block whose model already holds the effect (accepted: `model.effects`) or says it does not
/// explain the data (`poor_fit`, `band_top_misfit`) is not tested.
pub fn attach(model: &mut Model, session: &Session, settings: &Settings, id: &RunIdentification) {
    let Ok(span) = session.span(settings) else {
        return;
    };
    let run = session.run();
    let tests: Vec<(&BlockIdentification, &BlockModel)> = id
        .blocks
        .iter()
        .filter_map(|b| Some((b, model.blocks.get(b.block.name())?)))
        .filter(|(b, entry)| !holds(entry, tested(b.block)) && !says_misfit(entry))
        .collect();
    // The blocks in parallel: each is a whole-record design and a few fits.
    let found: Vec<(Block, IdentWarning)> = tests
        .par_iter()
        .filter_map(|(b, entry)| Some((b.block, suspicion(run, id, b, &span, entry)?)))
        .collect();
    for (block, w) in found {
        if let Some(entry) = model.blocks.get_mut(block.name()) {
            entry.fit.warnings.push(w);
        }
    }
}

/// Whether `entry`'s model holds `effect` (accepted into it).
fn holds(entry: &BlockModel, effect: Effect) -> bool {
    entry
        .effects
        .as_ref()
        .is_some_and(|e| e.accepted.iter().any(|a| a.effect == effect))
}

/// Whether `entry` says it does not explain the data. Such a model already sends the reader to
/// the diagnosis, which searches the whole band: over the model's band a misfit from above it
/// may take any shape (an accelerometer's mount mode at 27 Hz beyond a band ended at 20 Hz, its
/// resonance out of the rivals' reach there, was suspected as a lever-arm error moving `K` by
/// 18 %; the diagnosis names the mode).
fn says_misfit(entry: &BlockModel) -> bool {
    entry.fit.warnings.iter().any(|w| {
        matches!(
            w,
            IdentWarning::PoorFit { .. } | IdentWarning::BandTopMisfit { .. }
        )
    })
}

/// The smooth effects that may take the misfit the tested one would (measured on 1 Dec: without
/// them, a gyro's first-order lag was suspected as g-sensitivity on four runs of four, and an
/// accelerometer's channel skews and mount resonance as a lever-arm error on seven of eight).
/// Not a tone (a line) nor a clock drift (its test re-times the record).
const RIVALS: [Effect; 5] = [
    Effect::SensorLag,
    Effect::AxisTimeSkew,
    Effect::PlatformResonance,
    Effect::ReferenceBandLimit,
    Effect::ScaleNonlinearity,
];

/// The warning for one block, if its outputs hold [`tested`]'s effect over the model's band:
/// the effect removes more `chi2` than its parameters cost, fitted beside the paper's model and,
/// where a rival gains more, beside the paper's model with that rival too.
fn suspicion(
    run: &Run,
    id: &RunIdentification,
    b: &BlockIdentification,
    span: &Range<usize>,
    entry: &BlockModel,
) -> Option<IdentWarning> {
    let band = b.band_hz;
    let (design, _) = block_design(run, &id.motion.euler, b, (band, false), span)?;
    let per_parameter = (3.0 * design.dof_per_channel()).ln();
    let gain = |c: &Candidate| c.delta_chi2 - c.added_params as f64 * per_parameter;
    let base = State::base(design, b.structural.tau_s, band)?;
    let effect = tested(b.block);
    let alone = candidates_among(&base, band, &|e| e == effect)
        .into_iter()
        .next()?;
    // Most models end here: the rivals are fitted only for an effect that gains alone.
    (gain(&alone) > 0.0).then_some(())?;
    let rival = candidates_among(&base, band, &|e| RIVALS.contains(&e))
        .into_iter()
        .max_by(|x, y| gain(x).total_cmp(&gain(y)))
        .filter(|r| gain(r) > gain(&alone));
    let (from, candidate) = match rival {
        None => (base, alone),
        Some(r) => {
            let next = base.with(&r, band)?;
            let c = candidates_among(&next, band, &|e| e == effect)
                .into_iter()
                .next()?;
            (gain(&c) > 0.0).then_some(())?;
            (next, c)
        }
    };
    let Extension::Structural(fitted) = &candidate.extension else {
        return None;
    };
    let k_before = gain_of(&from);
    let k_after = {
        let beta = &fitted.profile.beta;
        [0, 1, 2].map(|i| [0, 1, 2].map(|j| beta[3 * i + j]))
    };
    let shift = fitted.theta.tau_s - from.fitted.theta.tau_s;
    Some(IdentWarning::EffectSuspected {
        effect,
        delta_chi2: candidate.delta_chi2,
        threshold: candidate.added_params as f64 * per_parameter,
        band_hz: band,
        delay_shift_s: shift,
        delay_shift_sigmas: entry.fit.tau_std_s.filter(|s| *s > 0.0).map(|s| shift.abs() / s),
        k_shift: furthest_element(b.block, &k_before, &k_after, &entry.fit.k_std),
        k_shift_relative: largest_relative_move(&k_before, &k_after),
    })
}

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
