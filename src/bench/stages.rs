//! The benchmark's state and its standard stage list.
//!
//! | stage | what is timed |
//! |---|---|
//! | `load` | reading the CSV and its sidecar into columns |
//! | `observer` | the observer's motion estimate and every block's inputs `u` (the "observer inputs") |
//! | `spectra` | the zero-padded Welch matrices of `[u; x]` of every block |
//! | `factorisation` | the factorisation stage of every block (the blocks in parallel) |
//! | `identify` | the regularised Wiener estimate `W_u` (A, Lambda) of every block |
//! | `structural_fit` | the structural fit (order) of every block |
//! | `retune` | a change of Lambda, as the app does it: Wiener and structural fit of every block from cached spectra and factorisation, the fit starting from the previous one ([`identify_block_from`] with `previous`), median of [`RETUNES`] successive changes |
//! | `retune_order` | a change of the model order (cycling through `0..=4` and `auto`) on unchanged data, from the previous fit |
//! | `retune_cold` | `retune` with the structural fit from scratch (what `identify` does) |
//! | `retune_order0` | `retune_cold` with the order fixed at 0 (`K e^(-tau s)`) instead of the settings' order |
//! | `diagnose` | the missing-effect workflow ([`crate::diagnose::diagnose_run`]) on the loaded run, its own identification included |
//! | `rewelch` | a change of the Welch settings (overlap 0.5 -> 0.6), as the app shows it at once: spectra, factorisation (Wilson started from the previous factors), Wiener and structural fit (from the previous fit) of every block from the cached observer inputs |
//! | `spectra_bare` | the lower bound of `spectra`: [`super::bare`]'s loop of the same FFTs and cross products |

use std::path::PathBuf;
use std::sync::Arc;

use rayon::prelude::*;

use super::{BenchError, Stage, bare};
use crate::ident::IdentError;
use crate::ident::band::native_bins;
use crate::ident::factorisation::{Factorisation, FactorisationSettings, factorise, factorise_from};
use crate::ident::identify::{identify_block_from, resolve_band, structural_fit};
use crate::ident::settings::{LambdaSetting, OrderSetting, Settings};
use crate::ident::signals::{BlockSignals, block_signals, channel_names};
use crate::ident::spectra::{BlockSpectra, block_spectra};
use crate::ident::structural::StructuralFit;
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
    /// Every block's latest structural fit, the start of the next retune.
    pub fits: Vec<Arc<StructuralFit>>,
    /// The settings of `fits`.
    pub fitted_with: Option<Settings>,
    /// Lambda changes done so far by `retune` and `retune_cold`.
    pub retunes: usize,
    /// Order changes done so far by `retune_order`.
    pub order_changes: usize,
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
            fits: Vec::new(),
            fitted_with: None,
            retunes: 0,
            order_changes: 0,
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

/// Spectra and factorisation of every block's `signals` with `welch`: the spectra block by block
/// (each parallel over segments), then the factorisations of all blocks at once (each block's two
/// Wilson factorisations take unequal times; together they keep both cores busy), started from
/// `previous` (one per block, in order) where given.
fn spectra_and_factorisations(
    planner: &mut WelchPlanner,
    signals: &[BlockSignals],
    sample_rate_hz: f64,
    welch: &WelchSettings,
    previous: &[Arc<Factorisation>],
) -> Result<Vec<Cached>, BenchError> {
    let spectra = signals
        .iter()
        .map(|s| Ok(Arc::new(block_spectra(planner, s, sample_rate_hz, welch)?)))
        .collect::<Result<Vec<_>, BenchError>>()?;
    spectra
        .into_par_iter()
        .enumerate()
        .map(|(i, sp)| {
            let start = previous.get(i).map(AsRef::as_ref);
            let factorisation = factorise_from(&sp, &FactorisationSettings::default(), start)?;
            Ok((sp, Arc::new(factorisation)))
        })
        .collect()
}

fn load_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let run = load(&state.path, &LoadOptions::default())?;
    state.settings.blocks = state.settings.blocks_for(&run.blocks());
    state
        .settings
        .validate(run.len(), run.sample_rate_hz, &run.blocks())
        .map_err(IdentError::from)?;
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
    .map_err(IdentError::from)?;
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
    // The blocks at once, as `rewelch` and the app do.
    state.factorisations = spectra
        .par_iter()
        .map(|s| Ok(Arc::new(factorise(s, &FactorisationSettings::default())?)))
        .collect::<Result<_, BenchError>>()?;
    Ok(())
}

fn identify_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let facts = BenchState::need(&state.factorisations, "identify", "factorisation")?;
    let s = &state.settings;
    state.wiener = (state.spectra.iter().zip(facts).zip(&state.signals))
        .map(|((sp, f), sig)| {
            let band_hz = resolve_band(sp, sig.block, s.band_hz)?;
            regularised_wiener(sp, f, &s.weight(), s.lambda, band_hz)
        })
        .collect::<Result<_, _>>()?;
    Ok(())
}

fn structural_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let wiener = BenchState::need(&state.wiener, "structural_fit", "identify")?;
    let mut fits = Vec::new();
    for (((sp, f), w), sig) in
        (state.spectra.iter().zip(&state.factorisations).zip(wiener)).zip(&state.signals)
    {
        let band = native_bins(sp, resolve_band(sp, sig.block, state.settings.band_hz)?);
        fits.push(Arc::new(structural_fit(
            sp,
            f,
            w,
            &band,
            state.settings.order,
            None,
        )?));
    }
    state.fits = fits;
    state.fitted_with = Some(state.settings.clone());
    Ok(())
}

/// Wiener and structural fit of every block with `settings` from the cached spectra and
/// factorisations, from the latest fits when `warm` (which the results then replace).
fn reidentify(state: &mut BenchState, settings: &Settings, warm: bool) -> Result<(), BenchError> {
    let stage = if warm { "retune" } else { "retune_cold" };
    let facts = BenchState::need(&state.factorisations, stage, "factorisation")?;
    let fits = BenchState::need(&state.fits, stage, "structural_fit")?;
    // The blocks in parallel, as the app does.
    let next = (state.signals.par_iter().zip(&state.spectra).zip(facts).zip(fits))
        .map(|(((sig, sp), f), fit)| {
            let previous = warm.then_some(fit.as_ref());
            identify_block_from(sig.block, Arc::clone(sp), Arc::clone(f), settings, previous)
                .map(|b| b.structural)
        })
        .collect::<Result<Vec<_>, _>>()?;
    if warm {
        state.fits = next;
        state.fitted_with = Some(settings.clone());
    }
    Ok(())
}

/// The settings with the next Lambda of the `retune` stages.
fn next_lambda(state: &mut BenchState) -> Settings {
    state.retunes += 1;
    let l = 0.01 * state.retunes as f64;
    Settings {
        lambda: LambdaSetting::Values([l, -l, 0.5 * l]),
        ..state.settings.clone()
    }
}

fn retune_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = next_lambda(state);
    reidentify(state, &settings, true)
}

fn retune_cold_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = next_lambda(state);
    reidentify(state, &settings, false)
}

fn retune_order_stage(state: &mut BenchState) -> Result<(), BenchError> {
    const ORDERS: [OrderSetting; 6] = [
        OrderSetting::Fixed(0),
        OrderSetting::Fixed(2),
        OrderSetting::Auto,
        OrderSetting::Fixed(1),
        OrderSetting::Fixed(4),
        OrderSetting::Fixed(3),
    ];
    let order = ORDERS[state.order_changes % ORDERS.len()];
    state.order_changes += 1;
    // The latest fits' own settings but the order: the same data, as after a retune.
    let settings = Settings {
        order,
        ..state
            .fitted_with
            .clone()
            .unwrap_or_else(|| state.settings.clone())
    };
    reidentify(state, &settings, true)
}

fn retune_order0_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let order = std::mem::replace(&mut state.settings.order, OrderSetting::Fixed(0));
    let result = retune_cold_stage(state);
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
    let fits = BenchState::need(&state.fits, "rewelch", "structural_fit")?;
    let previous = &state.factorisations;
    let cached = spectra_and_factorisations(&mut state.planner, signals, rate, &settings.welch, previous)?;
    for ((sig, (sp, f)), fit) in signals.iter().zip(cached).zip(fits) {
        identify_block_from(sig.block, sp, f, &settings, Some(fit))?;
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
        Stage::repeated("retune_order", RETUNES, retune_order_stage),
        Stage::repeated("retune_cold", RETUNES, retune_cold_stage),
        Stage::repeated("retune_order0", RETUNES, retune_order0_stage),
        Stage::once("diagnose", diagnose_stage),
        Stage::once("rewelch", rewelch_stage),
        Stage::once("spectra_bare", bare_stage),
    ]
}
