//! The error panel: loading and computing failures, each dismissable, a repeat counted on its
//! line; an analysis or diagnosis error goes when that run's next one succeeds. The app stays
//! usable.

use eframe::egui;

use crate::gui::app::{Command, ErrorEntry};

/// Draws the errors (newest last).
pub fn show(ui: &mut egui::Ui, errors: &[ErrorEntry], commands: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        ui.strong("Errors");
        ui.weak("(the last good results stay shown)");
    });
    egui::ScrollArea::vertical()
        .max_height(110.0)
        .stick_to_bottom(true)
        .show(ui, |ui| {
            for (k, entry) in errors.iter().enumerate() {
                ui.horizontal(|ui| {
                    if ui.small_button("dismiss").clicked() {
                        commands.push(Command::DismissError(k));
                    }
                    ui.colored_label(ui.visuals().error_fg_color, entry.line());
                });
            }
        });
}
