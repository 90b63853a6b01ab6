//! The system's file dialog does not freeze the app (issue 16): it runs on its own thread, the
//! app keeps drawing and taking clicks while it is open, and its answer sends the command a
//! typed path would have sent. A dialog that answers nothing at once was never shown (a desktop
//! without an xdg portal or GTK): the typed-path window opens, with the proposed file name. An
//! export answered after another run was selected is refused.
//! AccessKit (`egui_kittest`), no GPU; the pickers stand in for the desktop's dialog.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::app::{Command, DialogRequest, FilePicker, Tab};
use imu_attest::gui::{AppOptions, WorkerMode, sample_run_path};

use crate::common::gui as gui_common;

fn with_picker(paths: Vec<PathBuf>, picker: FilePicker) -> AppOptions {
    AppOptions {
        file_picker: picker,
        ..gui_common::options(paths, WorkerMode::Synchronous)
    }
}

#[test]
fn the_app_keeps_working_while_a_slow_dialog_is_open_and_opens_what_it_picks() {
    let sample = sample_run_path().expect("sample run");
    let picked = sample.clone();
    let picker = FilePicker::new(move |request: &DialogRequest| {
        assert_eq!(std::thread::current().name(), Some("file-dialog"));
        assert!(request.filter.1.contains(&"gz"));
        // A person choosing a file.
        std::thread::sleep(Duration::from_secs(2));
        Some(vec![picked.clone()])
    });
    let mut harness = gui_common::app(with_picker(Vec::new(), picker), 2);
    // The Runs panel's Open… (the File menu's sends the same command).
    harness.get_by_label("Open…").click();
    let asked = Instant::now();
    harness.run_steps(2);
    // The frames go on while the dialog is open (with a blocking dialog these two frames would
    // have waited its 2 s), the app says a dialog is open, and a click still changes the tab. The
    // bound leaves room for a loaded machine (the suite's other tests run beside this one).
    assert!(
        asked.elapsed() < Duration::from_millis(1500),
        "{:?}",
        asked.elapsed()
    );
    harness.get_by_label("file dialog open: Open stand runs (answer it; the app keeps working)");
    harness.get_by_label("Spectra").click();
    harness.run_steps(2);
    assert_eq!(harness.state().view().tab, Tab::Spectra);
    assert!(harness.state().runs().is_empty());
    // Another dialog is not stacked on the open one.
    harness.state_mut().push_command(Command::ExportModel(None));
    harness.run_steps(1);
    harness.get_by_label("a file dialog is already open: answer it first");
    let deadline = Instant::now() + Duration::from_secs(20);
    while harness.state().runs().is_empty() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        harness.run_steps(1);
    }
    assert_eq!(harness.state().runs().len(), 1, "{:?}", harness.state().errors());
    assert_eq!(harness.state().runs()[0].path, sample);
    assert!(harness.query_by_label_contains("file dialog open").is_none());
}

#[test]
fn a_dialog_that_answers_nothing_at_once_gives_the_typed_path_with_the_proposed_name() {
    let picker = FilePicker::new(|_: &DialogRequest| None);
    let sample = sample_run_path().expect("sample run");
    let mut harness = gui_common::app(with_picker(vec![sample], picker), 4);
    harness.state_mut().push_command(Command::ExportModel(None));
    let deadline = Instant::now() + Duration::from_secs(20);
    while harness.query_by_label("path").is_none() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        harness.run_steps(1);
    }
    harness.get_by_label(
        "No file dialog could be shown on this desktop (no xdg portal or GTK?): type the path.",
    );
    assert_eq!(
        harness.get_by_label("path").value().as_deref(),
        Some("cruise_model.json")
    );
    harness.get_by_label("Cancel").click();
    harness.run_steps(2);
    assert!(harness.query_by_label("path").is_none());
}

#[test]
fn a_cancelled_dialog_does_nothing() {
    let picker = FilePicker::new(|_: &DialogRequest| {
        std::thread::sleep(Duration::from_millis(300));
        None
    });
    let mut harness = gui_common::app(with_picker(Vec::new(), picker), 2);
    harness.state_mut().push_command(Command::OpenSession(None));
    harness.run_steps(1);
    harness.get_by_label("file dialog open: Open session (answer it; the app keeps working)");
    let deadline = Instant::now() + Duration::from_secs(20);
    while harness.query_by_label_contains("file dialog open").is_some() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        harness.run_steps(1);
    }
    assert!(harness.query_by_label_contains("file dialog open").is_none());
    assert!(
        harness.query_by_label("path").is_none(),
        "no typed-path window after a cancel"
    );
    assert!(harness.state().runs().is_empty());
    assert!(harness.state().errors().is_empty());
}

/// The app takes clicks while a dialog is open, so the selection can change under it: an answer
/// for the selected run's file (here its model) is refused when another run was selected
/// meanwhile, instead of writing the second run's model under the first's name.
#[test]
fn an_export_is_refused_when_the_selection_changed_while_its_dialog_was_open() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cruise_model.json");
    let target = out.clone();
    let picker = FilePicker::new(move |request: &DialogRequest| {
        assert_eq!(request.file_name.as_deref(), Some("cruise_model.json"));
        std::thread::sleep(Duration::from_millis(800));
        Some(vec![target.clone()])
    });
    let approach = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/approach.csv.gz");
    let sample = sample_run_path().expect("sample run");
    let mut harness = gui_common::app(with_picker(vec![sample, approach], picker), 6);
    let ids: Vec<_> = harness.state().runs().iter().map(|r| r.id).collect();
    assert_eq!(ids.len(), 2);
    harness.state_mut().push_command(Command::Select(ids[0]));
    harness.run_steps(2);
    harness.state_mut().push_command(Command::ExportModel(None));
    harness.run_steps(1);
    harness.state_mut().push_command(Command::Select(ids[1]));
    let deadline = Instant::now() + Duration::from_secs(20);
    while harness.query_by_label_contains("file dialog open").is_some() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        harness.run_steps(1);
    }
    harness.run_steps(2);
    assert!(
        !out.exists(),
        "the second run's model was written under the first's name"
    );
    assert!(
        harness
            .state()
            .errors()
            .iter()
            .any(|e| e.contains("another run was selected while the file dialog was open")),
        "{:?}",
        harness.state().errors()
    );
    // With the selection unchanged the same answer writes the model.
    harness.state_mut().push_command(Command::Select(ids[0]));
    harness.run_steps(2);
    harness.state_mut().push_command(Command::ExportModel(None));
    let deadline = Instant::now() + Duration::from_secs(20);
    while !out.exists() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        harness.run_steps(1);
    }
    assert!(out.exists());
}
