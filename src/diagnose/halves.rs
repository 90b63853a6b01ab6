//! Is a finding one property of the block over the run? Each half of the analysed stretch is
//! fitted on its own with the final model's structure (every finding of the block in it), and
//! each finding's sizes on the two halves are compared figure by figure, as runs are compared
//! (`compare::findings`: beyond [`crate::compare::SIGNIFICANCE_SIGMAS`] combined standard
//! deviations, each half's from its own fit, sandwich included). A sensor effect is the same in
//! both halves; a misfit of the effect's form that the motion or the reference makes (a rate-shaped
//! misfit the search calls a quadratic scale factor, on a real recording) need not be, and the
//! finding's evidence then says so. The halves' figures are kept in the finding (`halves`).
//! Where the halves agree, the record's quarters are fitted too, and a figure whose quarters'
//! sizes are not one size (their homogeneity `chi2`, 3 degrees of freedom, beyond the same
//! 0.27 % tail as the halves' three standard deviations) is said the same way: a size that
//! comes and goes within each half escapes the halves.
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
use crate::compare::findings::{SizeDelta, figures as finding_figures, most_different, sizes};
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

/// The final model of the block `block_index` refitted on each of `pieces` equal pieces of the
/// analysed stretch: `None` when a piece is shorter than [`MIN_HALF`] or cannot be fitted.
fn piece_states(
    source: &HalvesSource,
    block_index: usize,
    state: &State,
    band: [f64; 2],
    pieces: usize,
) -> Option<Vec<State>> {
    let span = &source.span;
    let len = span.len() / pieces;
    if len < MIN_HALF {
        return None;
    }
    let b = source.identification.blocks.get(block_index)?;
    let fit_on = |range: Range<usize>| {
        let (design, _) =
            super::workflow::block_design(&source.run, &source.identification.motion.euler, b, band, &range)?;
        State::refit(design, &state.fitted.structure, &state.fitted.theta, band)
    };
    (0..pieces)
        .map(|k| {
            let start = span.start + k * len;
            let end = if k + 1 == pieces { span.end } else { start + len };
            fit_on(start..end)
        })
        .collect()
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
    let Some(halves) = piece_states(source, block_index, state, band, 2) else {
        return;
    };
    let quarters = Pieces::of(piece_states(source, block_index, state, band, QUARTERS), band);
    let halves = Pieces::of(Some(halves), band);
    for (effect, index, finding) in entries.iter_mut().filter(|(e, _, _)| comparable(*e)) {
        let on = |k: usize| halves.finding(k, finding, *effect, *index, input_names);
        let (first, second) = (on(0), on(1));
        let said = finding.evidence.len();
        let compared = sizes(&first, &second);
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
        if finding.evidence.len() == said
            && let Some(words) = quarters_differ(&quarters, finding, *effect, *index, input_names)
        {
            finding.evidence.push_str(&words);
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
    let whole = finding_figures(finding);
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

/// Pieces of the record the quarters' check cuts it into.
const QUARTERS: usize = 4;

/// `chi2` with `QUARTERS - 1` degrees of freedom beyond which the quarters' sizes of one figure
/// are not one size: the tail of [`crate::compare::SIGNIFICANCE_SIGMAS`] two-sided, 0.27 %
/// (`scipy.stats.chi2.isf(erfc(3 / sqrt(2)), 3)` = 14.16).
const QUARTERS_CHI2: f64 = 14.16;

/// States refitted on pieces of the record, with their covariances.
struct Pieces(Vec<(State, Option<super::uncertainty::Covariance>)>);

impl Pieces {
    fn of(states: Option<Vec<State>>, band: [f64; 2]) -> Self {
        Self(
            states
                .unwrap_or_default()
                .into_iter()
                .map(|h| {
                    let dof = 3.0 * h.design.dof_per_channel();
                    let cov = covariance(&h, band, h.fitted.chi2() / dof);
                    (h, cov)
                })
                .collect(),
        )
    }

    /// `finding` with its sizes from piece `k`.
    fn finding(
        &self,
        k: usize,
        finding: &Finding,
        effect: Effect,
        index: usize,
        inputs: [&str; 3],
    ) -> Finding {
        let (state, cov) = &self.0[k];
        let mut f = finding.clone();
        f.parameters = parameters(effect, state, index, inputs);
        f.parameter_std = parameter_std(effect, state, index, cov.as_ref());
        f
    }
}

/// The quarters' check: where the halves agree, a size that drifts or comes and goes within
/// them can still be no one size (on a real recording with finger taps, a quadratic scale
/// factor of 0.050 ± 0.012 in the first quarter and none in the last two, its halves within 2
/// standard deviations). Per figure, the inverse-variance homogeneity `chi2` of the quarters'
/// sizes, beyond [`QUARTERS_CHI2`] for the largest, gives the words said; `None` when the
/// quarters could not be fitted or every figure agrees.
fn quarters_differ(
    quarters: &Pieces,
    finding: &Finding,
    effect: Effect,
    index: usize,
    inputs: [&str; 3],
) -> Option<String> {
    if quarters.0.len() != QUARTERS {
        return None;
    }
    let each: Vec<Vec<(String, f64, Option<f64>)>> = (0..QUARTERS)
        .map(|k| finding_figures(&quarters.finding(k, finding, effect, index, inputs)))
        .collect();
    let (name, chi2, sizes) = each[0]
        .iter()
        .filter_map(|(name, _, _)| {
            let sizes: Vec<(f64, f64)> = each
                .iter()
                .map(|q| {
                    q.iter()
                        .find(|(n, _, _)| n == name)
                        .and_then(|(_, v, sd)| Some((*v, (*sd)?)))
                })
                .collect::<Option<_>>()?;
            Some((name.clone(), homogeneity_chi2(&sizes), sizes))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (chi2 > QUARTERS_CHI2).then(|| {
        let listed: Vec<String> = sizes
            .iter()
            .map(|(v, sd)| format!("{v:.3e} ± {sd:.2e}"))
            .collect();
        format!(
            "; its size differs between the record's quarters ({name} {}; chi2 {chi2:.1} for {} degrees of \
             freedom): not one fixed property of the block over this run",
            listed.join(", "),
            QUARTERS - 1
        )
    })
}

/// `sum ((v - mean) / sd)^2` about the inverse-variance mean of `(value, sd)` pairs.
fn homogeneity_chi2(sizes: &[(f64, f64)]) -> f64 {
    let w: f64 = sizes.iter().map(|(_, sd)| sd.powi(-2)).sum();
    let mean = sizes.iter().map(|(v, sd)| v * sd.powi(-2)).sum::<f64>() / w;
    sizes.iter().map(|(v, sd)| ((v - mean) / sd).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use super::homogeneity_chi2;

    #[test]
    fn the_homogeneity_chi2_is_that_of_the_weighted_mean() {
        // Equal deviations: the mean is the plain one, chi2 the sum of squares about it.
        let equal = [(1.0, 0.5), (2.0, 0.5), (3.0, 0.5), (6.0, 0.5)];
        assert!((homogeneity_chi2(&equal) - 14.0 / 0.25).abs() < 1e-12);
        // Unequal: weighted mean (1/1 * 0 + 1/4 * 5) / (1 + 1/4) = 1; chi2 1 + 16/4 = 5.
        let unequal = [(0.0, 1.0), (5.0, 2.0)];
        assert!((homogeneity_chi2(&unequal) - 5.0).abs() < 1e-12);
        // One size: no spread.
        assert!(homogeneity_chi2(&[(3.0, 0.1); 4]).abs() < 1e-12);
    }
}
