//! The GUI's compute pipeline: one named worker thread runs jobs for the runs shown, stage by
//! stage, and sends immutable [`Arc`] snapshots back.
//!
//! Stages per run, each cached in the worker and keyed by what it depends on:
//!
//! | stage | depends on | result sent |
//! |---|---|---|
//! | load | the file | [`Event::Loaded`]: [`RunSummary`] + [`Measured`] |
//! | observer + block inputs | the run (sidecar lever arm, `g`, angle noise) | [`Event::Motion`] |
//! | spectra | block inputs + [`WelchSettings`](crate::spectral::WelchSettings) | [`Event::Spectra`] |
//! | factorisation | the spectra (per block) | (inside the next) |
//! | identification (Wiener + structural fit) | band, estimate, `A`, `Lambda`, order, blocks | [`Event::Identified`] |
//!
//! An [`JobKind::Analyse`] job carries the whole identifier [`Settings`]; each stage looks only at
//! its own key, so a Welch change recomputes the spectra and what follows, while a change of the
//! estimate, `A`, `Lambda` or the order redoes only `identify_block_from` (regularised Wiener + structural fit)
//! from the cached [`crate::ident::spectra::BlockSpectra`] and factorisation. The spectra are
//! computed once, by the identifier's own code, and the spectra tab reads the same snapshot.
//!
//! Jobs carry a generation (increasing over the app's life). The worker drains its queue before
//! working and computes only the newest analysis per run; the app ignores results older than its
//! newest request and keeps showing the last good one meanwhile. A panic inside a job is caught
//! and reported as [`Event::Failed`]; the worker and the cached stages before it survive.

mod analyse;
mod diagnosis;
mod display;
mod identified;
mod series;
mod stages;
mod validation;
mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

pub use diagnosis::{BlockWords, Diagnosis};
pub use display::{BlockSpectra, NativeCsd, Spectra, decibels};
pub use identified::{BAND_FLOOR_DB, BAND_SIGMAS, BlockBode, BodeElement, Identification, deviation};
pub use series::Series;
pub use stages::{Measured, Motion};
pub use worker::{Worker, WorkerMode};

use crate::block::Block;
use crate::effect::Effect;
use crate::ident::settings::Settings;

/// Identifies a run inside one app session.
pub type RunId = u64;

/// A unit of work for the worker.
#[derive(Debug)]
pub struct Job {
    /// The run it concerns.
    pub run: RunId,
    /// Increasing request number; results carry it back.
    pub generation: u64,
    /// What to do.
    pub kind: JobKind,
}

/// What a job does.
#[derive(Debug)]
pub enum JobKind {
    /// Load a run file; setting `cancel` stops the loader at its next progress report.
    Load {
        /// CSV or CSV.gz path.
        path: PathBuf,
        /// Set by the app to cancel.
        cancel: Arc<AtomicBool>,
    },
    /// Bring every stage of a loaded run up to date with these settings.
    Analyse {
        /// The identifier settings; each stage uses its own part.
        settings: Box<Settings>,
        /// Effects the engineer accepted into the model (`diagnose::extend`): the model shown,
        /// plotted and exported is the identified one extended by them.
        accepted: Vec<(Block, Effect)>,
    },
    /// Find the missing effects of a loaded run (on request: it takes seconds).
    Diagnose {
        /// The identifier settings.
        settings: Box<Settings>,
        /// Effects the engineer rejected, never offered again.
        rejected: Vec<(Block, Effect)>,
    },
    /// Write the run's model file to `path`, its noise terms computed on the worker's cached
    /// session (as `identify` writes it).
    ExportModel {
        /// Where the JSON goes.
        path: PathBuf,
    },
    /// Write the results table of `runs` (`crate::batch::table`: one row per run and block, the
    /// noise terms computed on the worker) to `path`, CSV or JSON by its extension.
    ExportResults {
        /// The runs, in the table's order.
        runs: Vec<RunId>,
        /// Where the table goes.
        path: PathBuf,
    },
    /// Write the run's certificate (`crate::report`) to `path`: the identification, noise
    /// terms and diagnosis on the worker's cached session.
    Report {
        /// The identifier settings.
        settings: Box<Settings>,
        /// Where the HTML goes.
        path: PathBuf,
    },
    /// Predict the run's outputs of `block` with `model` (identified on this run or another) and
    /// compare them with the measured ones (`crate::model::validation`).
    Validate {
        /// The identifier settings (their span).
        settings: Box<Settings>,
        /// The model, and the file it was identified on.
        model: Arc<crate::model::BlockModel>,
        /// What the result answers (shown with it; tells a stale result from the wanted one).
        key: ValidationKey,
    },
    /// Drop the run's cached stages.
    Forget,
    /// Fault injection: panics inside the worker as a bug in `stage` would (tests of the panic
    /// guard and of how the app shows it).
    InjectPanic {
        /// The stage the panic is reported in.
        stage: Stage,
    },
}

/// The pipeline stage a result or failure belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Reading the file.
    Load,
    /// Observer and block inputs.
    Motion,
    /// Welch spectral matrices.
    Spectra,
    /// Spectral factorisation.
    Factorisation,
    /// Regularised Wiener estimate and structural fit.
    Identify,
    /// The missing-effect diagnosis.
    Diagnose,
    /// A model's prediction of a run's outputs.
    Validate,
    /// Writing a model file or the certificate.
    Export,
}

impl Stage {
    /// Lower-case name for messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Stage::Load => "load",
            Stage::Motion => "observer",
            Stage::Spectra => "spectra",
            Stage::Factorisation => "factorisation",
            Stage::Identify => "identification",
            Stage::Diagnose => "diagnosis",
            Stage::Validate => "validation",
            Stage::Export => "export",
        }
    }
}

/// What a validation answers: which run's model, of which block, as identified when.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValidationKey {
    /// The run the model was identified on.
    pub model_run: RunId,
    /// The block.
    pub block: Block,
    /// The generation of the model run's identification used.
    pub model_generation: u64,
    /// The generation of the validated run's identification (its span and settings).
    pub data_generation: u64,
}

/// A model's prediction of a run's outputs, ready to plot.
#[derive(Debug)]
pub struct Validated {
    /// What it answers.
    pub key: ValidationKey,
    /// The file the model was identified on.
    pub model_file: String,
    /// The model's band, Hz (both signals low-passed at its top).
    pub band_hz: [f64; 2],
    /// Fit per output channel, percent.
    pub fit_percent: [f64; 3],
    /// Per output channel: measured, predicted and their difference (the residual).
    pub channels: [[Series; 3]; 3],
}

/// What a loaded run is, for the run list.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// File name (`cruise.csv.gz`).
    pub file_name: String,
    /// Path as loaded.
    pub path: PathBuf,
    /// Regime from the sidecar (or the file stem).
    pub regime: String,
    /// Number of samples.
    pub n_samples: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// `t_last - t_first`, s.
    pub duration_s: f64,
    /// Time of the first sample, s (the file's time column).
    pub start_s: f64,
    /// Blocks present, gyro first.
    pub blocks: Vec<Block>,
    /// SHA-256 of the file as stored (for the model's source).
    pub sha256: String,
    /// Loader notices (missing sidecar, unknown columns, ...).
    pub notices: Vec<String>,
    /// Faults of the recording itself (glitches, held samples, clipping), as `identify` finds
    /// them: shown with the run and written into the exported model.
    pub recording_faults: Vec<crate::faults::RecordingFault>,
    /// The run itself, shared (the settings panel checks a span's samples against it).
    pub run: Arc<crate::run::Run>,
}

/// A message from the worker.
#[derive(Debug)]
pub enum Event {
    /// Load progress, `fraction` in `[0, 1]`.
    Progress {
        /// The run.
        run: RunId,
        /// Bytes read over bytes total.
        fraction: f32,
    },
    /// The run loaded.
    Loaded {
        /// The run.
        run: RunId,
        /// The load job's generation.
        generation: u64,
        /// For the run list.
        summary: Arc<RunSummary>,
        /// Measured angles and block outputs.
        measured: Arc<Measured>,
    },
    /// Observer estimate and block inputs ready.
    Motion {
        /// The run.
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// The result.
        motion: Arc<Motion>,
    },
    /// Spectral matrices ready.
    Spectra {
        /// The run.
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// The result.
        spectra: Arc<Spectra>,
    },
    /// The identification (model, curves) ready.
    Identified {
        /// The run.
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// The result.
        identification: Arc<Identification>,
    },
    /// The missing-effect report ready.
    Diagnosed {
        /// The run.
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// The report and its words.
        diagnosis: Arc<Diagnosis>,
    },
    /// A model's prediction of the run's outputs ready.
    Validated {
        /// The run (whose outputs are predicted).
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// The result.
        validation: Arc<Validated>,
    },
    /// A file was written (a model file or the certificate).
    Written {
        /// The run.
        run: RunId,
        /// What (`model`, `report`).
        what: &'static str,
        /// Where.
        path: PathBuf,
    },
    /// A stage failed (error or caught panic); earlier results stay valid.
    Failed {
        /// The run.
        run: RunId,
        /// The job's generation.
        generation: u64,
        /// Where.
        stage: Stage,
        /// What went wrong, one line.
        message: String,
        /// Whose fault: the input's, ours, or a cancelled load.
        kind: FailureKind,
    },
}

/// What kind of failure an [`Event::Failed`] is: one classification with the command line's
/// exit status 2 (input) versus 1 (internal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailureKind {
    /// The run, or settings that do not fit it: the user can fix it.
    Input,
    /// Our fault (a numerical failure, a panic): worth a bug report.
    Internal,
    /// The user cancelled a load.
    Cancelled,
}

impl FailureKind {
    /// From an error's own classification.
    #[must_use]
    pub fn of(input: bool) -> Self {
        if input {
            FailureKind::Input
        } else {
            FailureKind::Internal
        }
    }
}
