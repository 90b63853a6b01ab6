//! The benchmark's state and its standard stage list. Every stage calls the core's one pipeline
//! ([`Session`]); the `identify` and `structural_fit` stages time the Wiener estimate and the
//! structural fit apart, on the session's cached spectra and factorisations.
//!
//! | stage | what is timed |
//! |---|---|
//! | `load` | reading the CSV and its sidecar into columns |
//! | `observer` | the observer's motion estimate and every block's inputs `u` (the "observer inputs") |
//! | `spectra` | the zero-padded Welch matrices of `[u; x]` of every block |
//! | `factorisation` | the factorisation stage of every block (the blocks in parallel) |
//! | `identify` | the regularised Wiener estimate `W_u` (A, Lambda) of every block |
//! | `structural_fit` | the structural fit (order) of every block |
//! | `retune` | a change of Lambda, as the app does it: Wiener and structural fit of every block from cached spectra and factorisation, the fit starting from the previous one ([`Session::identify`] with [`Start::Warm`]), median of [`RETUNES`] successive changes after one untimed (the session's first identification, from scratch, as the app's on opening) |
//! | `retune_order` | a change of the model order (cycling through `0..=4` and `auto`) on unchanged data, from the previous fit |
//! | `retune_cold` | `retune` with the structural fit from scratch (what `identify` does) |
//! | `retune_order0` | `retune_cold` with the order fixed at 0 (`K e^(-tau s)`) instead of the settings' order |
//! | `noise` | the noise terms of every block of the latest identification ([`crate::noise::of_model::attach_noise`]: residual of the model over the record, Allan deviations, term fits), as `identify` and the app's model export add them |
//! | `suspect` | the test of the latest identification's model for effects it takes in without a misfit ([`crate::diagnose::suspect::suspicions`]: the whole-record design over each block's band and the tested effect's fit, the blocks in parallel; the rivals only where it gains), as `identify` adds it |
//! | `diagnose` | the missing-effect workflow on the session ([`crate::diagnose::diagnose_session`]): the observer, spectra and factorisations are the session's; its order-0 fit over the search band is timed |
//! | `rewelch` | a change of the Welch settings (overlap 0.5 -> 0.6), as the app shows it at once: spectra, factorisation (Wilson started from the previous factors), Wiener and structural fit (from the previous fit) of every block from the cached observer inputs |
//! | `spectra_bare` | the lower bound of `spectra`: [`super::bare`]'s loop of the same FFTs and cross products |
//! | `open_to_model` | everything from the file to the model, as `identify` and the app do it on opening a run: load, observer, spectra, factorisation, Wiener and structural fit (a fresh session; the earlier stages' caches are dropped first) |

use std::path::PathBuf;
use std::sync::Arc;

use super::{BenchError, Stage, bare};
use crate::block::Block;
use crate::ident::IdentError;
use crate::ident::band::native_bins;
use crate::ident::factorisation::Factorisation;
use crate::ident::identify::{RunIdentification, resolve_band, structural_fit};
use crate::ident::session::{Session, Start};
use crate::ident::settings::{LambdaSetting, OrderSetting, Settings};
use crate::ident::signals::channel_names;
use crate::ident::spectra::BlockSpectra;
use crate::ident::wiener::{WienerEstimate, regularised_wiener};
use crate::run::{LoadOptions, Run, load};
use crate::spectral::WelchSettings;

/// Lambda changes timed by the `retune` stage.
pub const RETUNES: usize = 9;
/// Overlap the `rewelch` stage changes the Welch settings to.
pub const REWELCH_OVERLAP: f64 = 0.6;

/// One block's cached spectra and factorisation.
type Cached = (Block, Arc<BlockSpectra>, Arc<Factorisation>);

/// What the stages hand each other.
#[derive(Debug)]
pub struct BenchState {
    /// The run file.
    pub path: PathBuf,
    /// Identification settings (blocks filled in by `load`).
    pub settings: Settings,
    /// The loaded run's pipeline.
    pub session: Option<Session>,
    /// Every block's Wiener estimate (the `identify` stage).
    pub wiener: Vec<WienerEstimate>,
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
            session: None,
            wiener: Vec::new(),
            retunes: 0,
            order_changes: 0,
        }
    }

    /// The loaded run.
    #[must_use]
    pub fn run(&self) -> Option<&Arc<Run>> {
        self.session.as_ref().map(Session::run)
    }

    /// Number of distinct channels whose spectra are computed (`u` and `x` of every block).
    #[must_use]
    pub fn channels(&self) -> usize {
        let mut names: Vec<&str> = self
            .settings
            .blocks
            .iter()
            .flat_map(|&b| {
                let (u, x) = channel_names(b);
                u.into_iter().chain(x)
            })
            .collect();
        names.sort_unstable();
        names.dedup();
        names.len()
    }

    fn session(&mut self, stage: &'static str) -> Result<&mut Session, BenchError> {
        self.session
            .as_mut()
            .ok_or(BenchError::Missing { stage, needs: "load" })
    }

    /// The session's cached spectra and factorisations of every block (computed if missing).
    fn cached(&mut self, stage: &'static str) -> Result<Vec<Cached>, BenchError> {
        let settings = self.settings.clone();
        let session = self.session(stage)?;
        let spectra = session.spectra(&settings, &settings.blocks)?;
        let factorisations = session.factorisations(&settings, &settings.blocks, Start::Cold)?;
        Ok(spectra
            .into_iter()
            .zip(factorisations)
            .map(|((b, s), (_, f))| (b, s, f))
            .collect())
    }
}

fn load_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let run = load(&state.path, &LoadOptions::default())?;
    state.settings = state.settings.for_run(&run);
    state
        .settings
        .validate(run.len(), run.sample_rate_hz, &run.blocks())
        .map_err(IdentError::from)?;
    state.session = Some(Session::new(Arc::new(run)));
    Ok(())
}

fn observer_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let blocks = state.settings.blocks.clone();
    let session = state.session("observer")?;
    session.motion()?;
    for b in blocks {
        session.signals(b)?;
    }
    Ok(())
}

fn spectra_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = state.settings.clone();
    state.session("spectra")?.spectra(&settings, &settings.blocks)?;
    Ok(())
}

fn factorisation_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = state.settings.clone();
    // The blocks at once, as `rewelch` and the app do.
    state
        .session("factorisation")?
        .factorisations(&settings, &settings.blocks, Start::Cold)?;
    Ok(())
}

fn identify_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let cached = state.cached("identify")?;
    let s = &state.settings;
    state.wiener = cached
        .iter()
        .map(|(block, sp, f)| {
            let band_hz = resolve_band(sp, *block, s.band_hz)?;
            regularised_wiener(sp, f, s.estimate, &s.weight(), s.lambda, band_hz)
        })
        .collect::<Result<_, _>>()?;
    Ok(())
}

/// One structural fit per block over the band the coherence finds: a band ended at a misfit
/// (`ident::band_top`) fits a second time in `identify`, which `open_to_model` and the commands'
/// wall times include and this stage does not.
fn structural_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let cached = state.cached("structural_fit")?;
    if state.wiener.len() != cached.len() {
        return Err(BenchError::Missing {
            stage: "structural_fit",
            needs: "identify",
        });
    }
    for ((block, sp, f), w) in cached.iter().zip(&state.wiener) {
        let band_hz = resolve_band(sp, *block, state.settings.band_hz)?;
        let band = native_bins(sp, band_hz);
        std::hint::black_box(structural_fit(
            sp,
            f,
            w,
            &band,
            state.settings.order.of(*block),
            crate::ident::holdout::cached_held_out(sp, band_hz).as_deref(),
            None,
            None,
        )?);
    }
    Ok(())
}

/// The identification with `settings` on the session: warm (the app's retune, from the latest
/// fits) or cold (what `identify` does).
fn reidentify(state: &mut BenchState, settings: &Settings, start: Start) -> Result<(), BenchError> {
    let stage = match start {
        Start::Warm => "retune",
        Start::Cold => "retune_cold",
    };
    std::hint::black_box(state.session(stage)?.identify(settings, start, &mut |_| {})?);
    Ok(())
}

/// The settings with the next Lambda of the `retune` stages.
fn next_lambda(state: &mut BenchState) -> Settings {
    state.retunes += 1;
    // Admissible values (0 <= lambda, well inside the shrink limit), distinct at every call.
    let l = 0.005 * state.retunes as f64;
    Settings {
        lambda: LambdaSetting::Values([l, 0.5 * l, 0.25 * l]),
        ..state.settings.clone()
    }
}

fn retune_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = next_lambda(state);
    reidentify(state, &settings, Start::Warm)
}

fn retune_cold_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = next_lambda(state);
    reidentify(state, &settings, Start::Cold)
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
    // The latest identification's own settings but the order: the same data, as after a retune.
    let latest = state
        .session("retune_order")?
        .identification()
        .map(|(s, _)| s.clone());
    let settings = Settings {
        order: order.into(),
        ..latest.unwrap_or_else(|| state.settings.clone())
    };
    reidentify(state, &settings, Start::Warm)
}

fn retune_order0_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let order = std::mem::replace(&mut state.settings.order, OrderSetting::Fixed(0).into());
    let result = retune_cold_stage(state);
    state.settings.order = order;
    result
}

fn rewelch_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = Settings {
        welch: WelchSettings {
            overlap: REWELCH_OVERLAP,
            ..state.settings.welch
        },
        ..state.settings.clone()
    };
    reidentify(state, &settings, Start::Warm)
}

/// The noise terms of the session's latest identification.
fn noise_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let session = state.session("noise")?;
    let (settings, id) = latest_identification(session, "noise")?;
    let run = session.run().clone();
    let mut model = crate::model::Model::from_identification(&run, &settings, &id);
    crate::noise::of_model::attach_noise(&mut model, session, &settings)?;
    std::hint::black_box(model);
    Ok(())
}

/// The effects the latest identification's model may take in without a misfit, tested as
/// `identify` tests them ([`crate::diagnose::suspect`]).
fn suspect_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let session = state.session("suspect")?;
    let (settings, id) = latest_identification(session, "suspect")?;
    let model = crate::model::Model::from_identification(session.run(), &settings, &id);
    std::hint::black_box(crate::diagnose::suspect::suspicions(
        &model, session, &settings, &id,
    ));
    Ok(())
}

/// The session's latest identification and its settings, which `stage` needs (timed by
/// `retune_cold` before it).
fn latest_identification(
    session: &Session,
    stage: &'static str,
) -> Result<(Settings, Arc<RunIdentification>), BenchError> {
    session
        .identification()
        .map(|(s, i)| (s.clone(), i.clone()))
        .ok_or(BenchError::Missing {
            stage,
            needs: "retune_cold",
        })
}

/// The whole missing-effect workflow on the session.
fn diagnose_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let settings = state.settings.clone();
    let options = crate::diagnose::DiagnoseOptions::default();
    let session = state.session("diagnose")?;
    std::hint::black_box(crate::diagnose::diagnose_session(session, &settings, &options)?);
    Ok(())
}

fn bare_stage(state: &mut BenchState) -> Result<(), BenchError> {
    let (welch, blocks) = (state.settings.welch, state.settings.blocks.clone());
    let session = state.session("spectra_bare")?;
    for b in blocks {
        let s = session.signals(b)?;
        let channels: Vec<&[f64]> = s.input.iter().chain(&s.output).map(Vec::as_slice).collect();
        std::hint::black_box(bare::welch_sums(&channels, &welch)?);
    }
    Ok(())
}

/// From the file to the model in one go, on a fresh session.
fn open_to_model_stage(state: &mut BenchState) -> Result<(), BenchError> {
    state.session = None;
    let run = load(&state.path, &LoadOptions::default())?;
    let settings = state.settings.for_run(&run);
    let mut session = Session::new(Arc::new(run));
    std::hint::black_box(session.identify(&settings, Start::Cold, &mut |_| {})?);
    state.session = Some(session);
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
        Stage::repeated("retune", RETUNES, retune_stage).after_warm_up(),
        Stage::repeated("retune_order", RETUNES, retune_order_stage),
        Stage::repeated("retune_cold", RETUNES, retune_cold_stage),
        Stage::repeated("retune_order0", RETUNES, retune_order0_stage),
        Stage::once("noise", noise_stage),
        Stage::once("suspect", suspect_stage),
        Stage::once("diagnose", diagnose_stage),
        Stage::once("rewelch", rewelch_stage),
        Stage::once("spectra_bare", bare_stage),
        Stage::once("open_to_model", open_to_model_stage),
    ]
}
