//! Typing a path instead of using the system's file dialog: File > "Type a path…", and the
//! fallback when no dialog can be shown (a desktop without an xdg portal or GTK: `rfd` then
//! returns at once with nothing, which looked like the menu doing nothing at all).
//!
//! The prompt is a small window with the path's text field, OK and Cancel; OK sends the command
//! the dialog would have sent. Its text is the window's own draft (UI state, like the settings
//! fields' drafts); nothing of the core changes until OK.

use std::path::PathBuf;
use std::time::Duration;

use eframe::egui;

use super::Command;

/// Environment variable: when set, the app never shows the system's dialog and always asks for
/// a typed path (kiosks, remote sessions, tests).
pub const NO_DIALOG_VAR: &str = "IMU_ATTEST_NO_DIALOG";

/// A dialog that returns nothing faster than this was never shown (a person cannot cancel one
/// so fast): the prompt takes over.
pub const DIALOG_NEVER_SHOWN: Duration = Duration::from_millis(150);

/// What the fallback window says.
pub const NO_DIALOG_NOTE: &str =
    "No file dialog could be shown on this desktop (no xdg portal or GTK?): type the path.";

/// What the typed path is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathPurpose {
    /// Open a run (several, separated by `;`).
    Open,
    /// Write the selected run's model JSON.
    ExportModel,
    /// Write the view as PNG.
    ExportPng,
    /// Write the selected run's certificate.
    ExportReport,
    /// Write the results table.
    ExportResults,
    /// Write the session file.
    SaveSession,
    /// Read a session file.
    OpenSession,
}

impl PathPurpose {
    /// The prompt's title.
    #[must_use]
    pub fn title(self) -> &'static str {
        match self {
            PathPurpose::Open => "Open stand runs",
            PathPurpose::ExportModel => "Save model JSON",
            PathPurpose::ExportPng => "Save view as PNG",
            PathPurpose::ExportReport => "Save report (HTML)",
            PathPurpose::ExportResults => "Save results table (CSV or JSON)",
            PathPurpose::SaveSession => "Save session",
            PathPurpose::OpenSession => "Open session",
        }
    }

    /// Whether the file is the selected run's (its model, certificate or view), not every run's.
    #[must_use]
    pub fn of_selected_run(self) -> bool {
        matches!(
            self,
            PathPurpose::ExportModel | PathPurpose::ExportReport | PathPurpose::ExportPng
        )
    }

    /// The command the dialog would have sent for `text` (`None` for an empty path).
    #[must_use]
    pub fn command(self, text: &str) -> Option<Command> {
        let paths: Vec<PathBuf> = text
            .split(';')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(PathBuf::from)
            .collect();
        self.command_for(paths)
    }

    /// The command for the picked `paths` (`None` for none; one path for all but Open).
    #[must_use]
    pub fn command_for(self, paths: Vec<PathBuf>) -> Option<Command> {
        let one = paths.first().cloned();
        match self {
            PathPurpose::Open => (!paths.is_empty()).then_some(Command::Open(paths)),
            PathPurpose::ExportModel => one.map(|p| Command::ExportModel(Some(p))),
            PathPurpose::ExportPng => one.map(|p| Command::ExportPng(Some(p))),
            PathPurpose::ExportReport => one.map(|p| Command::ExportReport(Some(p))),
            PathPurpose::ExportResults => one.map(|p| Command::ExportResults(Some(p))),
            PathPurpose::SaveSession => one.map(|p| Command::SaveSession(Some(p))),
            PathPurpose::OpenSession => one.map(|p| Command::OpenSession(Some(p))),
        }
    }
}

/// The open prompt.
#[derive(Clone, Debug, PartialEq)]
pub struct PathPrompt {
    /// What it is for.
    pub purpose: PathPurpose,
    /// The path typed so far.
    pub text: String,
    /// Why it is shown instead of the dialog, if it is a fallback.
    pub note: Option<String>,
}

/// Whether a dialog that returned `picked_nothing` after `elapsed` was in fact never shown.
#[must_use]
pub fn dialog_never_shown(picked_nothing: bool, elapsed: Duration) -> bool {
    picked_nothing && elapsed < DIALOG_NEVER_SHOWN
}

/// Whether the system dialog is to be skipped altogether ([`NO_DIALOG_VAR`]).
#[must_use]
pub fn dialogs_disabled() -> bool {
    std::env::var_os(NO_DIALOG_VAR).is_some()
}

/// Draws the prompt; pushes the command on OK (or Enter) and [`Command::ClosePrompt`] on
/// Cancel or OK.
pub fn show(ctx: &egui::Context, prompt: &mut PathPrompt, commands: &mut Vec<Command>) {
    egui::Window::new(prompt.purpose.title())
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, egui::vec2(0.0, 0.0))
        .show(ctx, |ui| {
            if let Some(note) = &prompt.note {
                ui.label(note);
            }
            let hint = if prompt.purpose == PathPurpose::Open {
                "path of a run (.csv, .csv.gz); several separated by ;"
            } else {
                "path of the file to write"
            };
            let field = ui
                .horizontal(|ui| {
                    let label = ui.label("path");
                    ui.add(
                        egui::TextEdit::singleline(&mut prompt.text)
                            .hint_text(hint)
                            .desired_width(480.0),
                    )
                    .labelled_by(label.id)
                })
                .inner;
            let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            ui.horizontal(|ui| {
                let ok = ui.button("OK").clicked() || entered;
                if ok && let Some(command) = prompt.purpose.command(&prompt.text) {
                    commands.push(command);
                    commands.push(Command::ClosePrompt);
                }
                if ui.button("Cancel").clicked() {
                    commands.push(Command::ClosePrompt);
                }
            });
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dialog_that_returns_nothing_at_once_was_never_shown() {
        assert!(dialog_never_shown(true, Duration::from_millis(3)));
        assert!(
            !dialog_never_shown(true, Duration::from_secs(2)),
            "a person cancelled it"
        );
        assert!(
            !dialog_never_shown(false, Duration::from_millis(3)),
            "a path was picked"
        );
    }

    #[test]
    fn typed_paths_become_the_dialogs_commands() {
        assert!(matches!(
            PathPurpose::Open.command(" a.csv ; b.csv.gz ;"),
            Some(Command::Open(p)) if p == [PathBuf::from("a.csv"), PathBuf::from("b.csv.gz")]
        ));
        assert!(PathPurpose::Open.command("  ").is_none());
        assert!(matches!(
            PathPurpose::ExportResults.command("/tmp/t.csv"),
            Some(Command::ExportResults(Some(p))) if p == std::path::Path::new("/tmp/t.csv")
        ));
    }
}
