//! The benchmark's state and its standard stage list.
//!
//! | stage | what is timed |
//! |---|---|
//! | `load` | reading the CSV and its sidecar into columns |
//! | `observer` | the observer's motion estimate and every block's inputs `u` (the "observer inputs") |
//! | `spectra` | the zero-padded Welch matrices of `[u; x]` of every block |
//! | `factorisation` | the factorisation stage of every block |
//! | `identify` | the regularised Wiener estimate `W_u` (A, Lambda) of every block |
//! | `structural_fit` | the structural fit (order) of every block |
//! | `retune` | a change of Lambda: Wiener and structural fit of every block from cached spectra and factorisation ([`identify_block_from`]), median of [`RETUNES`] changes |
//! | `retune_order0` | `retune` with the order fixed at 0 (`K e^(-tau s)`) instead of the settings' order |
//! | `diagnose` | the missing-effect workflow ([`crate::diagnose::diagnose_run`]) on the loaded run, its own identification included |
//! | `rewelch` | a change of the Welch settings (overlap 0.5 -> 0.6): spectra, factorisation, Wiener and structural fit of every block from the cached observer inputs |
//! | `spectra_bare` | the lower bound of `spectra`: [`super::bare`]'s loop of the same FFTs and cross products |

use std::path::PathBuf;
use std::sync::Arc;

use super::{BenchError, Stage, bare};
use crate::ident::IdentError;
use crate::ident::factorisation::{Factorisation, FactorisationSettings, factorise};
use crate::ident::identify::{identify_block_from, native_band, structural_fit};
use crate::ident::settings::{LambdaSetting, OrderSetting, Settings};
use crate::ident::signals::{BlockSignals, block_signals, channel_names};
use crate::ident::spectra::{BlockSpectra, block_spectra};
use crate::ident::wiener::{WienerEstimate, regularised_wiener};
use crate::run::{LoadOptions, Run, load};
use crate::spectral::{WelchPlanner, WelchSettings};
use crate::stand::observer::{ObserverSettings, observe};

/// Lambda changes timed by the `retune` stage.
pub const RETUNES: usize = 9;
/// Overlap the `rewelch` stage changes the Welch settings to.
pub const REWELCH_OVERLAP: f64 = 0.6;

/// What the stages hand each other.
#[derive(Debug)]
pub struct BenchState {
    /// The run file.
    pub path: PathBuf,
    /// Identification settings (blocks filled in by `load`).
    pub settings: Settings,
    /// The loaded run.
    pub run: Option<Run>,
    /// Every block's signals `[u; x]`.
    pub signals: Vec<BlockSignals>,
    /// FFT plans and windows, reused across stages.
    pub planner: WelchPlanner,
    /// Every block's spectra.
    pub spectra: Vec<Arc<BlockSpectra>>,
    /// Every block's factorisation.
    pub factorisations: Vec<Arc<Factorisation>>,
    /// Every block's Wiener estimate.
    pub wiener: Vec<WienerEstimate>,
    /// Lambda changes done so far by `retune`.
    pub retunes: usize,
}

impl BenchState {
    /// A state before any stage, for the run at `path`.
    #[must_use]
    pub fn new(path: PathBuf, settings: Settings) -> Self {
        Self {
            path,
            settings,
            run: None,
            signals: Vec::new(),
            planner: WelchPlanner::new(),
            spectra: Vec::new(),
            factorisations: Vec::new(),
            wiener: Vec::new(),
            retunes: 0,
        }
    }

    /// Number of distinct channels whose spectra are computed (`u` and `x` of every block).
    #[must_use]
    pub fn channels(&self) -> usize {
        let mut names: Vec<&str> = self
            .signals
            .iter()
            .flat_map(|s| {
                let (u, x) = channel_names(s.block);
                u.into_iter().chain(x)
            })
            .collect();
        names.sort_unstable();
        names.dedup();
        names.len()
    }

    fn loaded(&self, stage: &'static str) -> Result<&Run, BenchError> {
        self.run
            .as_ref()
            .ok_or(BenchError::Missing { stage, needs: "load" })
    }

    fn need<'v, T>(v: &'v [T], stage: &'static str, needs: &'static str) -> Result<&'v [T], BenchError> {
        if v.is_empty() {
            Err(BenchError::Missing { stage, needs })
        } else {
            Ok(v)
        }
    }
}

/// One block's spectra and factorisation.
type Cached = (Arc<BlockSpectra>, Arc<Factorisation>);

/// Spectra and factorisation of every block's `signals` with `welch`.
fn spectra_and_factorisations(
    planner: &mut WelchPlanner,
    signals: &[BlockSignals],
    sample_rate_hz: f64,
    welch: &WelchSettings,
) -> Result<Vec<Cached>, BenchError> {
    signals
        .iter()
        .map(|s| {
            let spectra = block_spectra(planner, s, sample_rate_hz, welch)?;
            let factorisation = factorise(&spectra, &FactorisationSettings::default())?;
            Ok((Arc::new(spectra), Arc::new(factorisation)))
        })
        .collect()
}

fn load_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let run = load(&state.path, &LoadOptions::default())?;
    state.settings.blocks = state.settings.blocks_for(&run.blocks());
    state
        .settings
        .validate(run.len(), run.sample_rate_hz, &run.blocks())
        .map_err(|e| IdentError::Settings(e.to_string()))?;
    state.run = Some(run);
    Ok(())
}

fn observer_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let run = state.loaded("observer")?;
    let settings = ObserverSettings {
        angle_noise_rad: run.sidecar.angle_noise_rad,
        ..ObserverSettings::default()
    };
    let motion = observe(
        run.angles.each_ref().map(Vec::as_slice),
        run.sample_rate_hz,
        &settings,
    )
    .map_err(|e| IdentError::Observer(e.to_string()))?;
    let signals = state
        .settings
        .blocks
        .iter()
        .map(|&b| block_signals(run, &motion.euler, b).ok_or(IdentError::MissingBlock(b.name())))
        .collect::<Result<_, _>>()?;
    state.signals = signals;
    Ok(())
}

fn spectra_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let rate = state.loaded("spectra")?.sample_rate_hz;
    let signals = BenchState::need(&state.signals, "spectra", "observer")?;
    state.spectra = signals
        .iter()
        .map(|s| {
            Ok(Arc::new(block_spectra(
                &mut state.planner,
                s,
                rate,
                &state.settings.welch,
            )?))
        })
        .collect::<Result<_, BenchError>>()?;
    Ok(())
}

fn factorisation_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let spectra = BenchState::need(&state.spectra, "factorisation", "spectra")?;
    state.factorisations = spectra
        .iter()
        .map(|s| Ok(Arc::new(factorise(s, &FactorisationSettings::default())?)))
        .collect::<Result<_, BenchError>>()?;
    Ok(())
}

fn identify_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let facts = BenchState::need(&state.factorisations, "identify", "factorisation")?;
    let s = &state.settings;
    state.wiener = state
        .spectra
        .iter()
        .zip(facts)
        .map(|(sp, f)| regularised_wiener(sp, f, &s.weight(), s.lambda, s.band_hz))
        .collect::<Result<_, _>>()?;
    Ok(())
}

fn structural_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let wiener = BenchState::need(&state.wiener, "structural_fit", "identify")?;
    for ((sp, f), w) in state.spectra.iter().zip(&state.factorisations).zip(wiener) {
        structural_fit(
            sp,
            f,
            w,
            &native_band(sp, state.settings.band_hz),
            state.settings.order,
        )?;
    }
    Ok(())
}

fn retune_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let facts = BenchState::need(&state.factorisations, "retune", "factorisation")?;
    state.retunes += 1;
    let l = 0.01 * state.retunes as f64;
    let settings = Settings {
        lambda: LambdaSetting::Values([l, -l, 0.5 * l]),
        ..state.settings.clone()
    };
    for ((sig, sp), f) in state.signals.iter().zip(&state.spectra).zip(facts) {
        identify_block_from(sig.block, Arc::clone(sp), Arc::clone(f), &settings)?;
    }
    Ok(())
}

fn retune_order0_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let order = std::mem::replace(&mut state.settings.order, OrderSetting::Fixed(0));
    let result = retune_stage(state);
    state.settings.order = order;
    result
}

fn rewelch_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let rate = state.loaded("rewelch")?.sample_rate_hz;
    let signals = BenchState::need(&state.signals, "rewelch", "observer")?;
    let settings = Settings {
        welch: WelchSettings {
            overlap: REWELCH_OVERLAP,
            ..state.settings.welch
        },
        ..state.settings.clone()
    };
    for (sig, (sp, f)) in signals.iter().zip(spectra_and_factorisations(
        &mut state.planner,
        signals,
        rate,
        &settings.welch,
    )?) {
        identify_block_from(sig.block, sp, f, &settings)?;
    }
    Ok(())
}

/// The whole missing-effect workflow on the loaded run (its own identification included).
fn diagnose_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let run = state.loaded("diagnose")?;
    let options = crate::diagnose::DiagnoseOptions::default();
    std::hint::black_box(crate::diagnose::diagnose_run(run, &state.settings, &options)?);
    Ok(())
}

fn bare_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let signals = BenchState::need(&state.signals, "spectra_bare", "observer")?;
    for s in signals {
        let channels: Vec<&[f64]> = s.input.iter().chain(&s.output).map(Vec::as_slice).collect();
        std::hint::black_box(bare::welch_sums(&channels, &state.settings.welch)?);
    }
    Ok(())
}

/// The standard stages, in order (see the module docs).
#[must_use]
pub fn standard_stages() -> Vec<Stage<'static>> {
    vec![
        Stage::once("load", load_stage),
        Stage::once("observer", observer_stage),
        Stage::once("spectra", spectra_stage),
        Stage::once("factorisation", factorisation_stage),
        Stage::once("identify", identify_stage),
        Stage::once("structural_fit", structural_stage),
        Stage::repeated("retune", RETUNES, retune_stage),
        Stage::repeated("retune_order0", RETUNES, retune_order0_stage),
        Stage::once("diagnose", diagnose_stage),
        Stage::once("rewelch", rewelch_stage),
        Stage::once("spectra_bare", bare_stage),
    ]
}
