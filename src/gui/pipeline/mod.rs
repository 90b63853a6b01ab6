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
//!
//! An [`JobKind::Analyse`] job carries the whole identifier [`Settings`]; each stage looks only at
//! its own key, so a Welch change recomputes the spectra alone, and the stages that follow the
//! spectra (factorisation, identifier, structural fit) key on band, `A`, `Lambda`, order and
//! blocks without redoing them.
//!
//! Jobs carry a generation (increasing over the app's life). The worker drains its queue before
//! working and computes only the newest analysis per run; the app ignores results older than its
//! newest request and keeps showing the last good one meanwhile. A panic inside a job is caught
//! and reported as [`Event::Failed`]; the worker and the cached stages before it survive.

mod series;
mod stages;
mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

pub use series::Series;
pub use stages::{BlockSpectra, Measured, Motion, Spectra, decibels};
pub use worker::{Worker, WorkerMode};

use crate::block::Block;
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
    },
    /// Drop the run's cached stages.
    Forget,
    /// Panics inside the worker (unit tests of the panic guard only).
    #[cfg(test)]
    PanicForTest,
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
}

impl Stage {
    /// Lower-case name for messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Stage::Load => "load",
            Stage::Motion => "observer",
            Stage::Spectra => "spectra",
        }
    }
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
    /// Blocks present, gyro first.
    pub blocks: Vec<Block>,
    /// Loader notices (missing sidecar, unknown columns, ...).
    pub notices: Vec<String>,
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
        /// The user cancelled a load.
        cancelled: bool,
    },
}
