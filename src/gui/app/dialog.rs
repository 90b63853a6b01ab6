//! The system's file dialogs on their own thread, so that the app keeps drawing while one is
//! open (a blocking dialog on the UI thread froze it for the dialog's whole life, 4.5-9.9 s per
//! frame with an xdg portal, and that frame's time ended up in an exported PNG).
//!
//! A request ([`DialogRequest`]) goes to a thread named `file-dialog` running the app's
//! [`FilePicker`] (the system's dialog, or a test's); its answer comes back through a channel
//! and is turned, in the next `logic` pass, into the command a typed path would have sent
//! ([`PathPurpose::command_for`]). A dialog that answers nothing at once was never shown (no
//! portal or GTK): the typed-path window opens instead. One dialog at a time.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::time::{Duration, Instant};

use super::prompt::PathPurpose;
use crate::gui::pipeline::RunId;

/// The JSON files' dialog filter.
pub(super) const JSON: (&str, &[&str]) = ("json", &["json"]);

/// What to ask the user for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DialogRequest {
    /// What the path is for (which command it becomes).
    pub purpose: PathPurpose,
    /// The filter's name and extensions (without dots).
    pub filter: (&'static str, &'static [&'static str]),
    /// The proposed file name, for a file to write.
    pub file_name: Option<String>,
    /// The run selected when it was asked (its name proposed).
    pub selected: Option<RunId>,
}

impl DialogRequest {
    /// Runs to open (several at once).
    #[must_use]
    pub fn open_runs() -> Self {
        Self {
            purpose: PathPurpose::Open,
            filter: ("stand run (.csv, .csv.gz)", &["csv", "gz"]),
            file_name: None,
            selected: None,
        }
    }

    /// One JSON file to read for `purpose`.
    #[must_use]
    pub fn open_json(purpose: PathPurpose) -> Self {
        Self {
            purpose,
            filter: JSON,
            file_name: None,
            selected: None,
        }
    }

    /// A file to write for `purpose`, proposed as `file_name`.
    #[must_use]
    pub fn save(
        purpose: PathPurpose,
        filter: (&'static str, &'static [&'static str]),
        file_name: String,
    ) -> Self {
        Self {
            purpose,
            filter,
            file_name: Some(file_name),
            selected: None,
        }
    }
}

/// Shows a dialog and waits for the user's answer: the paths picked, `None` if cancelled (or if
/// no dialog could be shown). Runs on the `file-dialog` thread.
#[derive(Clone)]
pub struct FilePicker(Arc<PickFn>);

type PickFn = dyn Fn(&DialogRequest) -> Option<Vec<PathBuf>> + Send + Sync;

impl FilePicker {
    /// A picker calling `pick` (tests: an answer without a desktop).
    pub fn new(pick: impl Fn(&DialogRequest) -> Option<Vec<PathBuf>> + Send + Sync + 'static) -> Self {
        Self(Arc::new(pick))
    }

    /// The system's dialog (`rfd`: an xdg portal or zenity on Linux).
    #[must_use]
    pub fn system() -> Self {
        Self::new(|request: &DialogRequest| {
            let dialog = rfd::FileDialog::new()
                .set_title(request.purpose.title())
                .add_filter(request.filter.0, request.filter.1);
            match (request.purpose, &request.file_name) {
                (PathPurpose::Open, _) => dialog.pick_files(),
                (_, Some(name)) => dialog.set_file_name(name).save_file().map(|p| vec![p]),
                (_, None) => dialog.pick_file().map(|p| vec![p]),
            }
        })
    }
}

impl std::fmt::Debug for FilePicker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FilePicker")
    }
}

/// The answer's channel and the app's waker: dropped, it closes the channel, then wakes.
struct Answer<F: Fn()> {
    send: Option<Sender<(Option<Vec<PathBuf>>, Duration)>>,
    wake: F,
}

impl<F: Fn()> Drop for Answer<F> {
    fn drop(&mut self) {
        self.send = None;
        (self.wake)();
    }
}

/// A dialog being shown.
pub(super) struct PendingDialog {
    /// What was asked.
    pub request: DialogRequest,
    /// The answer and how long the dialog took.
    answer: Receiver<(Option<Vec<PathBuf>>, Duration)>,
}

/// How a dialog ended.
#[derive(Debug, PartialEq)]
pub(super) enum DialogOutcome {
    /// Still open.
    Open,
    /// Paths were picked.
    Picked(Vec<PathBuf>),
    /// The user cancelled it.
    Cancelled,
    /// It returned nothing at once: never shown.
    NeverShown,
    /// Its thread stopped without an answer (the picker panicked).
    Stopped,
}

impl PendingDialog {
    /// Shows `request` with `picker` on its own thread; `wake` is called when it answers (a
    /// repaint, so the answer is taken at once).
    ///
    /// # Errors
    /// The thread could not be started.
    pub fn start(
        picker: FilePicker,
        request: DialogRequest,
        wake: impl Fn() + Send + 'static,
    ) -> std::io::Result<Self> {
        let (send, answer) = channel();
        let asked = request.clone();
        std::thread::Builder::new()
            .name("file-dialog".into())
            .spawn(move || {
                // Wakes the app when dropped: after the answer is sent or, if the picker
                // panics, after the channel is closed.
                let answer = Answer {
                    send: Some(send),
                    wake,
                };
                let start = Instant::now();
                let picked = (picker.0)(&asked);
                if let Some(send) = &answer.send {
                    let _ = send.send((picked, start.elapsed()));
                }
            })?;
        Ok(Self { request, answer })
    }

    /// Its answer, if it has come.
    pub fn poll(&self) -> DialogOutcome {
        match self.answer.try_recv() {
            Err(TryRecvError::Empty) => DialogOutcome::Open,
            Err(TryRecvError::Disconnected) => DialogOutcome::Stopped,
            Ok((picked, elapsed)) => {
                let picked = picked.filter(|p| !p.is_empty());
                if super::prompt::dialog_never_shown(picked.is_none(), elapsed) {
                    DialogOutcome::NeverShown
                } else {
                    picked.map_or(DialogOutcome::Cancelled, DialogOutcome::Picked)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;

    fn wait(pending: &PendingDialog) -> DialogOutcome {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let outcome = pending.poll();
            if outcome != DialogOutcome::Open || Instant::now() > deadline {
                return outcome;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Waits until `count` reaches `n` (or 10 s pass) and returns it.
    fn woken(count: &AtomicUsize, n: usize) -> usize {
        let deadline = Instant::now() + Duration::from_secs(10);
        while count.load(Ordering::SeqCst) < n && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        count.load(Ordering::SeqCst)
    }

    #[test]
    fn a_slow_dialog_answers_on_its_own_thread_and_wakes_the_app() {
        let count = Arc::new(AtomicUsize::new(0));
        let c = count.clone();
        let picker = FilePicker::new(|r: &DialogRequest| {
            assert_eq!(std::thread::current().name(), Some("file-dialog"));
            std::thread::sleep(Duration::from_millis(300));
            Some(vec![PathBuf::from(r.file_name.clone().unwrap_or_default())])
        });
        let request = DialogRequest::save(PathPurpose::ExportModel, ("json", &["json"]), "m.json".into());
        let pending = PendingDialog::start(picker, request, move || {
            c.fetch_add(1, Ordering::SeqCst);
        })
        .expect("thread");
        // The caller is not blocked: the dialog is still open right after it was started.
        assert_eq!(pending.poll(), DialogOutcome::Open);
        assert_eq!(
            wait(&pending),
            DialogOutcome::Picked(vec![PathBuf::from("m.json")])
        );
        assert_eq!(woken(&count, 1), 1);
    }

    #[test]
    fn nothing_at_once_is_a_dialog_never_shown_and_nothing_later_a_cancel() {
        let at_once = FilePicker::new(|_: &DialogRequest| None);
        let pending = PendingDialog::start(at_once, DialogRequest::open_runs(), || {}).expect("thread");
        assert_eq!(wait(&pending), DialogOutcome::NeverShown);
        let empty = FilePicker::new(|_: &DialogRequest| Some(Vec::new()));
        let pending = PendingDialog::start(empty, DialogRequest::open_runs(), || {}).expect("thread");
        assert_eq!(wait(&pending), DialogOutcome::NeverShown);
        let cancelled = FilePicker::new(|_: &DialogRequest| {
            std::thread::sleep(super::super::prompt::DIALOG_NEVER_SHOWN + Duration::from_millis(50));
            None
        });
        let pending = PendingDialog::start(cancelled, DialogRequest::open_runs(), || {}).expect("thread");
        assert_eq!(wait(&pending), DialogOutcome::Cancelled);
    }

    #[test]
    fn a_picker_that_panics_stops_the_dialog_and_still_wakes_the_app() {
        let count = Arc::new(AtomicUsize::new(0));
        let c = count.clone();
        let broken = FilePicker::new(|_: &DialogRequest| panic!("no display"));
        let pending = PendingDialog::start(broken, DialogRequest::open_runs(), move || {
            c.fetch_add(1, Ordering::SeqCst);
        })
        .expect("thread");
        assert_eq!(woken(&count, 1), 1, "woken although the picker panicked");
        assert_eq!(wait(&pending), DialogOutcome::Stopped);
    }
}
