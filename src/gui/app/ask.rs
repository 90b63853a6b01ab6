//! The app's side of asking for a path: a request goes to the system's dialog on its own thread
//! ([`super::dialog`]), or to the typed-path window where there is no dialog; the answer becomes
//! the command a typed path sends. An answer for a run's file (its model, certificate or view)
//! is refused when another run was selected while the dialog was open: the name proposed was
//! the first run's, and the file would have held the second's.

use super::dialog::{DialogOutcome, DialogRequest, PendingDialog};
use super::prompt::{NO_DIALOG_NOTE, PathPurpose, dialogs_disabled};
use super::{App, ErrorTopic};

impl App {
    /// Asks for one file to read for `purpose` (a JSON file).
    pub(super) fn open_dialog(&mut self, purpose: PathPurpose) {
        self.ask(DialogRequest::open_json(purpose));
    }

    /// Asks where to write for `purpose`, proposing the selected run's name with `suffix`.
    pub(super) fn save_dialog(
        &mut self,
        purpose: PathPurpose,
        filter: (&'static str, &'static [&'static str]),
        suffix: &str,
    ) {
        let stem = self
            .selected()
            .and_then(super::RunEntry::summary)
            .map_or_else(|| "imu-attest".to_owned(), |s| crate::run::run_stem(&s.path));
        let mut request = DialogRequest::save(purpose, filter, format!("{stem}{suffix}"));
        request.selected = self.selected;
        self.ask(request);
    }

    /// Shows `request`'s dialog on the `file-dialog` thread; where dialogs are disabled
    /// ([`super::prompt::NO_DIALOG_VAR`]) or the thread cannot start, the typed-path window
    /// opens instead, its field holding the proposed file name. One dialog at a time.
    pub(super) fn ask(&mut self, request: DialogRequest) {
        if self.dialog.is_some() {
            self.status = Some("a file dialog is already open: answer it first".to_owned());
            return;
        }
        if dialogs_disabled() {
            self.prompt_instead(&request, None);
            return;
        }
        let ctx = self.ctx.clone();
        let fallback = request.clone();
        match PendingDialog::start(self.picker.clone(), request, move || ctx.request_repaint()) {
            Ok(pending) => self.dialog = Some(pending),
            Err(e) => self.prompt_instead(
                &fallback,
                Some(&format!(
                    "The file dialog's thread could not start ({e}): type the path."
                )),
            ),
        }
    }

    /// Takes the open dialog's answer, if it has come: the command it asks for, the typed-path
    /// window if it was never shown or stopped, nothing if cancelled.
    pub(super) fn poll_dialog(&mut self) {
        let Some(pending) = &self.dialog else { return };
        let outcome = pending.poll();
        if outcome == DialogOutcome::Open {
            return;
        }
        let request = pending.request.clone();
        self.dialog = None;
        match outcome {
            DialogOutcome::Open | DialogOutcome::Cancelled => {}
            DialogOutcome::NeverShown => self.prompt_instead(&request, Some(NO_DIALOG_NOTE)),
            DialogOutcome::Stopped => self.prompt_instead(
                &request,
                Some("The file dialog stopped without an answer (its thread failed): type the path."),
            ),
            DialogOutcome::Picked(paths) => {
                if request.purpose.of_selected_run() && request.selected != self.selected {
                    self.errors.push(
                        ErrorTopic::Export,
                        format!(
                            "{}: another run was selected while the file dialog was open; nothing \
                             written (select the run and export again)",
                            request.purpose.title()
                        ),
                    );
                } else if let Some(command) = request.purpose.command_for(paths) {
                    self.push_command(command);
                }
            }
        }
    }

    /// The typed-path window for `request`, its field holding the proposed file name.
    fn prompt_instead(&mut self, request: &DialogRequest, note: Option<&str>) {
        self.prompt_path(request.purpose, note);
        if let (Some(p), Some(name)) = (self.prompt.as_mut(), &request.file_name) {
            p.text.clone_from(name);
        }
    }
}
