//! What widgets ask for. Pushed during `ui`, applied at the start of the next `logic`.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::dialog::JSON;
use super::prompt::PathPurpose;
use super::{App, RunEntry};
use crate::block::Block;
use crate::effect::Effect;
use crate::gui::pipeline::{Job, JobKind, RunId, Stage, ValidationKey};
use crate::ident::settings::Settings;

/// A request from the UI.
#[derive(Debug)]
#[must_use]
pub enum Command {
    /// Show the file dialog and open what is picked.
    OpenDialog,
    /// Load these run files.
    Open(Vec<PathBuf>),
    /// Write the session (runs, settings, effects, view) here (`None`: ask with a save dialog).
    SaveSession(Option<PathBuf>),
    /// Reopen the session saved here (`None`: ask with a dialog).
    OpenSession(Option<PathBuf>),
    /// Stop loading a run.
    CancelLoad(RunId),
    /// Remove a run from the list.
    Remove(RunId),
    /// Show this run.
    Select(RunId),
    /// New identifier settings (Welch, band, A, Lambda, order, blocks).
    SetSettings(Box<Settings>),
    /// Forget one error message.
    DismissError(usize),
    /// Write the selected run's model JSON here (`None`: ask with a save dialog).
    ExportModel(Option<PathBuf>),
    /// Write the current view as PNG here (`None`: ask with a save dialog).
    ExportPng(Option<PathBuf>),
    /// Write the selected run's certificate (HTML) here (`None`: ask with a dialog).
    ExportReport(Option<PathBuf>),
    /// Write every loaded run's results table (CSV, or JSON by the name) here (`None`: ask).
    ExportResults(Option<PathBuf>),
    /// Add a run to, or remove it from, the comparison.
    ToggleCompare(RunId),
    /// Find the missing effects of this run.
    Diagnose(RunId),
    /// Keep a named effect (`block`, effect id) in the run's model.
    AcceptEffect(RunId, Block, Effect),
    /// Drop a named effect (`block`, effect id) and diagnose again without it.
    RejectEffect(RunId, Block, Effect),
    /// Forget the run's rejections and diagnose again.
    ClearRejected(RunId),
    /// Ask for a typed path for `purpose` (instead of the system's dialog).
    PromptPath(PathPurpose),
    /// Close the typed-path window.
    ClosePrompt,
    /// Predict this run's outputs of `block` with the model identified on `model_run` (itself
    /// or another loaded run).
    Validate {
        /// The run whose outputs are predicted.
        run: RunId,
        /// The run whose model predicts them.
        model_run: RunId,
        /// The block.
        block: Block,
    },
    /// Fault injection: make the worker panic in `stage` of this run's analysis, as a bug would.
    InjectPanic(RunId, Stage),
}

impl App {
    /// Queues a command for the next `logic` pass.
    pub fn push_command(&mut self, command: Command) {
        self.commands.push(command);
    }

    pub(super) fn apply(&mut self, command: Command) {
        match command {
            Command::OpenDialog => self.ask(super::dialog::DialogRequest::open_runs()),
            Command::PromptPath(purpose) => self.prompt_path(purpose, None),
            Command::ClosePrompt => self.prompt = None,
            Command::Open(paths) => {
                for p in paths {
                    self.open(p);
                }
            }
            Command::SaveSession(path) => match path {
                Some(path) => self.save_session(&path),
                None => self.save_dialog(PathPurpose::SaveSession, JSON, "_session.json"),
            },
            Command::OpenSession(path) => match path {
                Some(path) => self.open_session(&path),
                None => self.open_dialog(PathPurpose::OpenSession),
            },
            Command::CancelLoad(id) => {
                if let Some(reading) = self.run(id).and_then(|r| r.reading.as_ref()) {
                    reading.cancel.store(true, Ordering::Relaxed);
                }
            }
            Command::Remove(id) => {
                if let Some(reading) = self.run(id).and_then(|r| r.reading.as_ref()) {
                    reading.cancel.store(true, Ordering::Relaxed);
                }
                self.runs.retain(|r| r.id != id);
                self.compared.retain(|r| *r != id);
                // A closed run's computing errors are moot.
                self.errors.clear(super::ErrorTopic::Analysis(id));
                self.errors.clear(super::ErrorTopic::Diagnosis(id));
                let generation = self.next_generation();
                self.worker.submit(Job {
                    run: id,
                    generation,
                    kind: JobKind::Forget,
                });
                if self.selected == Some(id) {
                    self.selected = self.runs.first().map(|r| r.id);
                }
            }
            Command::Select(id) => self.selected = Some(id),
            Command::SetSettings(settings) => {
                if *settings != self.prefs.settings {
                    self.prefs.settings = *settings;
                    let ids: Vec<RunId> = self.runs.iter().filter(|r| r.loaded()).map(|r| r.id).collect();
                    for id in ids {
                        self.analyse(id);
                    }
                }
            }
            Command::ExportModel(path) => match path {
                Some(path) => self.export_model(&path),
                None => self.save_dialog(PathPurpose::ExportModel, JSON, "_model.json"),
            },
            Command::ExportResults(path) => match path {
                Some(path) => self.export_results(path),
                None => self.save_dialog(PathPurpose::ExportResults, ("csv", &["csv"]), "_results.csv"),
            },
            Command::ExportReport(path) => match path {
                Some(path) => self.export_report(path),
                None => self.save_dialog(PathPurpose::ExportReport, ("html", &["html"]), "_report.html"),
            },
            Command::ExportPng(path) => match path {
                Some(path) => self.screenshots.pending = Some(path),
                None => self.save_dialog(PathPurpose::ExportPng, ("png", &["png"]), "_view.png"),
            },
            Command::ToggleCompare(id) => {
                if self.compared.contains(&id) {
                    self.compared.retain(|r| *r != id);
                } else {
                    self.compared.push(id);
                }
            }
            Command::Diagnose(id) => self.diagnose(id),
            Command::Validate {
                run,
                model_run,
                block,
            } => self.validate(run, model_run, block),
            Command::AcceptEffect(id, block, effect) => {
                let pair = (block, effect);
                if let Some(run) = self.run_mut(id)
                    && !run.accepted.contains(&pair)
                {
                    run.accepted.push(pair);
                    // The model shown and exported becomes the identified one with the effect.
                    self.analyse(id);
                }
            }
            Command::RejectEffect(id, block, effect) => {
                let pair = (block, effect);
                if let Some(run) = self.run_mut(id) {
                    let was_accepted = run.accepted.contains(&pair);
                    run.accepted.retain(|p| *p != pair);
                    if !run.rejected.contains(&pair) {
                        run.rejected.push(pair);
                    }
                    if was_accepted {
                        self.analyse(id);
                    }
                    self.diagnose(id);
                }
            }
            Command::ClearRejected(id) => {
                if let Some(run) = self.run_mut(id) {
                    run.rejected.clear();
                    self.diagnose(id);
                }
            }
            Command::InjectPanic(id, stage) => self.request(id, JobKind::InjectPanic { stage }),
            Command::DismissError(index) => self.errors.dismiss(index),
        }
    }

    pub(super) fn open(&mut self, path: PathBuf) -> RunId {
        let id = self.next_run;
        self.next_run += 1;
        let generation = self.next_generation();
        let cancel = Arc::new(AtomicBool::new(false));
        self.runs
            .push(RunEntry::loading(id, path.clone(), generation, cancel.clone()));
        if self.selected.is_none() {
            self.selected = Some(id);
        }
        self.worker.submit(Job {
            run: id,
            generation,
            kind: JobKind::Load { path, cancel },
        });
        id
    }

    /// Asks the worker to bring a loaded run's stages up to date with the current settings.
    pub(super) fn analyse(&mut self, id: RunId) {
        let settings = Box::new(self.prefs.settings.clone());
        let accepted = self.run(id).map(|r| r.accepted.clone()).unwrap_or_default();
        self.request(id, JobKind::Analyse { settings, accepted });
    }

    fn diagnose(&mut self, id: RunId) {
        let settings = Box::new(self.prefs.settings.clone());
        let generation = self.next_generation();
        let Some(run) = self.run_mut(id) else { return };
        if !run.loaded() {
            return;
        }
        run.diagnosis.request(generation);
        let rejected = run.rejected.clone();
        self.worker.submit(Job {
            run: id,
            generation,
            kind: JobKind::Diagnose { settings, rejected },
        });
    }

    /// Submits the prediction of `id`'s outputs of `block` by `model_run`'s identified model (both
    /// identified; otherwise nothing happens: the Validation tab says what it waits for).
    fn validate(&mut self, id: RunId, model_run: RunId, block: Block) {
        let Some((model, model_generation)) = self.run(model_run).and_then(|r| {
            let id = r.identification.as_ref()?;
            let m = id.model.blocks.get(block.name())?;
            Some((Arc::new(m.clone()), r.identification.generation))
        }) else {
            return;
        };
        let settings = Box::new(self.prefs.settings.clone());
        let generation = self.next_generation();
        let Some(run) = self.run_mut(id) else { return };
        let Some(data_generation) = run
            .identification
            .is_some()
            .then_some(run.identification.generation)
        else {
            return;
        };
        let key = ValidationKey {
            model_run,
            block,
            model_generation,
            data_generation,
        };
        run.validation.request(generation);
        run.validation_wanted = Some(key.clone());
        self.worker.submit(Job {
            run: id,
            generation,
            kind: JobKind::Validate { settings, model, key },
        });
    }

    /// Submits an analysis-like job whose result (or failure) the run waits for.
    fn request(&mut self, id: RunId, kind: JobKind) {
        let generation = self.next_generation();
        if let Some(run) = self.run_mut(id) {
            run.spectra.request(generation);
            run.identification.request(generation);
        }
        self.worker.submit(Job {
            run: id,
            generation,
            kind,
        });
    }
}
