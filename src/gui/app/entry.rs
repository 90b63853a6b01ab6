//! One run in the run list: its file, and one [`StageRecord`] per computed stage (load,
//! observer, spectra, identification, diagnosis, validation), each holding the newest good value,
//! its generation, the newest generation requested and why that request failed. The only state
//! outside the records is what belongs to none of them: the read's progress while the file is
//! being read, and the engineer's accepted and rejected effects.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::block::Block;
use crate::effect::Effect;
use crate::gui::pipeline::{
    Diagnosis, Identification, Measured, Motion, RunId, RunSummary, Spectra, Validated, ValidationKey,
};

use super::StageRecord;

/// The load stage's value: what the file holds.
#[derive(Debug)]
pub struct LoadedRun {
    /// Summary (name, SHA-256, blocks, rate, notices, recording faults).
    pub summary: Arc<RunSummary>,
    /// Measured series.
    pub measured: Arc<Measured>,
}

/// A read under way.
#[derive(Clone, Debug)]
pub struct Reading {
    /// Bytes read / total.
    pub fraction: f32,
    /// Set to cancel.
    pub cancel: Arc<AtomicBool>,
}

/// One run in the run list, with the newest good result of each stage.
#[derive(Clone, Debug)]
pub struct RunEntry {
    /// Session id.
    pub id: RunId,
    /// File.
    pub path: PathBuf,
    /// The read's progress, while the file is being read (`None` once it is done).
    pub reading: Option<Reading>,
    /// The file's contents (requested once, with the load job's generation).
    pub load: StageRecord<LoadedRun>,
    /// Observer and block inputs: computed once per run, by the first analysis that reaches
    /// the observer (they do not depend on the settings); an observer failure is its error.
    pub motion: StageRecord<Motion>,
    /// Spectra (the last good ones), requested with every analysis.
    pub spectra: StageRecord<Spectra>,
    /// Identification (the last good one), requested with every analysis.
    pub identification: StageRecord<Identification>,
    /// The missing-effect report (the last good one; results of older requests are dropped).
    pub diagnosis: StageRecord<Diagnosis>,
    /// A model's prediction of the outputs (the Validation tab; the last good one).
    pub validation: StageRecord<Validated>,
    /// What the latest validation request answers.
    pub validation_wanted: Option<ValidationKey>,
    /// The SHA-256 a reopened session recorded for the file (checked when it loads).
    pub expected_sha256: Option<String>,
    /// Effects the engineer accepted (kept in the model shown).
    pub accepted: Vec<(Block, Effect)>,
    /// Effects the engineer rejected (never offered again).
    pub rejected: Vec<(Block, Effect)>,
}

impl RunEntry {
    pub(super) fn loading(id: RunId, path: PathBuf, generation: u64, cancel: Arc<AtomicBool>) -> Self {
        let mut load = StageRecord::default();
        load.request(generation);
        Self {
            id,
            path,
            reading: Some(Reading {
                fraction: 0.0,
                cancel,
            }),
            load,
            motion: StageRecord::default(),
            spectra: StageRecord::default(),
            identification: StageRecord::default(),
            diagnosis: StageRecord::default(),
            validation: StageRecord::default(),
            validation_wanted: None,
            expected_sha256: None,
            accepted: Vec::new(),
            rejected: Vec::new(),
        }
    }

    /// The run's summary, once loaded.
    #[must_use]
    pub fn summary(&self) -> Option<&Arc<RunSummary>> {
        self.load.as_ref().map(|l| &l.summary)
    }

    /// The measured series, once loaded.
    #[must_use]
    pub fn measured(&self) -> Option<&Arc<Measured>> {
        self.load.as_ref().map(|l| &l.measured)
    }

    /// Whether the file has been read.
    #[must_use]
    pub fn loaded(&self) -> bool {
        self.load.is_some()
    }

    /// Computing: loading, or an analysis newer than the identification shown is under way.
    #[must_use]
    pub fn busy(&self) -> bool {
        let refitting = self.identification.as_ref().is_some_and(|i| i.provisional());
        self.reading.is_some()
            || self.identification.running()
            || (self.identification.error.is_none() && refitting)
    }

    /// The file name shown.
    #[must_use]
    pub fn name(&self) -> String {
        self.path
            .file_name()
            .map_or_else(|| self.path.display().to_string(), |n| n.to_string_lossy().into())
    }
}
