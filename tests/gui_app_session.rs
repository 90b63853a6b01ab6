//! Sessions and recent files (issue 16): a day's work saved and reopened in a new app (runs by
//! path and SHA-256, settings, accepted and rejected effects, view, selection, comparison); a
//! file changed since is said; a broken session file is refused with its line and column; opened
//! runs are listed under File > Open recent. AccessKit (`egui_kittest`), no GPU; the worker runs
//! synchronously.

use std::path::{Path, PathBuf};

use egui_kittest::kittest::Queryable as _;
use imu_attest::block::Block;
use imu_attest::effect::Effect;
use imu_attest::gui::app::Tab;
use imu_attest::gui::app::session_file::{SESSION_SCHEMA, read_session};
use imu_attest::gui::{App, Command, WorkerMode};
use imu_attest::ident::settings::OrderSetting;

use crate::common::gui as gui_common;

/// The two sample runs copied (with their sidecars) into `dir`.
fn two_runs(dir: &Path) -> Vec<PathBuf> {
    let samples = Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs");
    ["cruise", "approach"]
        .iter()
        .map(|n| {
            for ext in ["csv.gz", "json"] {
                std::fs::copy(samples.join(format!("{n}.{ext}")), dir.join(format!("{n}.{ext}")))
                    .expect("copied");
            }
            dir.join(format!("{n}.csv.gz"))
        })
        .collect()
}

fn app(paths: Vec<PathBuf>) -> egui_kittest::Harness<'static, App> {
    gui_common::app(gui_common::options(paths, WorkerMode::Synchronous), 4)
}

fn push(harness: &mut egui_kittest::Harness<'_, App>, command: Command) {
    harness.state_mut().push_command(command);
    harness.run_steps(4);
}

#[test]
fn a_saved_session_reopens_as_it_was_and_says_when_a_file_changed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let paths = two_runs(dir.path());
    let mut harness = app(paths.clone());
    let ids: Vec<_> = harness.state().runs().iter().map(|r| r.id).collect();
    let mut settings = harness.state().settings().clone();
    settings.order.accel = OrderSetting::Fixed(0);
    push(&mut harness, Command::SetSettings(Box::new(settings.clone())));
    push(
        &mut harness,
        Command::RejectEffect(ids[1], Block::Gyro, Effect::SensorLag),
    );
    push(&mut harness, Command::ToggleCompare(ids[0]));
    push(&mut harness, Command::ToggleCompare(ids[1]));
    push(&mut harness, Command::Select(ids[1]));
    harness.get_by_label("Compare").click();
    harness.run_steps(2);
    let session = dir.path().join("day.json");
    push(&mut harness, Command::SaveSession(Some(session.clone())));
    let file = read_session(&session).expect("a session file");
    assert_eq!(file.schema, SESSION_SCHEMA);
    assert_eq!(file.runs.len(), 2);
    assert_eq!(file.runs[1].rejected, vec![(Block::Gyro, Effect::SensorLag)]);

    // A new app, nothing open: the session brings it all back.
    let mut fresh = app(Vec::new());
    push(&mut fresh, Command::OpenSession(Some(session.clone())));
    let state = fresh.state();
    let reopened: Vec<&Path> = state.runs().iter().map(|r| r.path.as_path()).collect();
    assert_eq!(reopened, paths.iter().map(PathBuf::as_path).collect::<Vec<_>>());
    assert_eq!(*state.settings(), settings);
    assert_eq!(state.runs()[1].rejected, vec![(Block::Gyro, Effect::SensorLag)]);
    assert_eq!(state.view().tab, Tab::Compare);
    assert_eq!(state.compared().len(), 2);
    assert!(
        state.runs().iter().all(|r| r.identification.is_some()),
        "identified again"
    );
    assert!(state.errors().is_empty(), "{:?}", state.errors());
    fresh.get_by_label("Compare");

    // The approach run's bytes replaced by the cruise run's: reopening says so.
    std::fs::copy(&paths[0], &paths[1]).expect("overwritten");
    let mut third = app(Vec::new());
    push(&mut third, Command::OpenSession(Some(session)));
    let errors = third.state().errors();
    assert!(
        errors
            .iter()
            .any(|e| e.contains("approach.csv.gz: the file has changed since the session was saved")),
        "{errors:?}"
    );
}

#[test]
fn a_broken_session_file_is_refused_with_its_line_and_column_and_the_app_goes_on() {
    let dir = tempfile::tempdir().expect("temp dir");
    let broken = dir.path().join("broken.json");
    std::fs::write(
        &broken,
        "{\n  \"schema\": \"imu-attest/session/1\",\n  \"runs\": [1,\n",
    )
    .expect("written");
    let mut harness = app(Vec::new());
    push(&mut harness, Command::OpenSession(Some(broken)));
    let errors = harness.state().errors();
    assert!(
        errors.iter().any(|e| e.contains("broken.json: line 3, column")),
        "{errors:?}"
    );
    assert!(harness.state().runs().is_empty());
    harness.get_by_label("File");
}

#[test]
fn opened_runs_are_listed_under_open_recent_newest_first() {
    let dir = tempfile::tempdir().expect("temp dir");
    let paths = two_runs(dir.path());
    let mut harness = app(paths.clone());
    harness.run_steps(2);
    let recent = &harness.state().prefs().recent;
    assert_eq!(recent.len(), 2);
    assert!(recent.contains(&paths[0]) && recent.contains(&paths[1]));
    // Open again from the menu: one more copy of the run, and it moves to the front.
    let first_again = paths[0].clone();
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Open recent").click();
    harness.run_steps(2);
    harness.get_by_label(&first_again.display().to_string()).click();
    harness.run_steps(4);
    assert_eq!(harness.state().runs().len(), 3);
    assert_eq!(harness.state().prefs().recent[0], first_again);
}
