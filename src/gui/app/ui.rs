//! The drawing half of a frame: panels and tabs. Nothing here computes or touches the pipeline;
//! requests are pushed as commands for the next `logic` pass.

use eframe::egui;

use super::{App, Command, Tab};
use crate::gui::view::{
    bode, compare, controls, discrepancy, errors, results, runs, spectra, timeseries, validation,
};

impl App {
    pub(super) fn draw(&mut self, ui: &mut egui::Ui) {
        let mut commands = Vec::new();
        let view = &mut self.prefs.view;
        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Open…").clicked() {
                        commands.push(Command::OpenDialog);
                    }
                    if ui.button("Open by typing a path…").clicked() {
                        commands.push(Command::PromptPath(super::PathPurpose::Open));
                    }
                    ui.menu_button("Open recent", |ui| {
                        if self.prefs.recent.is_empty() {
                            ui.weak("no run opened yet");
                        }
                        for path in &self.prefs.recent {
                            if ui.button(path.display().to_string()).clicked() {
                                commands.push(Command::Open(vec![path.clone()]));
                            }
                        }
                    });
                    if ui.button("Open session…").clicked() {
                        commands.push(Command::OpenSession(None));
                    }
                    if ui.button("Save session…").clicked() {
                        commands.push(Command::SaveSession(None));
                    }
                    ui.separator();
                    if ui.button("Export model JSON…").clicked() {
                        commands.push(Command::ExportModel(None));
                    }
                    if ui.button("Export results table (CSV)…").clicked() {
                        commands.push(Command::ExportResults(None));
                    }
                    if ui.button("Export report (HTML)…").clicked() {
                        commands.push(Command::ExportReport(None));
                    }
                    if ui.button("Export view as PNG…").clicked() {
                        commands.push(Command::ExportPng(None));
                    }
                    if ui.button("Quit").clicked() {
                        ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                    }
                });
                ui.separator();
                ui.selectable_value(&mut view.tab, Tab::TimeSeries, "Time series");
                ui.selectable_value(&mut view.tab, Tab::Spectra, "Spectra");
                ui.selectable_value(&mut view.tab, Tab::Bode, "Bode");
                ui.selectable_value(&mut view.tab, Tab::Diagnosis, "Missing effects");
                ui.selectable_value(&mut view.tab, Tab::Validation, "Validation");
                ui.selectable_value(&mut view.tab, Tab::Compare, "Compare");
                if let Some(dialog) = &self.dialog {
                    ui.separator();
                    // No spinner: it would repaint every frame while the user reads the dialog.
                    ui.label(format!(
                        "file dialog open: {} (answer it; the app keeps working)",
                        dialog.request.purpose.title()
                    ));
                }
                if let Some(status) = &self.status {
                    ui.separator();
                    ui.weak(status);
                }
                if let Some(s) = self.frame_cpu_s {
                    ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                        ui.weak(format!("frame {:.1} ms", 1e3 * s))
                            .on_hover_text("CPU time of the previous frame: drawing and rendering");
                    });
                }
            });
        });
        if !self.errors.is_empty() {
            egui::Panel::bottom("errors")
                .show(ui, |ui| errors::show(ui, self.errors.entries(), &mut commands));
        }
        let selected = self.selected.and_then(|id| self.runs.iter().find(|r| r.id == id));
        egui::Panel::left("side").default_size(320.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                runs::show(ui, &self.runs, self.selected, &mut commands);
                ui.separator();
                let summary = selected.and_then(|r| r.summary().map(AsRef::as_ref));
                controls::show(ui, &self.prefs.settings, summary, &mut commands);
            });
        });
        egui::Panel::right("results").default_size(360.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| results::show(ui, selected, &mut commands));
        });
        egui::CentralPanel::default().show(ui, |ui| {
            if view.tab == Tab::Compare {
                let comparison = self.comparison.as_ref().map(|(_, c)| c.as_ref());
                compare::show(ui, &self.runs, &self.compared, comparison, view, &mut commands);
                return;
            }
            let Some(run) = selected else {
                ui.centered_and_justified(|ui| {
                    ui.label("open a stand run (File > Open, or drop a file here)")
                });
                return;
            };
            match view.tab {
                Tab::TimeSeries => timeseries::show(ui, run, view, &self.prefs.settings, &mut commands),
                Tab::Spectra => {
                    let texture = self.pair_texture.as_ref().map(|(_, t)| t);
                    spectra::show(ui, run, view, texture);
                }
                Tab::Bode => bode::show(ui, run, view),
                Tab::Diagnosis => {
                    egui::ScrollArea::vertical()
                        .show(ui, |ui| discrepancy::show(ui, Some(run), &mut commands));
                }
                Tab::Validation => validation::show(ui, run, &self.runs, view),
                Tab::Compare => {}
            }
        });
        if let Some(prompt) = self.prompt.as_mut() {
            super::prompt::show(ui.ctx(), prompt, &mut commands);
        }
        self.commands.extend(commands);
    }
}
