//! The one staged, cached identification pipeline of a run, used by the command line
//! (`identify`, `discrepancy`, `compare`), `bench`, the diagnosis and the app's worker:
//!
//! | stage | cached per | recomputed when |
//! |---|---|---|
//! | observer (motion) and block signals | the run | never |
//! | spectra | block, Welch settings, span | the Welch settings or the span (`span_s`) change |
//! | factorisation | block, spectra | the spectra change |
//! | its causal stage (`D_u`, `W0`) | block, spectra | the spectra change, if the estimate is causal |
//! | the amplitude test's spectra (`odd_gain`) | block, Welch settings, span | as the spectra |
//! | Wiener and structural fit | settings | any other setting changes |
//!
//! Each stage's preconditions are checked in one place: the settings against the run
//! ([`Settings::validate`]) before anything runs, the observer's own (enough samples), the
//! excitation and the band in [`identify_block_from`]. A block refused for what its own data
//! lack ([`IdentError::is_refusal`]) is set aside in [`RunIdentification::refused`] and the
//! others are identified; only a run whose every block is refused fails. Results are `Arc`
//! snapshots, shared with whoever holds them (the app's plots, a model file being written).
//!
//! [`Start::Cold`] computes what is missing from scratch: what `imu-attest identify` gives.
//! [`Start::Warm`] (the app while a setting moves) starts the factorisation and the structural
//! fit from the previous ones, which is faster but may differ in the last digits; such an
//! identification is [`RunIdentification::provisional`], and [`Session::polish`] redoes it from
//! scratch.
//!
//! Nothing here reads a simulated run's answer key.

use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;

use super::IdentError;
use super::causal_stage::causal_stage;
use super::dead_output::{dead_output, moves};
use super::factorisation::{Factorisation, FactorisationSettings, factorise_from};
use super::identify::{
    BlockIdentification, FitStart, IdentStep, Refusal, RunIdentification, identify_block_from,
};
use super::left_out_noise::LeftOutNoise;
use super::odd_gain::{OddSpectra, amplitude_dependent, odd_spectra};
use super::settings::{Estimate, Settings};
use super::signals::{BlockSignals, block_signals, bridged, channel_names};
use super::spectra::{BlockSpectra, block_spectra};
use super::warnings::{ANGLE_NOISE_OVERSTATED, IdentWarning};
use crate::block::Block;
use crate::run::Run;
use crate::spectral::{WelchPlanner, WelchSettings};
use crate::stand::observer::{
    NoiseColour, NoiseSource, ObserverEstimate, ObserverSettings, observe_with_witness,
};

/// Where the factorisation and the structural fit start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// From scratch: the command line's result.
    Cold,
    /// From the previous factorisation and fit of each block, where there are any.
    Warm,
}

/// A block's entry in a per-block cache.
type PerBlock<T> = Vec<(Block, Arc<T>)>;

/// One run and its cached stages.
#[derive(Debug)]
pub struct Session {
    run: Arc<Run>,
    planner: WelchPlanner,
    motion: Option<Arc<ObserverEstimate>>,
    signals: PerBlock<BlockSignals>,
    /// The Welch settings and span (sample range) of `spectra`.
    spectra_key: Option<(WelchSettings, Range<usize>)>,
    spectra: PerBlock<BlockSpectra>,
    factorisations: PerBlock<Factorisation>,
    /// The factorisations of the spectra before the last Welch change: warm starts.
    previous_factorisations: PerBlock<Factorisation>,
    /// Every block's latest structural fit: warm starts.
    fits: PerBlock<FitStart>,
    identification: Option<(Settings, Arc<RunIdentification>)>,
    /// Each block's dead-channel verdict ([`dead_output`]) over the span it was made on: one pass
    /// over every output sample, not to be repeated on each retune.
    dead: Vec<(Block, Range<usize>, Option<IdentError>)>,
    /// Each block's amplitude test spectra ([`odd_spectra`]) under `spectra_key`: a retune only
    /// pools them again over its band.
    odd: PerBlock<OddSpectra>,
}

impl Session {
    /// A session of `run`, nothing computed yet.
    #[must_use]
    pub fn new(run: Arc<Run>) -> Self {
        Self {
            run,
            planner: WelchPlanner::new(),
            motion: None,
            signals: Vec::new(),
            spectra_key: None,
            spectra: Vec::new(),
            factorisations: Vec::new(),
            previous_factorisations: Vec::new(),
            fits: Vec::new(),
            identification: None,
            dead: Vec::new(),
            odd: Vec::new(),
        }
    }

    /// The run.
    #[must_use]
    pub fn run(&self) -> &Arc<Run> {
        &self.run
    }

    /// The observer's estimate of the platform motion (the sidecar's declared angle noise, else
    /// estimated, as the white floor; coloured per frequency by what the gyro's outputs do not
    /// explain when the run has a gyro block whose channels all move, [`super::dead_output`]),
    /// from the measured angles with their isolated
    /// glitches bridged ([`bridged`]: a spike in an angle would be differentiated twice into
    /// every block's input).
    ///
    /// # Errors
    /// What the observer refuses (too few samples, a bad declared noise).
    pub fn motion(&mut self) -> Result<Arc<ObserverEstimate>, IdentError> {
        if let Some(m) = &self.motion {
            return Ok(m.clone());
        }
        let settings = ObserverSettings {
            angle_noise_rad: self.run.sidecar.angle_noise_rad,
            ..ObserverSettings::default()
        };
        let angles = bridged(self.run.angles.clone());
        // A gyro with a channel that never moves is no witness: its flat axis would read every
        // motion of the stand about it as angle noise ([`super::dead_output`]). Nor is one with
        // a channel that holds samples or clips (`crate::faults`): what its stale or flat samples
        // miss of the motion would be read as the angles' noise, and the accelerometer's inputs
        // shrunk by it (a turbulent cruise run at 250 Hz with held samples in `gy`: the
        // accelerometer's `K` 0.87 % off, 10 deviations, with no word for that block).
        // Judged on the recorded samples by `crate::faults`' own rule, as its report says them
        // (a bridged glitch's points fall between a quantised channel's steps).
        let spoilt = |channel, x: &[f64]| {
            crate::faults::detect_channel(channel, &self.run.time_s, x)
                .iter()
                .any(crate::faults::RecordingFault::spoils_recording)
        };
        let witness = self
            .run
            .outputs(Block::Gyro)
            .filter(|gyro| {
                gyro.iter()
                    .zip([
                        crate::faults::Channel::Gx,
                        crate::faults::Channel::Gy,
                        crate::faults::Channel::Gz,
                    ])
                    .all(|(x, c)| moves(x) && !spoilt(c, x))
            })
            .map(|gyro| bridged(gyro.clone()));
        let m = Arc::new(observe_with_witness(
            angles.each_ref().map(Vec::as_slice),
            self.run.sample_rate_hz,
            &settings,
            witness.as_ref().map(|w| w.each_ref().map(Vec::as_slice)),
        )?);
        self.motion = Some(m.clone());
        Ok(m)
    }

    /// A block's input (from the observer) and output (glitches bridged).
    ///
    /// # Errors
    /// The observer's errors; [`IdentError::MissingBlock`] when the run has no such block.
    pub fn signals(&mut self, block: Block) -> Result<Arc<BlockSignals>, IdentError> {
        if let Some(s) = of_block(&self.signals, block) {
            return Ok(s);
        }
        let motion = self.motion()?;
        let s = Arc::new(
            block_signals(&self.run, &motion.euler, block).ok_or(IdentError::MissingBlock(block.name()))?,
        );
        self.signals.push((block, s.clone()));
        Ok(s)
    }

    /// The samples `settings.span_s` selects (all without a span).
    ///
    /// # Errors
    /// [`SettingsError::Span`](super::settings::SettingsError::Span) for a span outside the record.
    pub fn span(&self, settings: &Settings) -> Result<Range<usize>, IdentError> {
        Ok(settings.span_range(&self.run.time_s)?)
    }

    /// A block's signals over `span` (the whole record's, cut: the observer saw everything).
    fn span_signals(&mut self, block: Block, span: &Range<usize>) -> Result<Arc<BlockSignals>, IdentError> {
        let whole = self.signals(block)?;
        if *span == (0..self.run.len()) {
            return Ok(whole);
        }
        let cut = |c: &[Vec<f64>; 3]| c.each_ref().map(|x| x[span.clone()].to_vec());
        Ok(Arc::new(BlockSignals {
            block,
            input: cut(&whole.input),
            output: cut(&whole.output),
        }))
    }

    /// The Welch spectra of `blocks` under `settings`' Welch settings and span. A change of
    /// either drops the cached spectra and factorisations (the latter kept as warm starts).
    ///
    /// # Errors
    /// The signals' errors, a span outside the record, or what Welch refuses (a segment longer
    /// than the span, ...).
    pub fn spectra(
        &mut self,
        settings: &Settings,
        blocks: &[Block],
    ) -> Result<PerBlock<BlockSpectra>, IdentError> {
        let welch = settings.welch;
        let key = (welch, self.span(settings)?);
        if self.spectra_key.as_ref() != Some(&key) {
            self.spectra.clear();
            self.odd.clear();
            if !self.factorisations.is_empty() {
                self.previous_factorisations = std::mem::take(&mut self.factorisations);
            }
            self.spectra_key = Some(key.clone());
        }
        let span = key.1;
        let mut out = Vec::with_capacity(blocks.len());
        for &block in blocks {
            let spectra = if let Some(s) = of_block(&self.spectra, block) {
                s
            } else {
                let signals = self.span_signals(block, &span)?;
                let mut s = block_spectra(&mut self.planner, &signals, self.run.sample_rate_hz, &welch)?;
                let motion = self.motion()?;
                s.gyro_witnessed = block == Block::Gyro && motion.noise_colour == NoiseColour::FromGyro;
                if let Some(psd) = &motion.angle_noise_left_out_psd {
                    let angles = motion.euler.angle.each_ref().map(Vec::as_slice);
                    let sidecar = &self.run.sidecar;
                    s.left_out_noise = Some(Arc::new(match block {
                        Block::Gyro => LeftOutNoise::for_gyro(psd.clone(), angles),
                        Block::Accel => LeftOutNoise::for_accel(
                            psd.clone(),
                            angles,
                            sidecar.accel_lever_arm_m,
                            sidecar.g_mps2,
                        ),
                    }));
                }
                let s = Arc::new(s);
                self.spectra.push((block, s.clone()));
                s
            };
            out.push((block, spectra));
        }
        Ok(out)
    }

    /// The factorisations of `blocks`' spectra under `settings` (with the causal stage for the
    /// causal estimate), the missing ones computed in parallel over the blocks (and, within a
    /// block, the disturbance's factor beside the causal stage when both are needed).
    ///
    /// # Errors
    /// The spectra's errors, or a factorisation's.
    pub fn factorisations(
        &mut self,
        settings: &Settings,
        blocks: &[Block],
        start: Start,
    ) -> Result<PerBlock<Factorisation>, IdentError> {
        let spectra = self.spectra(settings, blocks)?;
        let (known, previous) = (&self.factorisations, &self.previous_factorisations);
        let estimate = settings.estimate;
        let factor_settings = FactorisationSettings::default();
        let done: Vec<Result<_, IdentError>> = spectra
            .into_par_iter()
            .map(|(block, spectra)| {
                let warm = match start {
                    Start::Warm => of_block(previous, block),
                    Start::Cold => None,
                };
                // A warm-started factor is no answer to a cold request: the disturbance's factor
                // decides whether the cached factorisation is kept, the causal stage whether it is
                // redone (only for the causal estimate, which alone goes through it).
                let kept = |fresh: bool| start == Start::Warm || fresh;
                let Some(f) = of_block(known, block).filter(|f| kept(f.noise_from_scratch)) else {
                    let f = factorise_from(&spectra, &factor_settings, warm.as_deref(), estimate)?;
                    return Ok((block, Arc::new(f), true));
                };
                let causal_kept = f.causal.as_ref().is_some_and(|c| kept(c.from_scratch));
                if estimate == Estimate::H1 || causal_kept {
                    return Ok((block, f, false));
                }
                // The causal estimate without a causal stage fit for this request: only that stage
                // is computed.
                let stage = causal_stage(
                    &spectra,
                    &factor_settings,
                    warm.as_ref().and_then(|w| w.causal.as_deref()),
                )?;
                Ok((block, Arc::new(f.with_causal_stage(stage)), true))
            })
            .collect();
        let mut out = Vec::new();
        // The first block's error in the settings' order, whichever thread failed first.
        let done: Vec<_> = done.into_iter().collect::<Result<_, _>>()?;
        for (block, f, new) in done {
            if new {
                self.factorisations.retain(|(b, _)| *b != block);
                self.factorisations.push((block, f.clone()));
            }
            out.push((block, f));
        }
        Ok(out)
    }

    /// The identification under `settings` (its blocks filled in from the run when empty),
    /// calling `progress` before each stage and once when done. A cached identification with
    /// the same settings is returned as it is (with [`Start::Cold`], only if it is not
    /// provisional).
    ///
    /// # Errors
    /// Settings that do not fit the run, and every stage's errors.
    pub fn identify(
        &mut self,
        settings: &Settings,
        start: Start,
        progress: &mut dyn FnMut(IdentStep),
    ) -> Result<Arc<RunIdentification>, IdentError> {
        self.compute(settings, start, progress, true)
    }

    /// An identification from scratch under `settings` that leaves the session's identification
    /// and warm starts as they were (the diagnosis's order-0 fit over its own band): only the
    /// observer, spectra and factorisations are shared.
    ///
    /// # Errors
    /// As [`Session::identify`].
    pub fn identify_aside(&mut self, settings: &Settings) -> Result<Arc<RunIdentification>, IdentError> {
        self.compute(settings, Start::Cold, &mut |_| {}, false)
    }

    fn compute(
        &mut self,
        settings: &Settings,
        start: Start,
        progress: &mut dyn FnMut(IdentStep),
        keep: bool,
    ) -> Result<Arc<RunIdentification>, IdentError> {
        let run = self.run.clone();
        let settings = settings.used_on(&run)?;
        if let Some((_, id)) = self
            .identification
            .as_ref()
            .filter(|(s, id)| keep && *s == settings && (start == Start::Warm || !id.provisional()))
        {
            return Ok(id.clone());
        }
        // A block with an output channel that never moves is refused before its spectra (its
        // noise weights would be infinite); the others go on.
        let motion = self.motion()?;
        let span = self.span(&settings)?;
        let mut dead = Vec::new();
        let mut blocks = Vec::with_capacity(settings.blocks.len());
        self.dead.retain(|(_, on, _)| *on == span);
        for &block in &settings.blocks {
            let verdict = if let Some((_, _, verdict)) = self.dead.iter().find(|(b, _, _)| *b == block) {
                verdict.clone()
            } else {
                let verdict = dead_output(&*self.signals(block)?, &span);
                self.dead.push((block, span.clone(), verdict.clone()));
                verdict
            };
            match verdict {
                Some(refusal) => dead.push((block, refusal)),
                None => blocks.push(block),
            }
        }
        let total = 1 + 3 * blocks.len();
        let mut done = 0;
        let mut step = |stage, block, count: usize| {
            progress(IdentStep {
                done,
                total,
                stage,
                block,
            });
            done += count;
        };
        step("observer", None, 1);
        for &block in &blocks {
            step("spectra", Some(block), 1);
            self.spectra(&settings, &[block])?;
        }
        step("factorisation", None, blocks.len());
        let factorisations = self.factorisations(&settings, &blocks, start)?;
        let spectra = self.spectra(&settings, &blocks)?;
        step("fit", None, blocks.len());
        let fits = &self.fits;
        let identified: Vec<Result<BlockIdentification, IdentError>> = spectra
            .into_iter()
            .zip(factorisations)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|((block, spectra), (_, factorisation))| {
                let previous = match start {
                    Start::Warm => of_block(fits, block),
                    Start::Cold => None,
                };
                identify_block_from(block, spectra, factorisation, &settings, previous.as_deref())
            })
            .collect();
        // In the settings' order again, the blocks refused for a flat channel among them.
        let mut identified = identified.into_iter();
        let identified: Vec<_> = settings
            .blocks
            .iter()
            .map(|block| match dead.iter().position(|(b, _)| b == block) {
                Some(i) => Err(dead[i].1.clone()),
                None => identified
                    .next()
                    .unwrap_or(Err(IdentError::MissingBlock(block.name()))),
            })
            .collect();
        // A refusal decided on a warm start (fit or factorisation) is redone from scratch.
        let (mut identified, mut refused) =
            split_refusals(&settings.blocks, identified, start == Start::Cold)?;
        // A flat channel is no start's doing: its refusal stands, warm or cold.
        for r in &mut refused {
            r.from_scratch |= matches!(r.error, IdentError::DeadOutput { .. });
        }
        for b in &mut identified {
            let said = self.amplitude_dependence(&settings, b);
            b.warnings.extend(said);
        }
        if let Some(w) = witness_noise_shared(&identified) {
            // The gyro's noise taken for the angles' shrank every block's inputs.
            for b in identified.iter_mut().filter(|b| b.block != Block::Gyro) {
                b.warnings.push(w.clone());
            }
        }
        if let Some(w) = angle_noise_overstated(&motion, self.run.sidecar.angle_noise_rad) {
            // What the gyro says of the declared angle noise concerns every block's inputs.
            for b in &mut identified {
                b.warnings.push(w.clone());
            }
        }
        if motion.noise_colour == NoiseColour::White {
            // No witness of the motion: what the observer could not check, every block says.
            for b in &mut identified {
                b.warnings.push(IdentWarning::AngleNoiseColourUnknown {
                    angle_noise_rad: motion.angle_noise_rad,
                    declared: motion.noise_source == NoiseSource::Declared,
                });
            }
        }
        step("done", None, 0);
        let id = Arc::new(RunIdentification {
            motion,
            blocks: identified,
            refused,
        });
        if !keep {
            return Ok(id);
        }
        for b in &id.blocks {
            self.fits.retain(|(block, _)| *block != b.block);
            self.fits.push((b.block, Arc::new(b.fit_start())));
        }
        // A refused block's last fit is no start for the next: it was not this run's answer.
        for r in &id.refused {
            self.fits.retain(|(block, _)| *block != r.block);
        }
        self.identification = Some((settings, id.clone()));
        Ok(id)
    }

    /// `gain_depends_on_amplitude` for an identified block ([`super::odd_gain`]), from its test
    /// spectra (computed once per Welch settings and span); `None` when it is not said or the
    /// test cannot be made (a span Welch refuses: the identification already stood on it).
    fn amplitude_dependence(&mut self, settings: &Settings, b: &BlockIdentification) -> Option<IdentWarning> {
        let odd = if let Some(odd) = of_block(&self.odd, b.block) {
            odd
        } else {
            let span = self.span(settings).ok()?;
            let signals = self.span_signals(b.block, &span).ok()?;
            let odd = Arc::new(
                odd_spectra(
                    &mut self.planner,
                    &signals,
                    self.run.sample_rate_hz,
                    (
                        &settings.welch,
                        b.spectra.equivalent_averages,
                        b.spectra.aligned_samples,
                    ),
                )
                .ok()?,
            );
            self.odd.push((b.block, odd.clone()));
            odd
        };
        let s = &b.structural;
        let outputs = amplitude_dependent(
            &odd,
            b.band_hz,
            b.spectra.bin_correlation,
            channel_names(b.block).1,
            (&s.k, &s.k_std, s.tau_s),
        );
        (!outputs.is_empty()).then_some(IdentWarning::GainDependsOnAmplitude {
            outputs,
            band_hz: b.band_hz,
        })
    }

    /// The latest identification and its settings, if any.
    #[must_use]
    pub fn identification(&self) -> Option<(&Settings, &Arc<RunIdentification>)> {
        self.identification.as_ref().map(|(s, id)| (s, id))
    }

    /// Redoes a provisional identification from scratch (its factorisations and fits); `None`
    /// when there is nothing to redo.
    ///
    /// # Errors
    /// Every stage's errors.
    pub fn polish(&mut self) -> Option<Result<Arc<RunIdentification>, IdentError>> {
        let (settings, id) = self.identification.clone()?;
        if !id.provisional() {
            return None;
        }
        Some(self.identify(&settings, Start::Cold, &mut |_| {}))
    }
}

/// `witness_noise_shared` for the other blocks when the gyro's identification says
/// `witness_noise_bias` ([`super::witness_noise`]): the angle-noise model that took part of the
/// gyro's own noise for the stand's made every block's inputs.
fn witness_noise_shared(identified: &[BlockIdentification]) -> Option<IdentWarning> {
    identified
        .iter()
        .filter(|b| b.block == Block::Gyro)
        .flat_map(|b| &b.warnings)
        .find_map(|w| match w {
            IdentWarning::WitnessNoiseBias { estimate, .. } => Some(IdentWarning::WitnessNoiseShared {
                gyro_estimate: *estimate,
            }),
            _ => None,
        })
}

/// `angle_noise_overstated` when the sidecar declares an angle noise more than
/// [`ANGLE_NOISE_OVERSTATED`] times the bound the gyro puts on it on some axis (`stand::colour`).
fn angle_noise_overstated(motion: &ObserverEstimate, declared: Option<f64>) -> Option<IdentWarning> {
    let declared_rad = declared?;
    let bound_rad = motion.angle_noise_bound_rad?;
    bound_rad
        .iter()
        .any(|b| declared_rad > ANGLE_NOISE_OVERSTATED * b)
        .then_some(IdentWarning::AngleNoiseOverstated {
            declared_rad,
            bound_rad,
        })
}

/// The blocks' identifications (in the settings' order, `blocks`) split into the identified
/// blocks and the refused ones ([`IdentError::is_refusal`], each marked `from_scratch` as the
/// identification was): a block the run cannot identify does not take the others with it.
///
/// # Errors
/// The first block's error that is not a refusal, in the settings' order (whichever thread failed
/// first); else, when every block is refused, the first refusal. Neither offers to leave its
/// block out: nothing would be left, or (a stand axis held still) nothing right.
fn split_refusals(
    blocks: &[Block],
    identified: Vec<Result<BlockIdentification, IdentError>>,
    from_scratch: bool,
) -> Result<(Vec<BlockIdentification>, Vec<Refusal>), IdentError> {
    let (mut ok, mut refused) = (Vec::new(), Vec::new());
    for (&block, result) in blocks.iter().zip(identified) {
        match result {
            Ok(b) => ok.push(b),
            Err(error) if error.is_refusal() => refused.push(Refusal {
                block,
                error,
                from_scratch,
            }),
            // A gyro's refusal is the run's (`IdentError::is_refusal`): leaving it out would not
            // help.
            Err(error) => return Err(error.alone()),
        }
    }
    if ok.is_empty() && !refused.is_empty() {
        return Err(refused.swap_remove(0).error.alone());
    }
    Ok((ok, refused))
}

/// The entry of `block` in a per-block list.
fn of_block<T>(list: &[(Block, Arc<T>)], block: Block) -> Option<Arc<T>> {
    list.iter().find(|(b, _)| *b == block).map(|(_, v)| v.clone())
}

#[cfg(test)]
#[path = "session_tests.rs"]
mod tests;
