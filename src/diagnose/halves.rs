//! Is a finding one property of the block over the run? Each half of the analysed stretch is
//! fitted on its own with the final model's structure (every finding of the block in it), and
//! each finding's sizes on the two halves are compared figure by figure, as runs are compared
//! (`compare::findings`: beyond [`crate::compare::SIGNIFICANCE_SIGMAS`] combined standard
//! deviations, each half's from its own fit, sandwich included). A sensor effect is the same in
//! both halves; a misfit of the effect's form that the motion or the reference makes (a rate-shaped
//! misfit the search calls a quadratic scale factor, on a real recording) need not be, and the
//! finding's evidence then says so. A second-order lag's damping is compared beside its `T`
//! (`compare::findings::shape_figures`): a filter of the block keeps its shape. The halves'
//! figures are kept in the finding (`halves`).
//!
//! Skipped (nothing said) for a block whose model holds a tone in its band or a clock
//! correction (a tone's phase and the re-timing are fitted on the whole record), for tone and
//! clock-drift findings themselves, and where a half is too short for the band or cannot be
//! fitted. Units as the findings' parameters.

use std::fmt::Write as _;
use std::ops::Range;
use std::sync::Arc;

use serde_json::json;

use super::report::{Finding, parameters};
use super::state::State;
use super::uncertainty::{covariance, parameter_std};
use crate::compare::Delta;
use crate::compare::findings::{
    SizeDelta, figures as finding_figures, most_different, shape_figures, sizes_and_shapes,
};
use crate::effect::Effect;
use crate::ident::identify::RunIdentification;
use crate::run::Run;

/// What the halves of a run's analysed stretch are built from (kept with the prepared run).
#[derive(Clone, Debug)]
pub struct HalvesSource {
    /// The run.
    pub run: Arc<Run>,
    /// Its order-0 identification over the diagnosis's band (inputs, noise model).
    pub identification: Arc<RunIdentification>,
    /// The analysed stretch, samples.
    pub span: Range<usize>,
}

/// Fewest samples a half may hold (below it the halves are not compared).
const MIN_HALF: usize = 2048;

/// The final model `state` of the block `block_index` refitted over `band` on the samples
/// `range` of the run (`None` when its design or fit fails): the halves here, the usable band in
/// `super::usable_band`.
pub(super) fn refit_over(
    source: &HalvesSource,
    block_index: usize,
    state: &State,
    band: [f64; 2],
    range: &Range<usize>,
) -> Option<State> {
    let b = source.identification.blocks.get(block_index)?;
    let (design, _) = super::workflow::block_design(
        &source.run,
        &source.identification.motion.euler,
        b,
        (band, false),
        range,
    )?;
    State::refit(design, &state.fitted.structure, &state.fitted.theta, band)
}

/// The final model of the block `block_index` refitted on each half: `None` when it cannot be.
fn half_states(
    source: &HalvesSource,
    block_index: usize,
    state: &State,
    band: [f64; 2],
) -> Option<[State; 2]> {
    let span = &source.span;
    let mid = span.start + span.len() / 2;
    if mid - span.start < MIN_HALF {
        return None;
    }
    let fit_on = |range: Range<usize>| refit_over(source, block_index, state, band, &range);
    Some([fit_on(span.start..mid)?, fit_on(mid..span.end)?])
}

/// Whether `effect`'s sizes can be compared between halves.
fn comparable(effect: Effect) -> bool {
    !matches!(effect, Effect::VibrationTone | Effect::ClockDrift)
}

/// Compares each finding's sizes between the halves of the record and says in its evidence
/// where they differ. `entries` are the block's findings with their effect and index in
/// `state` (the final model), `input_names` the block's inputs.
pub fn compare_halves(
    source: &HalvesSource,
    block_index: usize,
    state: &State,
    band: [f64; 2],
    input_names: [&str; 3],
    entries: &mut [(Effect, usize, Finding)],
) {
    let in_band_tone = state.tones.iter().any(|t| !t.upper);
    if in_band_tone || state.clock_drift.is_some() || !entries.iter().any(|(e, _, _)| comparable(*e)) {
        return;
    }
    let Some(halves) = half_states(source, block_index, state, band) else {
        return;
    };
    let covs = halves.each_ref().map(|h| {
        let dof = 3.0 * h.design.dof_per_channel();
        covariance(h, band, h.fitted.chi2() / dof)
    });
    for (effect, index, finding) in entries.iter_mut().filter(|(e, _, _)| comparable(*e)) {
        let on = |k: usize| {
            let mut f = finding.clone();
            f.parameters = parameters(*effect, &halves[k], *index, input_names);
            f.parameter_std = parameter_std(*effect, &halves[k], *index, covs[k].as_ref());
            f
        };
        let (first, second) = (on(0), on(1));
        let compared = sizes_and_shapes(&first, &second);
        if let Some((s, z)) = most_different(&compared) {
            let pm = |sd: Option<f64>| sd.map_or_else(String::new, |v| format!(" ± {v:.2e}"));
            let _ = write!(
                finding.evidence,
                "; its size differs between the record's halves ({} {:.3e}{} in the first, {:.3e}{} in the \
                 second, {z:.1} standard deviations apart): not one fixed property of the block over this run",
                s.name,
                s.a,
                pm(s.a_std),
                s.b,
                pm(s.b_std)
            );
        }
        // The halves' combination against the whole record's size: a stable effect gives the
        // same size from every stretch (the Hann tapers weigh time differently, so the two
        // are compared as if independent: a conservative test).
        if let Some((s, z)) = most_different(&against_whole(finding, &compared)) {
            let _ = write!(
                finding.evidence,
                "; the halves do not reproduce the whole record's size ({} {:.3e} from the whole, {:.3e} ± {:.2e} \
                 from the halves combined, {z:.1} standard deviations apart): not one fixed property of the block \
                 over this run",
                s.name,
                s.a,
                s.b,
                s.b_std.unwrap_or(f64::NAN)
            );
        }
        finding.halves = Some(json!([
            {"parameters": first.parameters, "parameter_std": first.parameter_std},
            {"parameters": second.parameters, "parameter_std": second.parameter_std},
        ]));
    }
}

/// Each figure of `finding` (the whole record's) against the inverse-variance combination of
/// the halves' (`halves`, as [`sizes`] compared them): `a` the whole's, `b` the combination's.
fn against_whole(finding: &Finding, halves: &[SizeDelta]) -> Vec<SizeDelta> {
    let mut whole = finding_figures(finding);
    whole.extend(shape_figures(finding));
    halves
        .iter()
        .filter_map(|h| {
            let (wa, ws) = whole
                .iter()
                .find(|(n, _, _)| *n == h.name)
                .map(|(_, v, s)| (*v, *s))?;
            let (sa, sb) = (h.a_std?, h.b_std?);
            let (ia, ib) = (sa.powi(-2), sb.powi(-2));
            let b = (h.a * ia + h.b * ib) / (ia + ib);
            let b_std = (ia + ib).sqrt().recip();
            Some(SizeDelta {
                name: h.name.clone(),
                a: wa,
                b,
                a_std: ws,
                b_std: Some(b_std),
                delta: Delta::new(wa, ws, b, Some(b_std)),
            })
        })
        .collect()
}
