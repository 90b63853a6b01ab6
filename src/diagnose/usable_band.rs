//! Where a finding's size is fitted: over the usable band. The search covers the whole band
//! asked for (0.1-40 Hz with `band_hz: "auto"`), beyond the usable band where the outputs are
//! coherent with the inputs from the angles (`ident::band`): a missing effect lowers the
//! coherence, and the usable band would hide the misfit looked for. But above the usable band the
//! inputs are not all the motion (the angles' noise, or a reference that carries less of the
//! motion than there is: a band limit), and a size fitted there leans on that. Measured on the
//! last campaign's runs (29 Nov, 120 s, the hidden lag's truth against the finding): beside
//! 0.1 mrad coloured angle noise the lag's time constant read more than 2 of its standard
//! deviations long on 6 of 8 runs over the band searched (up to 5.3), and -0.5 to +0.9 over the
//! usable band (11.5-15.1 Hz); on `--stand real` (a 30 Hz zero-phase band limit of the angles)
//! 4.1-6.1 deviations short, and 0.8-4.6 short over the usable band (26.4-28.7 Hz, where the limit already takes 5-13 % of the
//! motion: a zero-phase band limit leaves the coherence whole). An accepted effect is fitted over
//! the identifier's band (`super::extend`), within the usable band, too.
//!
//! So where the usable band is narrower than the band searched, the final model (every finding
//! of the block in it) is refitted there and each finding's sizes and deviations are that fit's;
//! the band searched's figures are kept in the finding (`search_band`; a second-order lag's
//! damping compared beside its `T`, `compare::findings::shape_figures`). Where the two differ
//! beyond [`crate::compare::SIGNIFICANCE_SIGMAS`] combined deviations (the fits share the usable
//! band's bins, so treating them as independent is conservative), the evidence says the size
//! depends on the band above it and is not certifiable as it stands. A finding whose size the
//! usable band does not determine (a false lag beside strong coloured noise read 0.0005 ms there,
//! with no deviation) keeps the band searched's size, and its evidence says it rests on the band
//! above; where the usable band's fit has no deviations at all (a figure at its bound), every
//! finding keeps the band searched's size and the one at its bound is said to rest on the band
//! above. The halves check (`super::halves`) is made before, over the band searched where the
//! finding was found (over the usable band the tapping recording's rate-shaped misfit, read as a
//! quadratic scale factor, reproduced between halves, which over the band searched it does not).
//!
//! Not applied (the band searched's sizes kept, nothing said) where the band is given
//! (`band_hz` fixed: the user's band is the band the sizes are fitted over), where the usable band
//! is the band searched (within 3 %), for a block with no finding but tones, for a block whose
//! model holds a tone in its band or a clock correction (fitted on the whole record's bins) or a
//! resonance outside the usable band or moved to its edge by the refit (its frequency would be
//! pinned there), and where the usable band is too short for a design or its fit fails. Units as
//! the findings' parameters; no figure is NaN except a missing one's value in the words.

use std::fmt::Write as _;

use serde_json::json;

use super::halves::{HalvesSource, refit_over};
use super::report::{Finding, parameters};
use super::state::State;
use super::uncertainty::{covariance, parameter_std};
use crate::compare::findings::{figures, most_different, sizes_and_shapes};
use crate::effect::Effect;

/// How far below the band searched the usable band's top must lie for the sizes to be fitted
/// over it, relative: a top closer than this moves a size by less than its deviation.
const NARROWER: f64 = 0.03;

/// The usable band to compare on, if it is narrower than `searched` at the top: its bottom no
/// lower than the search's.
#[must_use]
pub fn compared_band(usable: [f64; 2], searched: [f64; 2]) -> Option<[f64; 2]> {
    let band = [usable[0].max(searched[0]), usable[1].min(searched[1])];
    (band[1] < searched[1] * (1.0 - NARROWER) && band[1] > band[0]).then_some(band)
}

/// Whether every resonance of `state` lies inside `band`, away from its edges by the search's
/// margin ([`super::rules::inside_edges`]: a mode at an edge is pinned there by the fit).
fn modes_inside(state: &State, band: [f64; 2]) -> bool {
    state
        .fitted
        .theta
        .resonances
        .iter()
        .all(|&(f, _)| super::rules::inside_edges(f, band))
}

/// Whether the block's findings can be sized over `usable`: no tone in the band and no clock
/// correction (fitted on the whole record's bins), every resonance inside it.
#[must_use]
pub fn applies(state: &State, usable: [f64; 2]) -> bool {
    modes_inside(state, usable) && state.clock_drift.is_none() && !state.tones.iter().any(|t| !t.upper)
}

/// A figure of `effect` that the fit over the usable band left at the bound of its range (a
/// lag's time constant at zero, a mode's damping at its floor), with its value there: the
/// model then has no deviations over that band, and the finding rests on the band above.
fn at_bound(effect: Effect, there: &serde_json::Value) -> Option<(String, f64)> {
    let (key, floor) = match effect {
        Effect::SensorLag | Effect::ReferenceLag | Effect::ReferenceBandLimit => ("T_s", MIN_LAG_S),
        Effect::PlatformResonance => ("damping", MIN_DAMPING),
        _ => return None,
    };
    let value = there.get(key)?.as_f64()?;
    (value <= floor).then(|| (key.to_owned(), value))
}

/// A lag's time constant at or below which it is at its bound (zero), s: a thousandth of the
/// shortest lag the catalogue simulates (1 ms).
const MIN_LAG_S: f64 = 1e-6;
/// A damping at or below which it is at the fit's floor (0.005, `fit.rs`), with a margin for
/// the search's last step.
const MIN_DAMPING: f64 = 0.0051;

/// Refits the final model (`state`, fitted over `searched`) over `usable` and makes each
/// finding's sizes and deviations that fit's (tones above the band keep theirs), keeping the
/// band searched's in `search_band`; says in the evidence where they differ. A finding whose
/// size the usable band does not determine (a figure with a deviation over the band searched
/// has none there: a lag's time constant at zero) keeps the band searched's, and its evidence
/// says it rests on the band above. `entries` are the
/// block's findings with their effect and index in `state`, `input_names` the block's inputs.
/// Nothing changes where the usable band's design or fit fails.
pub fn size_over_usable_band(
    source: &HalvesSource,
    block_index: usize,
    (state, searched): (&State, [f64; 2]),
    usable: [f64; 2],
    input_names: [&str; 3],
    entries: &mut [(Effect, usize, Finding)],
) {
    if entries.iter().all(|(e, _, _)| *e == Effect::VibrationTone) {
        return;
    }
    let Some(refit) = refit_over(source, block_index, state, usable, &source.span)
        .filter(|refit| modes_inside(refit, usable))
    else {
        return;
    };
    let dof = 3.0 * refit.design.dof_per_channel();
    let Some(cov) = covariance(&refit, usable, refit.fitted.chi2() / dof) else {
        // No deviations over the usable band: the sizes stay the band searched's, and a
        // finding at its bound there is said to rest on the band above.
        for (effect, index, finding) in entries.iter_mut() {
            let there = parameters(*effect, &refit, *index, input_names);
            if let Some((name, value)) = at_bound(*effect, &there) {
                rests_on_band_above(finding, usable, &name, value);
            }
        }
        return;
    };
    for (effect, index, finding) in entries.iter_mut().filter(|(e, _, _)| *e != Effect::VibrationTone) {
        let mut there = finding.clone();
        there.parameters = parameters(*effect, &refit, *index, input_names);
        there.parameter_std = parameter_std(*effect, &refit, *index, Some(&cov));
        if let Some((name, value)) = undetermined(finding, &there) {
            rests_on_band_above(finding, usable, &name, value);
            continue;
        }
        let _ = write!(
            finding.evidence,
            "; its size is fitted over the usable band {:.2}-{:.2} Hz, where the outputs are coherent with the \
             inputs (as an accepted effect is)",
            usable[0], usable[1]
        );
        if let Some((s, z)) = most_different(&sizes_and_shapes(finding, &there)) {
            let pm = |sd: Option<f64>| sd.map_or_else(String::new, |v| format!(" ± {v:.2e}"));
            let _ = write!(
                finding.evidence,
                "; over the whole band searched it reads {} {:.3e}{} against {:.3e}{} here, {z:.1} standard \
                 deviations apart: the size depends on the band above (the angles' noise, or a reference's band \
                 limit, which may reach into the usable band's top too), not certifiable as it stands (a band_hz \
                 ending lower shows where it settles)",
                s.name,
                s.a,
                pm(s.a_std),
                s.b,
                pm(s.b_std)
            );
        }
        finding.search_band = Some(json!({
            "band_hz": searched,
            "parameters": finding.parameters,
            "parameter_std": finding.parameter_std,
        }));
        finding.parameters = there.parameters;
        finding.parameter_std = there.parameter_std;
    }
}

/// Says in `finding`'s evidence that over `usable` its size is not determined (`name` reads
/// `value` there): it rests on the band above.
fn rests_on_band_above(finding: &mut Finding, usable: [f64; 2], name: &str, value: f64) {
    let _ = write!(
        finding.evidence,
        "; over the usable band {:.2}-{:.2} Hz, where the outputs are coherent with the inputs, its size is not \
         determined ({name} {value:.3e}, at its bound or without a deviation): the finding rests on the band above, \
         where the inputs are not all the motion (the angles' noise, or a reference's band limit)",
        usable[0], usable[1]
    );
}

/// The first figure of `searched` with a deviation that `there` gives none (or lacks), with its
/// value there (`NaN` where it lacks it).
fn undetermined(searched: &Finding, there: &Finding) -> Option<(String, f64)> {
    let there = figures(there);
    figures(searched)
        .into_iter()
        .filter(|(_, _, sd)| sd.is_some())
        .find_map(|(name, _, _)| match there.iter().find(|(n, _, _)| *n == name) {
            Some((_, _, Some(_))) => None,
            Some((_, value, None)) => Some((name, *value)),
            None => Some((name, f64::NAN)),
        })
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::{at_bound, compared_band, rests_on_band_above, undetermined};
    use crate::block::Block;
    use crate::diagnose::Finding;
    use crate::effect::Effect;

    fn lag(t_s: f64, t_std: Option<f64>) -> Finding {
        Finding::sized(
            Block::Accel,
            Effect::SensorLag,
            json!({ "T_s": t_s }),
            json!({ "T_s": t_std }),
        )
    }

    /// A lag's time constant at zero or a damping at its floor over the usable band is at its
    /// bound; a figure with a deviation over the band searched and none there is undetermined;
    /// either way the evidence says the finding rests on the band above.
    #[test]
    fn a_size_at_its_bound_or_without_a_deviation_rests_on_the_band_above() {
        let at = |effect, there| at_bound(effect, &there);
        assert_eq!(
            at(Effect::SensorLag, json!({"T_s": 5e-7})),
            Some(("T_s".to_owned(), 5e-7))
        );
        assert_eq!(
            at(Effect::ReferenceLag, json!({"T_s": 0.0})),
            Some(("T_s".to_owned(), 0.0))
        );
        assert_eq!(at(Effect::SensorLag, json!({"T_s": 2e-3})), None);
        assert_eq!(
            at(
                Effect::PlatformResonance,
                json!({"damping": 0.005, "frequency_hz": 30.0})
            ),
            Some(("damping".to_owned(), 0.005))
        );
        assert_eq!(at(Effect::PlatformResonance, json!({"damping": 0.05})), None);
        // Not a figure with a bound.
        assert_eq!(
            at(Effect::LeverArmError, json!({"offset_m": [0.0, 0.0, 0.0]})),
            None
        );

        let searched = lag(1.9e-3, Some(2e-4));
        assert_eq!(undetermined(&searched, &lag(1.7e-3, Some(3e-4))), None);
        assert_eq!(
            undetermined(&searched, &lag(1e-7, None)),
            Some(("T_s".to_owned(), 1e-7))
        );
        // A figure without a deviation over the band searched asks nothing of the usable band.
        assert_eq!(undetermined(&lag(1.9e-3, None), &lag(1e-7, None)), None);

        let mut finding = searched;
        rests_on_band_above(&mut finding, [0.12, 4.15], "T_s", 1e-7);
        assert!(
            finding
                .evidence
                .starts_with("; over the usable band 0.12-4.15 Hz")
                && finding.evidence.contains("T_s 1.000e-7")
                && finding.evidence.contains("the finding rests on the band above"),
            "{}",
            finding.evidence
        );
    }

    #[test]
    fn only_a_usable_band_narrower_at_the_top_is_compared() {
        assert_eq!(compared_band([0.12, 26.6], [0.1, 40.0]), Some([0.12, 26.6]));
        assert_eq!(compared_band([0.05, 20.0], [0.1, 40.0]), Some([0.1, 20.0]));
        // Within the margin, or the search's own band ended at the usable band's top.
        assert_eq!(compared_band([0.12, 39.5], [0.1, 40.0]), None);
        assert_eq!(compared_band([0.12, 11.2], [0.1, 11.2]), None);
        // A usable band above the band searched leaves nothing.
        assert_eq!(compared_band([12.0, 30.0], [0.1, 11.0]), None);
    }
}
