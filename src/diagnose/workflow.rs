//! The rounds of the search: identify, build each block's design, grow the model effect by
//! effect while the criterion gains, and write the report.

use crate::ident::band::BandSetting;
use crate::ident::stretches::MIN_STRETCHES;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::DiagnoseError;
use super::candidates::{Candidate, Extension, candidates};
use super::design::{Design, DesignSignals};
use super::halves::{HalvesSource, compare_halves};
use super::input_limit::{InputLimit, falling_gain, input_limit};
use super::map::{disagreement_map, power, psd_cells};
use super::report::{
    BlockReport, CandidateSummary, Criterion, DISCREPANCY_SCHEMA, Finding, Report, Verdict, gain, parameters,
};
use super::state::State;
use super::uncertainty::{covariance, parameter_std};
use crate::block::Block;
use crate::effect::Effect;
use crate::ident::identify::{BlockIdentification, resolve_band};
use crate::ident::session::Session;
use crate::ident::settings::{OrderSetting, Settings};
use crate::ident::signals::{block_signals, channel_names};
use crate::model::refused::refused_blocks;
use crate::model::{BlockModel, Model, RefusedBlock, Source};
use crate::run::Run;
use crate::stand::kinematics::EulerSeries;
use std::sync::Arc;

/// Effects a block can carry at most (the search stops earlier when nothing gains).
const MAX_FINDINGS: usize = 5;
/// Log-spaced cells of the residual densities in the report.
const PSD_CELLS: usize = 80;

/// What the caller adds to a diagnosis.
#[derive(Clone, Debug, Default)]
pub struct DiagnoseOptions<'a> {
    /// A model identified before (perhaps from another run): each block's report also holds
    /// the gap it leaves as it is, before anything is refitted.
    pub given: Option<&'a Model>,
    /// Effects the engineer rejected: never offered as candidates on that block.
    pub rejected: Vec<(Block, Effect)>,
}

/// Diagnoses every block of `run` the settings name.
///
/// # Errors
/// The identification's errors (bad settings for this run, ...), a record too short for the
/// band, or degenerate inputs.
pub fn diagnose_run(
    run: &Run,
    settings: &Settings,
    options: &DiagnoseOptions<'_>,
) -> Result<Report, DiagnoseError> {
    diagnose_session(&mut Session::new(Arc::new(run.clone())), settings, options)
}

/// [`diagnose_run`] on a session's run: the observer, spectra and factorisations it holds are
/// used as they are (only the order-0 fit over the diagnosis's band is new), and its own
/// identification is left as it was.
///
/// # Errors
/// As [`diagnose_run`].
pub fn diagnose_session(
    session: &mut Session,
    settings: &Settings,
    options: &DiagnoseOptions<'_>,
) -> Result<Report, DiagnoseError> {
    Ok(diagnose_prepared(&prepare(session, settings)?, options))
}

/// What every diagnosis of a run under one set of settings starts from, computed once: the
/// order-0 identification over the diagnosis's band, each block's whole-record design and the
/// paper's model fitted on it. A rejection (the app) or an accepted effect ([`super::extend`])
/// starts from here again instead of redoing the identification and the record's spectra.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The identifier settings used (order 0, the band fixed, blocks resolved).
    pub settings: Settings,
    /// The run.
    pub source: Source,
    /// One entry per block, in the order of the settings.
    pub blocks: Vec<PreparedBlock>,
    /// The blocks the run cannot identify, beside those it can (not diagnosed).
    pub refused_blocks: BTreeMap<String, RefusedBlock>,
    /// What the record's halves are built from, to tell whether each finding is one property
    /// of the block over the run ([`super::halves`]; `None`: not compared).
    pub halves: Option<HalvesSource>,
}

/// One block's starting point.
#[derive(Clone, Debug)]
pub struct PreparedBlock {
    /// The block.
    pub block: Block,
    /// The diagnosis's band, Hz.
    pub band_hz: [f64; 2],
    /// Where the inputs from the angles are not the motion, at the top of the band asked for
    /// ([`super::input_limit`]).
    pub input_limit: Option<InputLimit>,
    /// A step in the delays of the stretches over the band searched
    /// ([`crate::ident::delay_step`]): the record's streams slipped, and the report says so.
    pub delay_step: Option<crate::ident::delay_step::DelayStep>,
    /// Whether a clock drift is searched: not through a step, unless the slope its two sides
    /// share is a drift.
    pub search_drift: bool,
    /// The paper's model `K e^(-tau s)` fitted on the whole-record design (with the stretches'
    /// delay trend as the clock-drift hint).
    pub base: State,
    /// Real degrees of freedom of the band (all three channels): BIC's `n`.
    pub dof: f64,
}

/// [`Prepared`] for `session`'s run under `settings`.
///
/// # Errors
/// As [`diagnose_run`].
pub fn prepare(session: &mut Session, settings: &Settings) -> Result<Prepared, DiagnoseError> {
    let run = session.run().clone();
    let run = run.as_ref();
    // The diagnosis searches the whole band asked for (with "auto", the auto band's search
    // limits): a missing effect lowers the coherence, so the usable band of the identification
    // would hide the very misfit the diagnosis looks for.
    // Only where the inputs are not the motion does an auto band end below the search limits
    // ([`super::input_limit`]).
    let given = matches!(settings.band_hz, BandSetting::Fixed(_));
    let asked = settings.band_hz;
    let order = settings.order;
    let band_hz = BandSetting::Fixed(settings.band_hz.search_limits(run.sample_rate_hz));
    let settings = Settings {
        order: OrderSetting::Fixed(0).into(),
        band_hz,
        ..settings.for_run(run)
    };
    let id = session.identify_aside(&settings)?;
    let span = session.span(&settings)?;
    let mut blocks = Vec::new();
    let mut refused = refused_blocks(&id.refused);
    let mut first_refusal = id.refused.first().map(|r| r.error.clone());
    for b in &id.blocks {
        let name = b.block.name();
        // The identification's refusal of a block without a usable band (a dead block) holds
        // here too, though the band searched is fixed: the diagnosis of a block the model
        // refused would be of nothing, and a gyro's refuses the run as it does there.
        if !given && let Err(e) = resolve_band(&b.spectra, b.block, BandSetting::Auto) {
            match RefusedBlock::of(&e).filter(|_| e.is_refusal()) {
                Some(entry) => {
                    refused.insert(name.to_owned(), entry);
                    first_refusal.get_or_insert(e);
                    continue;
                }
                None => return Err(e.alone().into()),
            }
        }
        // Only an auto band is ended, and only where the order-0 fit sees the gain fall evenly;
        // then the identifier, its order selection on, tells the inputs' noise from the block's
        // own dynamics (a lag's droop): a user's fixed order above 0 is dynamics as given, and
        // an identification that fails ends nothing.
        let dynamics = !given
            && falling_gain(b).is_some()
            && match order.of(b.block) {
                OrderSetting::Fixed(n) if n > 0 => true,
                _ => session
                    .identify_aside(&Settings {
                        order: OrderSetting::Auto.into(),
                        blocks: vec![b.block],
                        ..settings.clone()
                    })
                    .ok()
                    .and_then(|own| own.blocks.first().map(|o| o.structural.order > 0))
                    .unwrap_or(true),
            };
        let mut input_limit = input_limit(b, b.band_hz, given, dynamics);
        let mut band = b.band_hz;
        let mut design = None;
        if let Some(ended) = input_limit
            .as_ref()
            .filter(|l| l.band_ended)
            .map(InputLimit::band_hz)
        {
            design = block_design(run, &id.motion.euler, b, (ended, false), &span);
            if design.is_some() {
                band = ended;
            } else if let Some(l) = input_limit.as_mut() {
                // Too few bins below the inputs' limit: the band asked for, with the limit said.
                l.band_ended = false;
            }
        }
        let design = design.or_else(|| block_design(run, &id.motion.euler, b, (band, true), &span));
        let (design, upper) = design.ok_or(DiagnoseError::TooShort {
            block: name,
            low: band[0],
            high: band[1],
        })?;
        let dof = 3.0 * design.dof_per_channel();
        let mut base =
            State::base(design, b.structural.tau_s, band).ok_or(DiagnoseError::Degenerate(name))?;
        // Only stretches on the settings' own segment, and all of them fitted: on a record too
        // short for them the stationarity comes from a few stretches of a shorter segment (a
        // floor on the deviations), and with a stretch named without a delay from three, whose
        // trend is too weak a test to skip the re-timing search on.
        // Over the band searched: where it was ended, the stretches' delays over the whole band
        // are biased by the inputs that are not the motion (a real recording's slow run, one
        // sample slipped: 3.8 and 5.1 ms before the slip, a step no longer seen, a drift read).
        let stationarity = if band.map(f64::to_bits) == b.band_hz.map(f64::to_bits) {
            b.stationarity.clone()
        } else {
            crate::ident::stretches::cached_stationarity(&b.spectra, band)
        };
        base.drift_hint = stationarity
            .as_deref()
            .filter(|st| st.segment_len.is_none() && st.stretches.len() >= MIN_STRETCHES)
            .map(|st| {
                let (trend, trend_std) = st.drift();
                [trend, trend_std]
            });
        let delay_step = stationarity.as_deref().and_then(|st| st.delay_step);
        let drifts = stationarity
            .as_deref()
            .is_some_and(crate::ident::stretches::Stationarity::drifts);
        if let Some(upper) = upper {
            base.set_upper(upper);
        }
        blocks.push(PreparedBlock {
            block: b.block,
            band_hz: band,
            input_limit,
            delay_step,
            search_drift: delay_step.is_none() || drifts,
            base,
            dof,
        });
    }
    // Every block set aside: refused as the identification refuses a run with none left.
    if blocks.is_empty()
        && let Some(e) = first_refusal
    {
        return Err(e.alone().into());
    }
    Ok(Prepared {
        // The band as asked: each block's band searched is in its report.
        settings: Settings {
            band_hz: asked,
            ..settings
        },
        source: Source::of(run),
        blocks,
        refused_blocks: refused,
        halves: Some(HalvesSource {
            run: session.run().clone(),
            identification: id,
            span,
        }),
    })
}

/// The diagnosis from a [`Prepared`] run: only the rounds of the search are done here.
#[must_use]
pub fn diagnose_prepared(prep: &Prepared, options: &DiagnoseOptions<'_>) -> Report {
    let mut findings = Vec::new();
    let mut blocks = BTreeMap::new();
    let mut penalty = 0.0;
    for pb in &prep.blocks {
        // The block's place in the identification the halves refit (blocks set aside are not
        // in `prep.blocks`).
        let block_index = prep.halves.as_ref().map_or(usize::MAX, |h| {
            h.identification
                .blocks
                .iter()
                .position(|b| b.block == pb.block)
                .unwrap_or(usize::MAX)
        });
        let given = options.given.and_then(|m| m.blocks.get(pb.block.name()));
        // A rejected stand-side lag rejects the lag it was found as.
        // Nor is a clock drift searched through a step of the delay.
        let rejected: Vec<Effect> = options
            .rejected
            .iter()
            .filter(|(block, _)| *block == pb.block)
            .map(|&(_, e)| {
                if e == Effect::ReferenceLag {
                    Effect::SensorLag
                } else {
                    e
                }
            })
            .chain((!pb.search_drift).then_some(Effect::ClockDrift))
            .collect();
        let (report, mut found) = diagnose_block(pb, (prep.halves.as_ref(), block_index), given, &rejected);
        penalty = pb.dof.ln();
        findings.append(&mut found);
        blocks.insert(pb.block.name().to_owned(), report);
    }
    name_stand_side(&mut findings);
    findings.sort_by(|a: &Finding, b: &Finding| b.criterion_gain.total_cmp(&a.criterion_gain));
    Report {
        schema: DISCREPANCY_SCHEMA.to_owned(),
        verdict: if findings.is_empty() {
            Verdict::NoMissingEffect
        } else {
            Verdict::EffectFound
        },
        findings,
        source: prep.source.clone(),
        settings: prep.settings.clone(),
        criterion: Criterion {
            name: "BIC with a look-elsewhere term".to_owned(),
            penalty_per_parameter: penalty,
            look_elsewhere: "2 ln(m), m the candidates tried in the round".to_owned(),
        },
        blocks,
        refused_blocks: prep.refused_blocks.clone(),
    }
}

/// Top of the line search above the fit's band, relative to the band's top: tones are searched
/// inside the band and up to half as far again above it (and below 0.45 of the rate). Further
/// up, the inputs computed from the measured angles are their noise (the stand's motion reaches
/// about 60 Hz), and subtracting the model there puts that noise's lines into the residual: on
/// simulated approach runs, "tones" at 157-205 Hz in the accelerometer.
const LINE_SEARCH_TOP: f64 = 1.5;

/// The block's whole-record design, its expected disturbance level taken from the
/// identification's `S_psi`, and its spectra above the band up to [`LINE_SEARCH_TOP`] times
/// the band's top for the line search (`None` when too few bins remain).
pub(super) fn block_design(
    run: &Run,
    motion: &EulerSeries,
    b: &BlockIdentification,
    (band, lines_above): ([f64; 2], bool),
    span: &std::ops::Range<usize>,
) -> Option<(Design, Option<Design>)> {
    let signals = block_signals(run, motion, b.block)?;
    let cut = |x: &[f64]| x[span.clone()].to_vec();
    let g = run.sidecar.g_mps2;
    let auxiliary: Vec<Vec<f64>> = match b.block {
        Block::Gyro => motion
            .specific_forces(run.sidecar.gyro_lever_arm_m, g)
            .into_iter()
            .collect(),
        Block::Accel => {
            let r = run.sidecar.accel_lever_arm_m;
            let at = motion.specific_forces(r, g);
            let shifted: Vec<[Vec<f64>; 3]> = (0..3)
                .map(|l| {
                    let mut rl = r;
                    rl[l] += 1.0;
                    motion.specific_forces(rl, g)
                })
                .collect();
            // d f_i / d r_l at AUX + 3 i + l (f is affine in the lever arm: the difference is exact).
            (0..3)
                .flat_map(|i| (0..3).map(move |l| (i, l)))
                .map(|(i, l)| shifted[l][i].iter().zip(&at[i]).map(|(a, b)| a - b).collect())
                .collect()
        }
    };
    let expected = smoothed_noise_psd(b);
    let freq = &b.spectra.frequency_hz;
    let lookup = |i: usize, f: f64| {
        let k = freq.partition_point(|&x| x < f).clamp(1, freq.len() - 1);
        let t = ((f - freq[k - 1]) / (freq[k] - freq[k - 1])).clamp(0.0, 1.0);
        expected[i][k - 1] * (1.0 - t) + expected[i][k] * t
    };
    let output = signals.output.each_ref().map(|x| cut(x));
    let input = signals.input.each_ref().map(|x| cut(x));
    let design = Design::new(
        &DesignSignals {
            block: b.block,
            output: &output,
            input: &input,
            auxiliary: &auxiliary.iter().map(|x| cut(x)).collect::<Vec<_>>(),
            sample_rate_hz: run.sample_rate_hz,
        },
        band,
        &lookup,
    )?;
    let top = (LINE_SEARCH_TOP * band[1]).min(0.45 * run.sample_rate_hz);
    // The line search needs a line's neighbourhood on both sides, so neither range finds a line
    // within its edge margin: the upper range starts that margin below the band's top, and a
    // line at the top is inside one of the two.
    let margin =
        2.0 * super::tone::EDGE_MARGIN_BINS as f64 * run.sample_rate_hz / output[0].len().max(1) as f64;
    let from = (band[1] - margin).max(band[0]);
    // Not above a band ended where the inputs stop being the motion: the residual there is the
    // model driven by the angles' noise, and its roll-off passed for tones (on a `--stand real`
    // run with a mount resonance, two to four "tones" at 27-38 Hz above a band ended at 26-28
    // Hz, against none over the whole band).
    let upper = lines_above
        .then(|| Design::line_search(b.block, &output, &input, run.sample_rate_hz, [from, top]))
        .flatten();
    Some((design, upper))
}

/// `S_psi,ii` running-median smoothed over about four native Welch bins each side, so that a
/// line does not raise the level it is tested against; near zero frequency the window shrinks to
/// a quarter of the bin's index each side, since there the density changes by a large factor
/// within a few bins (the coloured disturbance below 0.5 Hz) and a wide window would
/// underestimate it.
fn smoothed_noise_psd(b: &BlockIdentification) -> [Vec<f64>; 3] {
    let psd = &b.factorisation.noise_psd;
    let half = 4 * b.spectra.native_step();
    // S_psi is a regression residual of n_eq averages less the three inputs' degrees of freedom,
    // so its mean is (n_eq - 3) / n_eq of the disturbance's; the median of its scaled
    // chi-squared(2 (n_eq - 3)) distribution lies a further (1 - 1/(9 (n_eq - 3)))^3 below
    // (Wilson-Hilferty). Both are undone.
    let dof = (b.spectra.equivalent_averages - 3.0).max(1.0);
    let unbias = (dof + 3.0) / dof / (1.0 - 1.0 / (9.0 * dof)).powi(3);
    [0, 1, 2].map(|i| {
        let diag: Vec<f64> = psd.iter().map(|m| m[(i, i)].re.max(0.0) * unbias).collect();
        (0..diag.len())
            .map(|k| {
                let h = half.min(k / 4);
                let lo = k.saturating_sub(h);
                let hi = (k + h + 1).min(diag.len());
                super::tone::median(&mut diag[lo..hi].to_vec())
            })
            .collect()
    })
}

/// The decision rule: BIC's `ln n` per added parameter, plus `2 ln m` for having tried `m`
/// candidates in the round: the look-elsewhere cost of picking the best of several. With the bare
/// BIC threshold (`ln n` = 9.9 for one parameter) a clean test run (cruise, seed 107) came within
/// 0.6 of a false `sensor_lag`; the chance level for the best of `m` chi-squared draws grows
/// like `2 ln m`.
#[derive(Clone, Copy, Debug)]
struct Rule {
    per_parameter: f64,
    multiplicity: f64,
}

impl Rule {
    fn threshold(self, added: usize) -> f64 {
        added as f64 * self.per_parameter + self.multiplicity
    }

    fn gain(self, c: &Candidate) -> f64 {
        c.delta_chi2 - self.threshold(c.added_params)
    }
}

fn summary(c: &Candidate, rule: Rule) -> CandidateSummary {
    CandidateSummary {
        effect: c.effect,
        delta_chi2: c.delta_chi2,
        added_parameters: c.added_params,
        criterion_gain: rule.gain(c),
    }
}

/// Grows one block's model; returns its report and findings.
fn diagnose_block(
    pb: &PreparedBlock,
    (halves, block_index): (Option<&HalvesSource>, usize),
    given: Option<&BlockModel>,
    rejected: &[Effect],
) -> (BlockReport, Vec<Finding>) {
    let (b, band, dof) = (pb, pb.band_hz, pb.dof);
    let (input_names, _) = channel_names(b.block);
    let base = &pb.base;
    let mut state = base.clone();
    let mut accepted: Vec<(Effect, usize, Finding)> = Vec::new();
    let mut first_round = Vec::new();
    for round in 0..MAX_FINDINGS {
        let mut cands = candidates(&state, band);
        cands.retain(|c| !rejected.contains(&c.effect));
        let rule = Rule {
            per_parameter: dof.ln(),
            multiplicity: 2.0 * (cands.len().max(1) as f64).ln(),
        };
        cands.sort_by(|a, b| rule.gain(b).total_cmp(&rule.gain(a)));
        if round == 0 {
            first_round = cands.iter().map(|c| summary(c, rule)).collect();
        }
        // The best significant candidate that closes part of the gap (contract section 5) and
        // opens it nowhere: one that trades the strong bins for the weak ones is no finding.
        let before = state.worst_gap_db();
        let chosen = cands
            .iter()
            .take_while(|c| rule.gain(c) > 0.0)
            .filter(|c| within_reach(c, band))
            .find_map(|c| {
                state
                    .with(c, band)
                    .filter(|n| above_band(c) || closes_gap(&state, n))
                    .map(|n| (c, n))
            });
        let Some((best, next)) = chosen else { break };
        let index = match &best.extension {
            Extension::Tone(_) => state.tones.len(),
            Extension::Structural(_) | Extension::ClockCorrected { .. } => {
                state.fitted.structure.resonance_axes.len()
            }
        };
        let (delta, added) = (best.delta_chi2, best.added_params);
        let threshold = rule.threshold(added);
        let gain = delta - threshold;
        let after = next.worst_gap_db();
        let closed = super::describe::misfit_closed(state.total_gap_db(), next.total_gap_db());
        let finding = Finding {
            block: b.block,
            effect: best.effect,
            name: best.effect.name_on(b.block),
            // Filled from the final model: every finding's size is re-identified with the others.
            parameters: serde_json::Value::Null,
            parameter_std: serde_json::Value::Null,
            gap_before_db: before,
            gap_after_db: after,
            evidence: format!(
                "removes chi2 {delta:.1} with {added} added parameters (threshold {threshold:.1}: BIC plus the \
                 look-elsewhere cost; gain {gain:.1}); worst-channel gap {before:.2} dB -> {after:.2} dB; {closed}"
            ),
            delta_chi2: delta,
            added_parameters: added,
            criterion_gain: gain,
            halves: None,
        };
        accepted.push((best.effect, index, finding));
        state = next;
    }
    let chi2_per_dof = state.fitted.chi2() / dof;
    let cov = if accepted.is_empty() {
        None
    } else {
        covariance(&state, band, chi2_per_dof)
    };
    for (effect, index, finding) in &mut accepted {
        finding.parameters = parameters(*effect, &state, *index, input_names);
        finding.parameter_std = parameter_std(*effect, &state, *index, cov.as_ref());
        if super::describe::size_within_noise(finding) {
            let _ = write!(finding.evidence, "; {}", super::describe::SIZE_WITHIN_NOISE);
        }
    }
    if let Some(source) = halves {
        compare_halves(source, block_index, &state, band, input_names, &mut accepted);
    }
    let findings = accepted.into_iter().map(|(_, _, finding)| finding).collect();
    let mut report = block_report(base, &state, first_round, dof);
    report.band_hz = band;
    report.input_limit.clone_from(&pb.input_limit);
    report.delay_step = pb.delay_step;
    report.given_model_gap_db = given.map(|m| base.gap_of(m.k, m.tau_s));
    (report, findings)
}

/// How many standard deviations two blocks' lags may differ by and still be one lag.
const SHARED_LAG_SIGMAS: f64 = 3.0;

/// A first-order lag found on both blocks with the same time constant (within
/// [`SHARED_LAG_SIGMAS`] of their combined standard deviation) is the angle measurement's, not
/// the sensors': both blocks see the stand's band limit or latency through their inputs, and
/// per block an input lag and an output lag are the same filter. Both findings are renamed
/// [`Effect::ReferenceLag`]. (The simulator draws a sensor lag on each block independently,
/// 3.2-5 ms apart by up to 1.8 ms, far beyond the few hundredths of a ms their deviations are.)
pub(super) fn name_stand_side(findings: &mut [Finding]) {
    let lag = |f: &Finding| {
        let t = f.parameters.get("T_s")?.as_f64()?;
        let sd = f.parameter_std.get("T_s")?.as_f64()?;
        Some((t, sd))
    };
    let of = |findings: &[Finding], block: Block| {
        findings
            .iter()
            .position(|f| f.block == block && f.effect == Effect::SensorLag)
    };
    let (Some(g), Some(a)) = (of(findings, Block::Gyro), of(findings, Block::Accel)) else {
        return;
    };
    let (Some((tg, sg)), Some((ta, sa))) = (lag(&findings[g]), lag(&findings[a])) else {
        return;
    };
    if (tg - ta).abs() > SHARED_LAG_SIGMAS * sg.hypot(sa) {
        return;
    }
    for k in [g, a] {
        let f = &mut findings[k];
        f.effect = Effect::ReferenceLag;
        f.name = Effect::ReferenceLag.name_on(f.block);
        let _ = write!(
            f.evidence,
            "; the same lag on both blocks (gyro {:.3} ± {:.3} ms, accelerometer {:.3} ± {:.3} ms): the angle \
             measurement's band limit or latency, seen by both through their inputs, not the sensors'",
            tg * 1e3,
            sg * 1e3,
            ta * 1e3,
            sa * 1e3
        );
    }
}

/// Highest damping ratio of a resonance reported as a finding: 0.5, where the mode's gain at its
/// own frequency, `1 / (2 zeta)`, is 1. A mode damped more attenuates even there (its peak, if
/// any, under 1.25 dB, none beyond 0.707): the data cannot tell it from a gentle roll-off (a lag,
/// the stand's band limit), and its phase lag trades with the channels' delays. A real
/// recording with one gyro channel delayed 3 ms had its skew found right, then "resonances" of
/// damping 0.57-0.60 at 22-28 Hz added, each taking 6.5-8.8 ms from its channel's delay: the
/// skew reported with a channel at -2.5 ms, -7.1 ms on another run. The catalogue's weakest
/// simulated resonance has damping 0.4 (`sim::block`).
const MAX_RESONANCE_DAMPING: f64 = 0.5;
/// How close to a band edge (relative) a resonance may sit and still be a finding.
const EDGE_MARGIN: f64 = 0.03;

/// Whether a candidate's size is inside what the data can show: a resonance inside the band
/// (not within [`EDGE_MARGIN`] of an edge, where the fit parks a mode that explains a misfit
/// beyond the band) and damped at most [`MAX_RESONANCE_DAMPING`]. (A lag whose corner lies
/// beyond the band is still seen by its droop: a 1.2 ms lag takes 4 % off the gain at 40 Hz.)
fn within_reach(c: &Candidate, band: [f64; 2]) -> bool {
    match (&c.extension, c.effect) {
        (Extension::Structural(fitted), Effect::PlatformResonance) => {
            fitted.theta.resonances.last().is_some_and(|&(f, zeta)| {
                f > band[0] * (1.0 + EDGE_MARGIN)
                    && f < band[1] * (1.0 - EDGE_MARGIN)
                    && zeta <= MAX_RESONANCE_DAMPING
            })
        }
        _ => true,
    }
}

/// Whether the candidate is a tone above the fit's band: it leaves the band's gap as it is
/// (what it explains is its own line, measured against the local continuum there).
fn above_band(c: &Candidate) -> bool {
    matches!(&c.extension, Extension::Tone(t) if t.upper)
}

/// Numerical tolerance of "a channel's gap does not grow", dB: refitting every parameter moves
/// the gap of a channel the effect does not touch by a few ten-thousandths of a dB either way.
const GAP_TOLERANCE_DB: f64 = 0.005;

/// Whether `next` closes part of `state`'s gap and opens it nowhere: the total (all channels)
/// shrinks, and no channel's gap (the worst's included) grows beyond [`GAP_TOLERANCE_DB`]. A
/// skew of 0.1 ms between channels closes the gap of the channels it delays and leaves the
/// worst channel's as it was, to 0.0004 dB.
fn closes_gap(state: &State, next: &State) -> bool {
    let (before, after) = (state.gap_db(), next.gap_db());
    next.total_gap_db() < state.total_gap_db()
        && before.iter().zip(&after).all(|(b, a)| *a <= b + GAP_TOLERANCE_DB)
}

fn block_report(base: &State, last: &State, candidates: Vec<CandidateSummary>, dof: f64) -> BlockReport {
    let d = &base.design;
    BlockReport {
        k_base: gain(base),
        tau_base_s: base.fitted.theta.tau_s,
        k: gain(last),
        tau_s: last.fitted.theta.tau_s,
        chi2_per_dof: [base.fitted.chi2() / dof, last.fitted.chi2() / dof],
        gap_db: [base.gap_db(), last.gap_db()],
        candidates,
        map: [
            disagreement_map(d, &base.residual),
            disagreement_map(d, &last.residual),
        ],
        residual_psd: [
            psd_cells(d, &power(&base.residual), PSD_CELLS),
            psd_cells(d, &power(&last.residual), PSD_CELLS),
        ],
        expected_psd: psd_cells(d, &d.expected, PSD_CELLS),
        band_hz: [0.0; 2],
        input_limit: None,
        delay_step: None,
        given_model_gap_db: None,
    }
}
