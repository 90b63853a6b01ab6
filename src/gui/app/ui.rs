//! The drawing half of a frame: panels and tabs. Nothing here computes or touches the pipeline;
//! requests are pushed as commands for the next `logic` pass.

use eframe::egui;

use super::{App, Command, Tab};
use crate::gui::view::{controls, errors, runs, spectra, timeseries};

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
                    if ui.button("Quit").clicked() {
                        ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                    }
                });
                ui.separator();
                ui.selectable_value(&mut view.tab, Tab::TimeSeries, "Time series");
                ui.selectable_value(&mut view.tab, Tab::Spectra, "Spectra");
            });
        });
        if !self.errors.is_empty() {
            egui::Panel::bottom("errors").show(ui, |ui| errors::show(ui, &self.errors, &mut commands));
        }
        let selected = self.selected.and_then(|id| self.runs.iter().find(|r| r.id == id));
        egui::Panel::left("side").default_size(320.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                runs::show(ui, &self.runs, self.selected, &mut commands);
                ui.separator();
                let summary = selected.and_then(|r| r.summary.as_deref());
                controls::show(ui, &self.prefs.settings, summary, &mut commands);
            });
        });
        egui::CentralPanel::default().show(ui, |ui| {
            let Some(run) = selected else {
                ui.centered_and_justified(|ui| {
                    ui.label("open a stand run (File > Open, or drop a file here)")
                });
                return;
            };
            match view.tab {
                Tab::TimeSeries => timeseries::show(ui, run, view),
                Tab::Spectra => {
                    let texture = self.pair_texture.as_ref().map(|(_, t)| t);
                    spectra::show(ui, run, view, texture);
                }
            }
        });
        self.commands.extend(commands);
    }
}
