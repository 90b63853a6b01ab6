//! The run list: regime, duration, rate, blocks, notices; load progress with a cancel button.

use eframe::egui;

use crate::gui::app::{Command, RunEntry};
use crate::gui::pipeline::RunId;

/// Draws the list; returns the commands the user asked for.
pub fn show(ui: &mut egui::Ui, runs: &[RunEntry], selected: Option<RunId>, commands: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        ui.heading("Runs");
        if ui.button("Open…").clicked() {
            commands.push(Command::OpenDialog);
        }
    });
    if runs.is_empty() {
        ui.weak("no run: File > Open, or drop a .csv / .csv.gz here");
    }
    for run in runs {
        ui.separator();
        let name = run
            .path
            .file_name()
            .map_or_else(|| run.path.display().to_string(), |n| n.to_string_lossy().into());
        ui.horizontal(|ui| {
            if ui.selectable_label(selected == Some(run.id), &name).clicked() {
                commands.push(Command::Select(run.id));
            }
            if run.busy() {
                ui.spinner();
            }
            if ui
                .small_button("×")
                .on_hover_text("remove from the list")
                .clicked()
            {
                commands.push(Command::Remove(run.id));
            }
        });
        match (&run.reading, run.summary()) {
            (Some(reading), _) => {
                ui.horizontal(|ui| {
                    ui.add(
                        egui::ProgressBar::new(reading.fraction)
                            .desired_width(140.0)
                            .show_percentage(),
                    );
                    if ui.button("Cancel").clicked() {
                        commands.push(Command::CancelLoad(run.id));
                    }
                });
            }
            (None, Some(s)) => {
                let blocks: Vec<&str> = s.blocks.iter().map(|b| b.name()).collect();
                ui.label(format!("regime: {}", s.regime));
                ui.label(format!(
                    "{:.1} s at {:.1} Hz ({} samples)",
                    s.duration_s, s.sample_rate_hz, s.n_samples
                ));
                ui.label(format!("blocks: {}", blocks.join(", ")));
                for notice in &s.notices {
                    ui.colored_label(ui.visuals().warn_fg_color, format!("notice: {notice}"));
                }
                for fault in &s.recording_faults {
                    ui.colored_label(ui.visuals().error_fg_color, format!("recording fault: {fault}"));
                }
                if let Some(e) = &run.identification.error {
                    ui.colored_label(ui.visuals().error_fg_color, e);
                }
            }
            (None, None) => {}
        }
    }
}
