//! What every diagnosis of a run starts from ([`Prepared`]): the order-0 identification over the
//! diagnosis's band, each block's whole-record design and the paper's model fitted on it.

use std::collections::BTreeMap;

use super::DiagnoseError;
use super::design::{Design, DesignSignals};
use super::halves::HalvesSource;
use super::input_limit::{InputLimit, falling_gain, input_limit};
use super::noisy_angles::{Below, MIN_BELOW_BINS, NoisyAngles, confirmation_range, noisy_angles_range};
use super::state::State;
use crate::block::Block;
use crate::ident::band::BandSetting;
use crate::ident::band::{last_bin_below, native_bins, untrusted_to_top};
use crate::ident::identify::{BlockIdentification, resolve_band};
use crate::ident::session::Session;
use crate::ident::settings::{OrderSetting, Settings};
use crate::ident::signals::block_signals;
use crate::ident::stretches::MIN_STRETCHES;
use crate::model::refused::refused_blocks;
use crate::model::{RefusedBlock, Source};
use crate::run::Run;
use crate::stand::kinematics::EulerSeries;
use crate::stand::observer::NoiseColour;

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
    /// Faults of the recording itself (`crate::faults::detect`), as the model file has them.
    pub recording_faults: Vec<crate::faults::RecordingFault>,
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
    /// Where the inputs may not be the motion up to the band's top ([`super::noisy_angles`]):
    /// the angles mostly their noise, or the block's outputs no longer coherent with its inputs;
    /// a smooth finding must be confirmed below the lower ([`NoisyAngles::below_top_hz`]).
    pub noisy_angles: Option<NoisyAngles>,
    /// The paper's model fitted on the band below `noisy_angles` (up to its `below_top_hz`),
    /// where the search confirms its findings (`None`: no such range, or too little below it).
    pub below: Option<Below>,
    /// A step in the delays of the stretches over the band searched
    /// ([`crate::ident::delay_step`]): the record's streams slipped, and the report says so.
    pub delay_step: Option<crate::ident::delay_step::DelayStep>,
    /// The stretches' delays, s, where they are too few to test for a step
    /// ([`super::step_caveat::TOO_FEW_FOR_A_STEP`] or fewer, no step found): a clock drift named
    /// then may be a slipped sample, and its evidence says so with them. Empty otherwise.
    pub untested_step_delays_s: Vec<f64>,
    /// Whether a clock drift is searched: not through a step, unless the slope its two sides
    /// share is a drift.
    pub search_drift: bool,
    /// Where the expected disturbance level's smoothing window is whole ([`smoothed_noise_psd`]),
    /// Hz: below, it narrows towards zero frequency and follows a line's own power, so a tone
    /// there is measured against itself and may go unnamed at any size (a campaign on 29 Nov:
    /// one-output tones at 0.3 Hz not named at 300 times the level its neighbours set).
    pub full_level_hz: f64,
    /// The paper's model `K e^(-tau s)` fitted on the whole-record design (with the stretches'
    /// delay trend as the clock-drift hint).
    pub base: State,
    /// Real degrees of freedom of the band (all three channels): BIC's `n`.
    pub dof: f64,
    /// The usable band where it is narrower than the band searched at the top and the band is
    /// `"auto"`: each finding's sizes are fitted there ([`super::usable_band`]). A band the user
    /// gives is the band the sizes are fitted over.
    pub usable_band_hz: Option<[f64; 2]>,
    /// Whether the observer took the angle noise white for want of a sound gyro: a smooth
    /// finding may then be the stand's coloured angle noise, and its evidence says so
    /// ([`super::white_angles`]).
    pub angle_noise_taken_white: bool,
}

/// [`Prepared`] for `session`'s run under `settings`.
///
/// # Errors
/// As [`diagnose_run`](super::diagnose_run).
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
    let angle_snr = id.motion.angle_snr();
    for b in &id.blocks {
        let name = b.block.name();
        // The identification's refusal of a block without a usable band (a dead block) holds
        // here too, though the band searched is fixed: the diagnosis of a block the model
        // refused would be of nothing, and a gyro's refuses the run as it does there.
        // The usable band, once: its absence refuses the block, and where it is narrower than
        // the band searched the findings are sized over it (`super::usable_band`).
        let usable = (!given).then(|| resolve_band(&b.spectra, b.block, BandSetting::Auto));
        if let Some(Err(e)) = usable {
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
        let untested_step_delays_s = stationarity
            .as_deref()
            .filter(|st| delay_step.is_none() && st.stretches.len() <= super::step_caveat::TOO_FEW_FOR_A_STEP)
            .map(|st| st.stretches.iter().map(|s| s.tau_s).collect())
            .unwrap_or_default();
        let drifts = stationarity
            .as_deref()
            .is_some_and(crate::ident::stretches::Stationarity::drifts);
        if let Some(upper) = upper {
            base.set_upper(upper);
        }
        // Where the block's own outputs are last coherent with its inputs below a range that
        // reaches the band's top. With the angles' noisy range and no coherent bin below, the
        // band below is empty (the band's bottom): the smooth findings are said unconfirmed.
        // Without that range and no coherent bin below (a user's band above the usable band),
        // the block is not asked (`super::noisy_angles::confirmation_range`).
        let untrusted = untrusted_to_top(&b.spectra, band);
        let last_coherent = untrusted.and_then(|r| last_bin_below(&b.spectra, band, r[0]));
        let angles = noisy_angles_range(&angle_snr, band);
        let usable_top = match angles {
            Some(_) => untrusted.map(|_| last_coherent.unwrap_or(band[0])),
            None => last_coherent,
        };
        let noisy = confirmation_range(angles, usable_top);
        blocks.push(PreparedBlock {
            block: b.block,
            band_hz: band,
            input_limit,
            below: noisy.as_ref().and_then(|n| {
                let below = [band[0], n.below_top_hz()?];
                if native_bins(&b.spectra, below).len() < MIN_BELOW_BINS {
                    return None;
                }
                let (design, _) = block_design(run, &id.motion.euler, b, (below, false), &span)?;
                let dof = 3.0 * design.dof_per_channel();
                let state = State::base(design, b.structural.tau_s, below)?;
                Some(Below {
                    state,
                    band_hz: below,
                    dof,
                })
            }),
            noisy_angles: noisy,
            delay_step,
            untested_step_delays_s,
            search_drift: delay_step.is_none() || drifts,
            base,
            dof,
            full_level_hz: full_level_hz(b),
            usable_band_hz: usable
                .and_then(Result::ok)
                .and_then(|usable| super::usable_band::compared_band(usable, band)),
            angle_noise_taken_white: id.motion.noise_colour == NoiseColour::White,
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
        recording_faults: crate::faults::detect(run),
        halves: Some(HalvesSource {
            run: session.run().clone(),
            identification: id,
            span,
        }),
    })
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
    let g = run.sidecar.g_mps2;
    let auxiliary: Vec<Vec<f64>> = match b.block {
        Block::Gyro => motion
            .specific_forces(run.sidecar.gyro_lever_arm_m, g)
            .into_iter()
            .collect(),
        // d f_i / d r_l at AUX + 3 i + l (exact: f is affine in the lever arm).
        Block::Accel => motion.lever_arm_jacobian().into_iter().collect(),
    };
    // Views of the span: no copies of whole records.
    let expected = smoothed_noise_psd(b);
    let freq = &b.spectra.frequency_hz;
    let lookup = |i: usize, f: f64| {
        let k = freq.partition_point(|&x| x < f).clamp(1, freq.len() - 1);
        let t = ((f - freq[k - 1]) / (freq[k] - freq[k - 1])).clamp(0.0, 1.0);
        expected[i][k - 1] * (1.0 - t) + expected[i][k] * t
    };
    let output = signals.output.each_ref().map(|x| &x[span.clone()]);
    let input = signals.input.each_ref().map(|x| &x[span.clone()]);
    let auxiliary: Vec<&[f64]> = auxiliary.iter().map(|x| &x[span.clone()]).collect();
    let design = Design::new(
        &DesignSignals {
            block: b.block,
            output,
            input,
            auxiliary: &auxiliary,
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
        .then(|| Design::line_search(b.block, output, input, run.sample_rate_hz, [from, top]))
        .flatten();
    Some((design, upper))
}

/// Native Welch bins each side of [`smoothed_noise_psd`]'s window where it is whole.
const LEVEL_HALF_NATIVE: usize = 4;

/// The lowest frequency where [`smoothed_noise_psd`]'s window is whole (its half-width, a quarter
/// of the bin's index below, reaches [`LEVEL_HALF_NATIVE`] native bins), Hz.
fn full_level_hz(b: &BlockIdentification) -> f64 {
    let k = 4 * LEVEL_HALF_NATIVE * b.spectra.native_step();
    let f = &b.spectra.frequency_hz;
    f.get(k).or(f.last()).copied().unwrap_or(0.0)
}

/// `S_psi,ii` running-median smoothed over about four native Welch bins each side, so that a
/// line does not raise the level it is tested against; near zero frequency the window shrinks to
/// a quarter of the bin's index each side, since there the density changes by a large factor
/// within a few bins (the coloured disturbance below 0.5 Hz) and a wide window would
/// underestimate it.
fn smoothed_noise_psd(b: &BlockIdentification) -> [Vec<f64>; 3] {
    let psd = &b.factorisation.noise_psd;
    let half = LEVEL_HALF_NATIVE * b.spectra.native_step();
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
