//! Accepting effects into a block's model (issue 15, "accept means accept"): the paper's model
//! fitted on the whole record ([`Prepared`]) is extended by each accepted effect in turn, every
//! parameter refitted, as the diagnosis's rounds do but without asking the effect to be
//! significant (the engineer decided). The result replaces the block's structural model in the
//! model file ([`crate::model::ModelEffects`]): what `identify --effects` writes and what the
//! app shows and exports after Accept. When none of a block's accepted effects can be added, its
//! identified model is kept and they are listed with the reasons.

use super::DiagnoseError;
use super::candidates::{Candidate, candidates_among};
use super::design::WINDOW_ENBW;
use super::fit::Fitted;
use super::profile;
use super::report::{gain, parameters};
use super::rules::within_reach;
use super::state::State;
use super::structure::LagShape;
use super::uncertainty::{covariance, parameter_std, tau_std};
use super::workflow::{Prepared, PreparedBlock, prepare};
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::identify::IdentStep;
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::ident::signals::channel_names;
use crate::model::band_limit::FittedBandLimit;
use crate::model::effects::{AcceptedEffect, Identified, NotAdded, Resonance};
use crate::model::{BlockModel, Model, ModelEffects};

/// The model file of `session`'s run under `settings` with the `accepted` effects in its
/// blocks' models, its noise terms attached: `identify --effects`. With nothing accepted it is
/// exactly [`super::identified::identified_model`]'s file.
///
/// # Errors
/// The identification's and the diagnosis's (a record too short for the whole-record fit).
pub fn extended_model(
    session: &mut Session,
    settings: &Settings,
    accepted: &[(Block, Effect)],
    progress: &mut dyn FnMut(IdentStep),
) -> Result<Model, DiagnoseError> {
    let mut model = super::identified::bare_model(session, settings, progress)?;
    let preps = prepare_for_effects(session, settings, &model, accepted)?;
    apply_effects(&mut model, &preps, accepted);
    crate::noise::of_model::attach_noise(&mut model, session, settings)?;
    Ok(model)
}

/// The whole-record starting points the `accepted` effects of `model`'s blocks are fitted
/// from, for each block that has any: one over that block's own band as identified (the usable
/// band with `band_hz: "auto"`, ended where the model stops explaining the data at its top). Not
/// the diagnosis's band: the diagnosis looks for misfit where the inputs may not be trustworthy,
/// but a model is fitted only where they are (on the real recordings, over 0.1-40 Hz a gyro's K
/// came out 0.4-1.4 % off; over its usable band, within 0.6 %). Where that top was cut because
/// the identified model missed the data above it (`band_top_misfit`) and a filter is accepted
/// (a mode, a lag, a band limit, channel delays: [`Effect::shapes_the_band_top`]), a second one
/// through the band that was cut ([`uncut_band`]; left out where it cannot be prepared): the
/// filter may be what the identified model missed. [`apply_effects`]
/// tells them apart by their bands.
///
/// # Errors
/// As [`prepare`], for a block's own band.
pub fn prepare_for_effects(
    session: &mut Session,
    settings: &Settings,
    model: &Model,
    accepted: &[(Block, Effect)],
) -> Result<Vec<Prepared>, DiagnoseError> {
    let mut preps = Vec::new();
    for block in Block::BOTH {
        let Some(entry) = model.blocks.get(block.name()) else {
            continue;
        };
        let effects = of_block(accepted, block);
        if effects.is_empty() {
            continue;
        }
        let over = |band: [f64; 2]| Settings {
            band_hz: crate::ident::band::BandSetting::Fixed(band),
            blocks: vec![block],
            ..settings.clone()
        };
        preps.push(prepare(session, &over(entry.band_hz))?);
        if let Some(band) = uncut_band(entry, &effects)
            && let Ok(p) = prepare(session, &over(band))
        {
            preps.push(p);
        }
    }
    Ok(preps)
}

/// Whether `preps` hold, for every block of `model` with `accepted` effects, a start over the
/// band that block is identified over ([`apply_effects`] tells the starts apart by band): a
/// cache of them made for another model under the same settings (a refined fit's band top, then
/// the cold refit's) is not this model's.
#[must_use]
pub fn starts_match(preps: &[Prepared], model: &Model, accepted: &[(Block, Effect)]) -> bool {
    Block::BOTH.iter().all(|&block| {
        let Some(entry) = model.blocks.get(block.name()) else {
            return true;
        };
        of_block(accepted, block).is_empty()
            || preps
                .iter()
                .flat_map(|p| &p.blocks)
                .any(|pb| pb.block == block && same_top(pb.band_hz, entry.band_hz))
    })
}

/// Whether two bands end at the same frequency (a fixed band is prepared as given).
fn same_top(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[1] - b[1]).abs() <= 1e-9 * b[1]
}

/// The effects of `accepted` on `block`, in order.
fn of_block(accepted: &[(Block, Effect)], block: Block) -> Vec<Effect> {
    accepted
        .iter()
        .filter(|(b, _)| *b == block)
        .map(|&(_, e)| e)
        .collect()
}

/// The band `entry` was identified over with its top where it was before the identified model's
/// misfit cut it (`band_top_misfit`), where `effects` hold a filter that can be what the model
/// missed there ([`Effect::shapes_the_band_top`]): a gyro with a 21.7 Hz mode, the band cut at
/// 24.9 Hz of a usable 39.8, the model's chi2 per bin above it 24535 times its expectation; a
/// stand whose angles are band-limited at 30 Hz, the band cut at 25.9 Hz of a usable 32.6, 37.5
/// times. `None` otherwise.
fn uncut_band(entry: &BlockModel, effects: &[Effect]) -> Option<[f64; 2]> {
    if !effects.iter().any(|e| e.shapes_the_band_top()) {
        return None;
    }
    entry.fit.warnings.iter().find_map(|w| match w {
        crate::ident::warnings::IdentWarning::BandTopMisfit { band_hz, .. }
            if band_hz[1] > entry.band_hz[1] =>
        {
            Some([entry.band_hz[0], band_hz[1]])
        }
        _ => None,
    })
}

/// Extends every block of `model` that has accepted effects (`preps` from
/// [`prepare_for_effects`] on the same run, settings and model), from its start over the band
/// it was identified over (by band; the first of the block's where none matches). Blocks without
/// any are left as identified. Where a block also has a start through a wider band (the one its
/// identified model's misfit cut, [`uncut_band`]), the model fitted through it replaces that
/// one where it explains the data there ([`explains_through`]): the model's band is then the
/// wider one, and the misfit's warning goes
/// ([`BlockModel::take_back_the_cut_band`]).
pub fn apply_effects(model: &mut Model, preps: &[Prepared], accepted: &[(Block, Effect)]) {
    let calibrated = model.settings.calibrated;
    for block in Block::BOTH {
        let effects = of_block(accepted, block);
        let Some(entry) = model.blocks.get_mut(block.name()) else {
            continue;
        };
        let starts: Vec<&PreparedBlock> = preps
            .iter()
            .flat_map(|p| &p.blocks)
            .filter(|pb| pb.block == block)
            .collect();
        let top = entry.band_hz[1];
        let Some(&own) = starts
            .iter()
            .find(|pb| same_top(pb.band_hz, entry.band_hz))
            .or(starts.first())
        else {
            continue;
        };
        if effects.is_empty() {
            continue;
        }
        // The model as identified, kept only where there is a wider start to fit it through.
        let wider = starts
            .iter()
            .find(|pb| pb.band_hz[1] > top * (1.0 + 1e-9))
            .map(|&pb| (pb, entry.clone()));
        extend_block(entry, own, &effects, calibrated);
        let Some((wider, mut through)) = wider else {
            continue;
        };
        let Some(fitted) = extend_block(&mut through, wider, &effects, calibrated) else {
            continue;
        };
        // The wider fit's own chi2 over the cut band: its structure and nonlinear parameters on
        // that band's design, the linear ones solved again (at most its own there: the strict
        // side for what the stretch adds).
        let base = &own.base;
        let below = profile::project(
            &base.design,
            &base.grams,
            &fitted.structure,
            &fitted.layout,
            &fitted.theta,
        )
        .map(|p| 2.0 * p.cost / WINDOW_ENBW);
        if let (Some(t), Some(n), Some(below)) = (&through.effects, &entry.effects, below)
            && explains_through(t, n, below, [own.dof, wider.dof])
        {
            through.take_back_the_cut_band(wider.band_hz);
            *entry = through;
        }
    }
}

/// Whether `through`, the effects fitted through a wider band than `narrow`'s (`dof`: the two
/// fits' degrees of freedom, narrow first), holds a filter the wider band was tried for
/// ([`Effect::shapes_the_band_top`]) that it determines (a deviation known: not held at a bound
/// of its range or unseen by the band, `super::uncertainty`, a filter that does nothing there)
/// and every effect `narrow` adds, and explains the data there: its chi2/dof at most
/// [`crate::ident::selfcheck::POOR_FIT`], and so is the chi2 the stretch added takes per degree
/// of freedom it adds, `(chi2 - chi2_below) / (dof - narrow_dof)` with `chi2_below` its own chi2
/// over the narrow band (the absolute arm of the rule that cut the band, which asks the stretch
/// above it not to exceed that; the whole band's figure alone could hide a stretch at 3.5 beside
/// a band at 0.8). Not the narrow fit's chi2: where the mode lies above the cut, the narrow fit
/// cannot hold it, and its chi2 (the delay-only fit's, in the hundreds) would take the stretch
/// for explained whatever it holds.
fn explains_through(
    through: &ModelEffects,
    narrow: &ModelEffects,
    chi2_below: f64,
    [narrow_dof, through_dof]: [f64; 2],
) -> bool {
    let poor = crate::ident::selfcheck::POOR_FIT;
    let added = (through.chi2_per_dof[1] * through_dof - chi2_below) / (through_dof - narrow_dof);
    through
        .accepted
        .iter()
        .any(|a| a.effect.shapes_the_band_top() && holds_a_deviation(&a.parameter_std))
        && narrow
            .accepted
            .iter()
            .all(|a| through.accepted.iter().any(|b| b.effect == a.effect))
        && through.chi2_per_dof[1] <= poor
        && through_dof > narrow_dof
        && added <= poor
}

/// The candidate an accepted effect is fitted as: the one that explains most, each added
/// parameter charged `ln(dof)` as in the diagnosis's criterion (its shapes are each a candidate:
/// a band limit's, its causal shape set aside where it beats the shapes without phase by less
/// than `ln(dof)`, `super::band_limit::without_needless_phase`; a lag's first and second order).
/// The shape is chosen again on the record the model is fitted to, not read from the finding.
fn best_candidate(candidates: Vec<Candidate>, dof: f64) -> Option<Candidate> {
    // Shapes with more parameters pay for them as in the diagnosis's criterion.
    let gain = |c: &Candidate| c.delta_chi2 - dof.max(1.0).ln() * c.added_params as f64;
    candidates.into_iter().max_by(|a, b| gain(a).total_cmp(&gain(b)))
}

/// Whether an accepted effect's `parameter_std` holds a finite number (a parameter held at a
/// bound, or unseen by the band, has `null`).
fn holds_a_deviation(std: &serde_json::Value) -> bool {
    match std {
        serde_json::Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        serde_json::Value::Array(a) => a.iter().any(holds_a_deviation),
        serde_json::Value::Object(o) => o.values().any(holds_a_deviation),
        _ => false,
    }
}

/// Adds `effects` (in order, each once) to the block's whole-record model and writes the result
/// into `entry`; when none can be added, `entry` keeps its identified model and only lists them
/// with the reasons.
fn extend_block(
    entry: &mut BlockModel,
    pb: &PreparedBlock,
    effects: &[Effect],
    calibrated: bool,
) -> Option<Fitted> {
    let band = pb.band_hz;
    let mut state = pb.base.clone();
    let mut added: Vec<(Effect, usize)> = Vec::new();
    let mut not_added = Vec::new();
    for &effect in effects {
        if added.iter().any(|(e, _)| *e == effect) || not_added.iter().any(|n: &NotAdded| n.effect == effect)
        {
            continue;
        }
        if !effect.blocks().contains(&pb.block) {
            not_added.push(NotAdded {
                effect,
                reason: format!(
                    "{} is not an effect of the {} block",
                    effect.what(),
                    pb.block.name()
                ),
            });
            continue;
        }
        let index = index_of(&state, effect);
        // The stand's lag is fitted as a lag of the block's model (the same filter).
        let fitted = if effect == Effect::ReferenceLag {
            Effect::SensorLag
        } else {
            effect
        };
        let best = best_candidate(candidates_among(&state, band, &|e| e == fitted), pb.dof);
        let next = best.and_then(|c| state.with(&c, band));
        match next
            .as_ref()
            .map(|next| (next, unfit(effect, &state, next, band)))
        {
            Some((next, None)) => {
                state = next.clone();
                added.push((effect, index));
            }
            Some((_, Some(reason))) => not_added.push(NotAdded { effect, reason }),
            None => not_added.push(NotAdded {
                effect,
                reason: "it could not be fitted on this record (no candidate, or a degenerate fit)"
                    .to_owned(),
            }),
        }
    }
    let (input_names, _) = channel_names(pb.block);
    let chi2_per_dof = [pb.base.fitted.chi2() / pb.dof, state.fitted.chi2() / pb.dof];
    // No covariance where nothing was added: the block keeps its identified model (below).
    let cov = (!added.is_empty())
        .then(|| covariance(&state, band, chi2_per_dof[1]))
        .flatten();
    let accepted = added
        .iter()
        .map(|&(effect, index)| AcceptedEffect {
            effect,
            name: match (effect, state.fitted.structure.lag) {
                (Effect::SensorLag, Some(shape)) => shape.name_on(pb.block),
                _ => effect.name_on(pb.block),
            },
            parameters: parameters(effect, &state, index, input_names),
            parameter_std: parameter_std(effect, &state, index, cov.as_ref()),
        })
        .collect();
    let f = &state.fitted;
    let effects = ModelEffects {
        accepted,
        not_added,
        lag_s: f.structure.lag.map(|_| f.theta.lag_s),
        lag_damping: (f.structure.lag == Some(LagShape::SecondOrder)).then_some(f.theta.lag_damping),
        channel_skew_s: f.structure.skew.then(|| f.theta.channel_skew_s()),
        resonances: f
            .structure
            .resonance_axes
            .iter()
            .zip(&f.theta.resonances)
            .map(|(&axis, &(frequency_hz, damping))| Resonance {
                axis,
                frequency_hz,
                damping,
            })
            .collect(),
        reference_band_limit: f.structure.band_limit.map(|shape| FittedBandLimit {
            shape,
            t_s: f.theta.band_limit_t_s,
        }),
        identified: Identified {
            k: entry.k,
            tau_s: entry.tau_s,
            order: entry.order,
            band_hz: Some(entry.band_hz),
        },
        band_hz: band,
        chi2_per_dof,
        gap_db: [pb.base.gap_db(), state.gap_db()],
    };
    if added.is_empty() {
        // Nothing could be added: the block's model stays as identified (over its usable band,
        // with its order, poles and even gain), not the whole-record fit without effects, whose
        // K and delay differ within their deviations; the effects only list what was asked.
        entry.effects = Some(effects);
        return None;
    }
    let k_std = [0, 1, 2].map(|i| [0, 1, 2].map(|j| cov.as_ref().and_then(|c| c.linear_std(3 * i + j))));
    let tau_sd = cov.as_ref().and_then(tau_std);
    entry.set_effects(effects, gain(&state), k_std, f.theta.tau_s, tau_sd, calibrated);
    Some(state.fitted)
}

/// Why an accepted effect's fit `next` (from `state`, over `band`) is not added, if it is not: a
/// mode the band does not reach, parked at its edge or damped past a peak (the diagnosis's own
/// rule, [`within_reach`]), or a fit that leaves the model worse than without the effect (a fit
/// that did not converge: the effect nests the model without it; not a clock correction, whose
/// chi2 is of resampled outputs). Accepting a mode the diagnosis found at 30 Hz into a gyro
/// identified over 0.12-4.15 Hz (0.2 mrad coloured angle noise) put it at 4.15 Hz with damping
/// 0.43, the delay at -2.8 ms and K 3 % off, chi2/dof 1.06 -> 3.51, with no word.
fn unfit(effect: Effect, state: &State, next: &State, band: [f64; 2]) -> Option<String> {
    let (before, after) = (state.fitted.chi2(), next.fitted.chi2());
    if effect == Effect::PlatformResonance
        && let Some(&(f, zeta)) = next.fitted.theta.resonances.last()
        && !within_reach(f, zeta, band)
    {
        return Some(format!(
            "the band the block is identified over ({:.2}-{:.2} Hz) does not reach the mode: its \
             fit there parks at {f:.2} Hz, damping {zeta:.2}; give a band_hz that reaches the \
             mode to fit it",
            band[0], band[1]
        ));
    }
    // A clock correction resamples the outputs: its chi2 is of another design, not comparable
    // (a fit that diverged is still refused).
    if effect == Effect::ClockDrift && after.is_finite() {
        return None;
    }
    // A NaN chi2 is worse.
    let better = after
        .partial_cmp(&(before * (1.0 + 1e-9)))
        .is_some_and(std::cmp::Ordering::is_le);
    (!better).then(|| {
        format!(
            "its fit over {:.2}-{:.2} Hz leaves the model worse than without it (chi2 {before:.1} \
             -> {after:.1}): the fit did not converge",
            band[0], band[1]
        )
    })
}

/// The index the effect's next instance will have in `state` (tones and resonances are counted).
fn index_of(state: &State, effect: Effect) -> usize {
    match effect {
        Effect::VibrationTone => state.tones.len(),
        _ => state.fitted.structure.resonance_axes.len(),
    }
}

#[cfg(test)]
#[path = "extend_tests.rs"]
mod tests;
