//! The missing-effect report (contract section 5, schema `imu-attest/discrepancy/1`), with the
//! contract's fields first and this program's extensions after them: the criterion, and per
//! block the model before and after, every candidate's evidence in the first round, the
//! disagreement maps and residual densities before and after.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::map::{DisagreementMap, ResidualPsd};
use super::state::State;
use super::structure::{LagShape, Theta};
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::selfcheck::POOR_FIT;
use crate::ident::settings::Settings;
use crate::model::{RefusedBlock, Source};

/// The report's schema name.
pub const DISCREPANCY_SCHEMA: &str = "imu-attest/discrepancy/1";

/// The overall verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// At least one effect is significant.
    EffectFound,
    /// Nothing significant is left by the paper's model.
    NoMissingEffect,
}

/// The whole report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// [`DISCREPANCY_SCHEMA`].
    pub schema: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Named effects, most important (largest criterion gain) first.
    pub findings: Vec<Finding>,
    /// The run.
    pub source: Source,
    /// The identifier settings used (order forced to 0: effects extend `K e^(-tau s)`), the band
    /// as asked (each block's band searched is its `band_hz`).
    pub settings: Settings,
    /// How significance is decided.
    pub criterion: Criterion,
    /// Per block details.
    pub blocks: BTreeMap<String, BlockReport>,
    /// The run's blocks the identification refused beside the others (`Model::refused_blocks`):
    /// not diagnosed, the verdict is the other blocks'. Absent when every block was diagnosed.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub refused_blocks: BTreeMap<String, RefusedBlock>,
    /// Faults of the recording itself (`crate::faults::detect`, as in the model file): a finding
    /// on a channel they spoil may be theirs (held samples read as a skew or a lag, clipping as
    /// a nonlinearity). Absent when none was found.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub recording_faults: Vec<crate::faults::RecordingFault>,
}

impl Report {
    /// What the model with the findings still leaves unexplained, per block, in words: where its
    /// chi2/dof after the findings stays above the identifier's [`POOR_FIT`], the disagreement is
    /// mostly not one of the catalogue's effects, and any finding there is a partial fit of it
    /// whose size cannot be certified (angles measured through a 20 Hz filter, before the stand's
    /// band limit was a candidate or with it rejected: chi2/dof 5.1-5.3 after five findings that
    /// were none of the run's; 55-62 on an independent simulator's run after ten). One sentence per block, naming it; empty when every block is explained; the
    /// real recordings leave 1.13-1.44.
    #[must_use]
    pub fn unexplained(&self) -> Vec<String> {
        self.blocks
            .iter()
            .filter(|(_, b)| b.chi2_per_dof[1] > POOR_FIT || b.chi2_per_dof[1].is_nan())
            .map(|(name, b)| {
                let named = self.findings.iter().filter(|f| f.block.name() == name).count();
                let [before, after] = b.chi2_per_dof;
                if named == 0 {
                    format!(
                        "{name}: the paper's model leaves chi2/dof {after:.2} and no effect of the \
                         catalogue explains it: the disagreement is something else (the \
                         identifier's warnings and the disturbance density say where)"
                    )
                } else {
                    format!(
                        "{name}: with its {named} finding(s) the model still leaves chi2/dof \
                         {after:.2} ({before:.2} before them): most of the disagreement is not an \
                         effect of the catalogue, and the findings may be partial fits of it, their \
                         sizes not certifiable (the identifier's warnings and the disturbance \
                         density say where)"
                    )
                }
            })
            .collect()
    }

    /// The significant candidates a block's search did not name, in words, and whether that is
    /// a warning (refused evidence stronger than every finding named there: [`super::not_named`]);
    /// `None` where none was refused or the block is not in the report.
    #[must_use]
    pub fn not_named_words(&self, block_name: &str) -> Option<(String, bool)> {
        let b = self.blocks.get(block_name)?;
        let block = crate::block::Block::from_name(block_name)?;
        let words = super::not_named::words(&b.not_named, block_name, b.band_hz)?;
        let weakest = self
            .findings
            .iter()
            .filter(|f| f.block == block)
            .map(|f| f.criterion_gain)
            .reduce(f64::min);
        Some((words, super::not_named::is_warning(&b.not_named, weakest)))
    }

    /// What the verdict covers where a block's band was ended, as said after it:
    /// `" (gyro only up to 11.16 Hz; ...: the inputs above are not the motion)"`; empty when every
    /// band is the one asked for ([`Self::ended_bands`]).
    #[must_use]
    pub fn verdict_scope(&self) -> String {
        let ended = self.ended_bands();
        if ended.is_empty() {
            ended
        } else {
            format!(" ({ended}: the inputs above are not the motion)")
        }
    }

    /// Where a block's band was ended below the band asked for (its inputs not the motion
    /// above: [`super::input_limit`]), `"gyro only up to 11.16 Hz"`, joined, with the other
    /// blocks' bands said whole: what the verdict covers. Empty when every band is the one asked
    /// for.
    #[must_use]
    pub fn ended_bands(&self) -> String {
        let ended = |b: &BlockReport| b.input_limit.as_ref().is_some_and(|l| l.band_ended);
        let mut parts: Vec<String> = self
            .blocks
            .iter()
            .filter(|(_, b)| ended(b))
            .map(|(name, b)| format!("{name} only up to {:.2} Hz", b.band_hz[1]))
            .collect();
        if parts.is_empty() {
            return String::new();
        }
        if self.blocks.values().any(|b| !ended(b)) {
            parts.push("the other blocks over their whole band".to_owned());
        }
        parts.join("; ")
    }
}

/// The decision rule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Criterion {
    /// `"BIC"`.
    pub name: String,
    /// What an added real parameter must buy in `chi2`: `ln(n)`.
    pub penalty_per_parameter: f64,
    /// What winning a round among `m` candidates costs on top: `2 ln(m)`.
    pub look_elsewhere: String,
}

/// One named effect.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// The block (`gyro` or `accel` in JSON).
    pub block: Block,
    /// The catalogue entry (its id in JSON).
    pub effect: Effect,
    /// Readable name.
    pub name: String,
    /// Estimated size, re-identified with every finding of the block in the model.
    pub parameters: Value,
    /// The standard deviations of `parameters`' figures, under the same keys (`null` where the
    /// data do not determine one; `diagnose::uncertainty`).
    #[serde(default, skip_serializing_if = "Value::is_null")]
    pub parameter_std: Value,
    /// Worst channel's gap before adding it, dB.
    pub gap_before_db: f64,
    /// Worst channel's gap after, dB.
    pub gap_after_db: f64,
    /// The evidence in words.
    pub evidence: String,
    /// Reduction of `chi2`.
    pub delta_chi2: f64,
    /// Real parameters added.
    pub added_parameters: usize,
    /// `delta_chi2 - added_parameters ln(n) - 2 ln(m)`: positive means significant.
    pub criterion_gain: f64,
    /// The sizes fitted on each half of the analysed stretch over the band searched,
    /// `[{parameters, parameter_std}, ..]` (`halves.rs`; absent where the halves are not
    /// compared; beside `search_band`'s sizes where the finding's are the usable band's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub halves: Option<Value>,
    /// Where the sizes above are fitted over the usable band (narrower than the band searched),
    /// the band searched's: `{band_hz, parameters, parameter_std}` (`usable_band.rs`; absent
    /// where the sizes are the band searched's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_band: Option<Value>,
}

#[cfg(test)]
impl Finding {
    /// A finding of `effect` on `block` with these sizes and nothing else said, for the
    /// diagnosis's module tests.
    pub(crate) fn sized(block: Block, effect: Effect, parameters: Value, parameter_std: Value) -> Self {
        Self {
            block,
            effect,
            name: effect.name_on(block),
            parameters,
            parameter_std,
            gap_before_db: -20.0,
            gap_after_db: -30.0,
            evidence: String::new(),
            delta_chi2: 100.0,
            added_parameters: 1,
            criterion_gain: 80.0,
            halves: None,
            search_band: None,
        }
    }
}

/// A candidate's evidence in one round.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateSummary {
    /// The catalogue entry (its id in JSON).
    pub effect: Effect,
    /// Reduction of `chi2`.
    pub delta_chi2: f64,
    /// Real parameters added.
    pub added_parameters: usize,
    /// `delta_chi2 - added_parameters ln(n) - 2 ln(m)`.
    pub criterion_gain: f64,
    /// A band limit's shape (`reference_band_limit` is tried in several, each a candidate of
    /// its own); absent for the other effects.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band_limit: Option<crate::model::band_limit::BandLimitShape>,
    /// A lag's shape (`sensor_lag` is tried first and second order, each a candidate of its
    /// own); absent for the other effects.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lag_shape: Option<LagShape>,
}

/// One block's details.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockReport {
    /// Static gain of the paper's model alone.
    #[serde(rename = "K_base")]
    pub k_base: [[f64; 3]; 3],
    /// Its delay, s.
    pub tau_base_s: f64,
    /// Static gain with every finding in the model.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Its delay, s.
    pub tau_s: f64,
    /// `chi2` per degree of freedom before and after (near 1 when the model explains the data).
    pub chi2_per_dof: [f64; 2],
    /// Per-channel gap before and after, dB.
    pub gap_db: [[f64; 3]; 2],
    /// First round's candidates, best first.
    pub candidates: Vec<CandidateSummary>,
    /// Disagreement before and after.
    pub map: [DisagreementMap; 2],
    /// Residual densities before and after.
    pub residual_psd: [ResidualPsd; 2],
    /// The disturbance density the model expects.
    pub expected_psd: ResidualPsd,
    /// The band searched, Hz.
    #[serde(default)]
    pub band_hz: [f64; 2],
    /// Where the inputs from the angles are not the motion, at the top of the band asked for
    /// (the band then ended below it, or the user's band kept: [`super::input_limit`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_limit: Option<super::input_limit::InputLimit>,
    /// Where the inputs may not be the motion up to the band's top (the angles mostly their
    /// noise, or the block's outputs no longer coherent with its inputs), and the smooth effects
    /// the band below did not confirm (not named) or could not (named, said)
    /// ([`super::noisy_angles`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noisy_angles: Option<super::noisy_angles::NoisyAngles>,
    /// Significant candidates not named, and why ([`super::not_named`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_named: Vec<super::not_named::NotNamed>,
    /// A step of the delay through the record (the streams slipped: [`crate::ident::delay_step`]);
    /// no clock drift was searched, and the findings are of both sides of it mixed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay_step: Option<crate::ident::delay_step::DelayStep>,
    /// Per-channel gap of the model given with `--model`, as it is (no refit), dB.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub given_model_gap_db: Option<[f64; 3]>,
    /// What the tone search could have seen: per frequency and channel, the amplitude a constant
    /// tone needs to be named ([`super::tone_limit`]; absent where no tone was searched).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tone_limit: Option<super::tone_limit::ToneLimit>,
    /// What the search could have seen of the effects with linear sizes it did not name: the
    /// size each needs to be named ([`super::size_limit`]; absent where none is stated).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub size_limits: Vec<super::size_limit::SizeLimit>,
}

/// The static gain `K` of a state.
#[must_use]
pub fn gain(state: &State) -> [[f64; 3]; 3] {
    gain_of_beta(&state.fitted.profile.beta)
}

/// `K` from a fitted profile's linear parameters (its first nine, row by row).
#[must_use]
pub fn gain_of_beta(beta: &[f64]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| beta[3 * i + j]))
}

fn slice3(beta: &[f64], at: Option<usize>) -> [f64; 3] {
    at.map_or([0.0; 3], |p| [beta[p], beta[p + 1], beta[p + 2]])
}

/// The estimated size of `effect` in `state` (for a resonance, the one on `axis`; for a tone,
/// tone number `index`).
#[must_use]
pub fn parameters(effect: Effect, state: &State, index: usize, input_names: [&str; 3]) -> Value {
    let f = &state.fitted;
    let b = &f.profile.beta;
    let theta: &Theta = &f.theta;
    match effect {
        Effect::GSensitivity => {
            let g = f
                .layout
                .g
                .map_or([[0.0; 3]; 3], |p| [0, 1, 2].map(|i| slice3(b, Some(p + 3 * i))));
            json!({"G": g, "units": "output units per m/s^2"})
        }
        Effect::SensorLag | Effect::ReferenceLag => match f.structure.lag {
            Some(shape @ LagShape::SecondOrder) => {
                let mut v = json!({
                    "T_s": theta.lag_s,
                    "damping": theta.lag_damping,
                    "shape": shape.name(),
                });
                // No frequencies at T = 0 (a report holds no null outside deviations).
                if theta.lag_s > 0.0 {
                    let natural = 1.0 / (2.0 * std::f64::consts::PI * theta.lag_s);
                    v["natural_frequency_hz"] = json!(natural);
                    v["corner_hz"] = json!(natural * LagShape::corner_ratio(theta.lag_damping));
                }
                v
            }
            _ => json!({"T_s": theta.lag_s}),
        },
        Effect::ReferenceBandLimit => {
            let top = state.design.frequency_hz.last().copied().unwrap_or(0.0);
            let Some(shape) = f.structure.band_limit else {
                return Value::Null;
            };
            let t = theta.band_limit_t_s;
            let mut p = json!({
                "T_s": t,
                "shape": shape.name(),
                "causal": shape.causal(),
                "band_top_hz": top,
                "gain_rise_at_band_top": shape.rise_at(t, top),
            });
            // Present only where they exist (a report holds no null outside deviations): the
            // corner (none at T = 0), the Butterworth order (none for the interpolated shape),
            // the interpolated shape's reference rate 1 / T.
            if let Some(c) = shape.corner_hz(t) {
                p["corner_hz"] = json!(c);
            }
            if let Some(m) = shape.order() {
                p["order"] = json!(m);
            }
            if let Some(r) = shape.reference_rate_hz(t) {
                p["reference_rate_hz"] = json!(r);
            }
            p
        }
        Effect::AxisTimeSkew => {
            let skew = theta.channel_skew_s();
            json!({"channel_delay_s": skew.map(|d| theta.tau_s + d), "skew_s": skew})
        }
        Effect::ScaleNonlinearity => json!({"k2": slice3(b, f.layout.k2)}),
        Effect::LeverArmError => json!({"offset_m": slice3(b, f.layout.lever_arm)}),
        Effect::PlatformResonance => {
            let axis = f.structure.resonance_axes.get(index).copied().unwrap_or(0);
            let (frequency_hz, damping) = theta.resonances.get(index).copied().unwrap_or((0.0, 0.0));
            json!({"axis": input_names[axis], "axis_index": axis, "frequency_hz": frequency_hz, "damping": damping})
        }
        Effect::ClockDrift => {
            let d = state.clock_drift.unwrap_or(0.0);
            let duration = state.design.n_samples as f64 / state.design.sample_rate_hz;
            json!({"drift_ppm": d * 1e6, "delay_change_s": d * duration})
        }
        Effect::VibrationTone => state.tones.get(index).map_or(Value::Null, |t| {
            let duration = state.design.n_samples as f64 / state.design.sample_rate_hz;
            let (on_s, on_fraction) = t
                .gate
                .as_ref()
                .map_or((vec![[0.0, duration]], 1.0), |g| (g.on_s.clone(), g.on_fraction));
            json!({"frequency_hz": t.frequency_hz, "amplitude": t.amplitude(), "on_fraction": on_fraction, "on_s": on_s})
        }),
    }
}
