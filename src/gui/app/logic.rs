//! The non-drawing half of a frame: commands, dropped files, worker events, textures.

use std::sync::Arc;
use std::time::{Duration, Instant};

use eframe::egui;

use super::{App, Command, ErrorTopic, HeatmapMode, LoadedRun, RunEntry};
use crate::block::Block;
use crate::compare::compare;
use crate::gui::pipeline::{Event, FailureKind, RunId, Stage};
use crate::gui::view::colormap;
use crate::model::Model;

/// Longest time spent draining worker events in one pass.
const DRAIN_BUDGET: Duration = Duration::from_millis(10);

/// What the pair-grid texture shows: run, spectra generation, block, mode.
pub(super) type TextureKey = (RunId, u64, Block, HeatmapMode);

/// What the comparison was computed from: each compared run and its identification generation.
/// The compared runs with their identification's and diagnosis's generations (0: none).
pub(super) type ComparisonKey = Vec<(RunId, u64, u64)>;

impl App {
    pub(super) fn logic_pass(&mut self, ctx: &egui::Context) {
        let dropped: Vec<_> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if !dropped.is_empty() {
            self.push_command(Command::Open(dropped));
        }
        self.poll_dialog();
        for command in std::mem::take(&mut self.commands) {
            self.apply(command);
        }
        self.drain_events(ctx);
        self.update_comparison();
        self.update_validation();
        self.screenshot_pass(ctx);
        self.update_pair_texture(ctx);
    }

    /// Applies pending commands and worker events now (tests with a synchronous worker).
    pub fn process_pending(&mut self) {
        for _ in 0..8 {
            let commands = std::mem::take(&mut self.commands);
            if commands.is_empty() {
                break;
            }
            for command in commands {
                self.apply(command);
            }
        }
        while let Ok(event) = self.worker.events.try_recv() {
            self.handle(event);
        }
        self.update_comparison();
        self.update_validation();
    }

    /// On the Validation tab: asks for the prediction the tab should show (the selected run's
    /// outputs of the shown block, by the chosen run's model) when it is not the one last asked
    /// for, e.g. after a new identification of either run.
    fn update_validation(&mut self) {
        if self.prefs.view.tab != super::Tab::Validation {
            return;
        }
        let Some(id) = self.selected else { return };
        let block = self.prefs.view.bode_block;
        let model_run = self.prefs.view.validation_model.unwrap_or(id);
        let (Some(run), Some(model)) = (self.run(id), self.run(model_run)) else {
            return;
        };
        if run.identification.is_none() || model.identification.is_none() {
            return;
        }
        // A block the model's run refused has no model to predict with (the tab says so).
        if model
            .identification
            .as_ref()
            .is_some_and(|m| m.block_model(block).is_none())
        {
            return;
        }
        let wanted = crate::gui::pipeline::ValidationKey {
            model_run,
            block,
            model_generation: model.identification.generation,
            data_generation: run.identification.generation,
        };
        if run.validation_wanted.as_ref() != Some(&wanted) {
            self.push_command(Command::Validate {
                run: id,
                model_run,
                block,
            });
        }
    }

    /// Recomputes the comparison when the compared runs or their identifications changed.
    fn update_comparison(&mut self) {
        let key: ComparisonKey = self
            .compared
            .iter()
            .filter_map(|&id| self.run(id))
            .filter(|r| r.identification.is_some())
            .map(|r| (r.id, r.identification.generation, r.diagnosis.generation))
            .collect();
        if key.len() < 2 {
            self.comparison = None;
            return;
        }
        if self.comparison.as_ref().is_some_and(|(k, _)| *k == key) {
            return;
        }
        let entries: Vec<&RunEntry> = key.iter().filter_map(|&(id, _, _)| self.run(id)).collect();
        let models: Vec<Model> = entries
            .iter()
            .filter_map(|r| r.identification.as_ref().map(|i| i.model.clone()))
            .collect();
        let mut comparison = compare(&models).ok();
        // Every compared run diagnosed (Find missing effects): their findings compared too.
        let reports: Vec<&crate::diagnose::Report> = entries
            .iter()
            .filter_map(|r| r.diagnosis.value.as_deref().map(|d| &d.report))
            .collect();
        // Only diagnoses made under one set of settings are comparable.
        let same_settings = reports
            .windows(2)
            .all(|w| w[0].settings.same_request(&w[1].settings));
        if let Some(c) = comparison
            .as_mut()
            .filter(|_| reports.len() == entries.len() && same_settings)
        {
            let names: Vec<String> = entries.iter().map(|r| r.name()).collect();
            c.add_findings(&reports, &names);
        }
        self.comparison = comparison.map(|c| (key, Arc::new(c)));
    }

    fn drain_events(&mut self, ctx: &egui::Context) {
        let start = Instant::now();
        while let Ok(event) = self.worker.events.try_recv() {
            self.frame_events += 1;
            self.handle(event);
            if start.elapsed() > DRAIN_BUDGET {
                ctx.request_repaint();
                break;
            }
        }
    }

    fn handle(&mut self, event: Event) {
        match event {
            Event::Progress { run, fraction } => {
                if let Some(reading) = self.run_mut(run).and_then(|r| r.reading.as_mut()) {
                    reading.fraction = fraction;
                }
            }
            Event::Loaded {
                run,
                generation,
                summary,
                measured,
            } => {
                let Some(entry) = self.run_mut(run).filter(|r| r.load.requested == generation) else {
                    return;
                };
                entry.reading = None;
                let changed = entry
                    .expected_sha256
                    .take()
                    .filter(|sha| *sha != summary.sha256)
                    .map(|_| format!(
                        "{}: the file has changed since the session was saved (its SHA-256 differs): the results are not the session's",
                        summary.file_name
                    ));
                let path = summary.path.clone();
                entry
                    .load
                    .offer(generation, Arc::new(LoadedRun { summary, measured }));
                if let Some(message) = changed {
                    self.errors.push(ErrorTopic::Load, message);
                }
                self.remember_recent(&path);
                self.analyse(run);
            }
            Event::Motion {
                run,
                generation,
                motion,
            } => {
                // The observer runs once per run (the settings do not change it): the first
                // analysis that gets through it answers, with its generation.
                if let Some(entry) = self.run_mut(run) {
                    entry.motion.offer(generation, motion);
                }
            }
            Event::Spectra {
                run,
                generation,
                spectra,
            } => {
                let Some(entry) = self.run_mut(run) else { return };
                // Only the newest analysis's spectra (an older job's would flicker).
                if generation >= entry.spectra.requested {
                    entry.spectra.offer(generation, spectra);
                }
            }
            Event::Identified {
                run,
                generation,
                identification,
            } => {
                let Some(entry) = self.run_mut(run) else { return };
                // The same generation again is its refit from scratch (see `provisional`).
                entry.identification.offer(generation, identification);
                // An identification went through the observer: an earlier observer failure is
                // moot (the observer's result is cached, so no new one may come).
                entry.motion.error = None;
                if entry.identification.error.is_none() && generation >= entry.identification.requested {
                    self.errors.clear(ErrorTopic::Analysis(run));
                }
            }
            Event::Diagnosed {
                run,
                generation,
                diagnosis,
            } => {
                let Some(entry) = self.run_mut(run) else { return };
                // A stale report (an older request finishing after a newer one) never replaces
                // the newer one: only the newest request's report is taken.
                if generation >= entry.diagnosis.requested {
                    entry.diagnosis.offer(generation, diagnosis);
                    self.errors.clear(ErrorTopic::Diagnosis(run));
                }
            }
            Event::Validated {
                run,
                generation,
                validation,
            } => {
                let Some(entry) = self.run_mut(run) else { return };
                if generation >= entry.validation.requested {
                    entry.validation.offer(generation, validation);
                    self.errors.clear(ErrorTopic::Validation(run));
                }
            }
            Event::Written { what, path, .. } => {
                self.status = Some(format!("{what} written to {}", path.display()));
            }
            Event::Failed {
                stage: Stage::Export,
                message,
                kind,
                ..
            } => {
                self.status = None;
                self.errors.push(
                    ErrorTopic::Export,
                    format!("export: {}", described(&message, kind)),
                );
            }
            Event::Failed {
                stage: stage @ (Stage::Validate | Stage::Diagnose),
                run,
                generation,
                message,
                kind,
            } => {
                let Some(entry) = self.run_mut(run) else { return };
                let message = described(&message, kind);
                let (failed, topic) = if stage == Stage::Validate {
                    (
                        entry.validation.fail(generation, message.clone()),
                        ErrorTopic::Validation(run),
                    )
                } else {
                    (
                        entry.diagnosis.fail(generation, message.clone()),
                        ErrorTopic::Diagnosis(run),
                    )
                };
                if !failed {
                    return;
                }
                let name = entry.name();
                self.errors
                    .push(topic, format!("{name}: {}: {message}", stage.name()));
            }
            Event::Failed {
                run,
                generation,
                stage,
                message,
                kind,
            } => self.failed(run, generation, stage, &message, kind),
        }
    }

    fn failed(&mut self, run: RunId, generation: u64, stage: Stage, message: &str, kind: FailureKind) {
        let message = described(message, kind);
        let Some(entry) = self.run_mut(run) else { return };
        if stage == Stage::Load {
            let name = entry.name();
            self.runs.retain(|r| r.id != run);
            if self.selected == Some(run) {
                self.selected = self.runs.first().map(|r| r.id);
            }
            let line = if kind == FailureKind::Cancelled {
                format!("loading {name} cancelled")
            } else {
                message
            };
            self.errors.push(ErrorTopic::Load, line);
        } else {
            // A failure before the spectra leaves neither spectra nor identification; a later
            // one leaves the spectra of this request standing.
            if stage == Stage::Motion {
                entry.motion.fail(generation, message.clone());
            }
            if matches!(stage, Stage::Motion | Stage::Spectra) {
                entry.spectra.fail(generation, message.clone());
            }
            if entry.identification.fail(generation, message.clone()) {
                let name = entry.summary().map_or_else(String::new, |s| s.file_name.clone());
                self.errors.push(
                    ErrorTopic::Analysis(run),
                    format!("{name}: {} stage: {message}", stage.name()),
                );
            }
        }
    }

    /// Builds the frequency-by-pair heatmap texture when its content changed.
    fn update_pair_texture(&mut self, ctx: &egui::Context) {
        let view = &self.prefs.view;
        let Some(run) = self.selected() else { return };
        let Some(spectra) = run.spectra.as_ref() else {
            return;
        };
        let Some(block) = spectra
            .blocks
            .iter()
            .find(|b| b.block == view.spectra_block)
            .or(spectra.blocks.first())
        else {
            return;
        };
        let key = (run.id, run.spectra.generation, block.block, view.heatmap_mode);
        if self.pair_texture.as_ref().is_some_and(|(k, _)| *k == key) {
            return;
        }
        let image = colormap::pair_image(block, view.heatmap_mode);
        let texture = ctx.load_texture("pair-heatmap", image, egui::TextureOptions::NEAREST);
        self.pair_texture = Some((key, texture));
    }
}

/// `message` as the error panel shows it: an internal error says so (the command line's exit
/// status 1), an input error is the message as it is.
fn described(message: &str, kind: FailureKind) -> String {
    match kind {
        FailureKind::Internal => format!("internal error (please report it): {message}"),
        FailureKind::Input | FailureKind::Cancelled => message.to_owned(),
    }
}
