//! The app's missing-effect view through AccessKit (`egui_kittest`, no GPU): the diagnosis runs
//! on the worker (synchronously here), the verdict and findings appear in the tab, and rejecting a
//! named effect diagnoses again without it.

use std::path::PathBuf;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::{App, WorkerMode, sample_run_path};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

#[path = "common/gui.rs"]
mod gui_common;

fn app(paths: Vec<PathBuf>) -> Harness<'static, App> {
    gui_common::app(gui_common::options(paths, WorkerMode::Synchronous), 3)
}

fn diagnose(harness: &mut Harness<'static, App>) {
    harness.get_by_label("Missing effects").click();
    harness.run_steps(2);
    harness.get_by_label("Find missing effects").click();
    harness.run_steps(4);
}

#[test]
fn the_clean_sample_run_has_no_missing_effect() {
    let mut harness = app(vec![sample_run_path().unwrap()]);
    diagnose(&mut harness);
    harness.get_by_label("verdict: no missing effect");
    let run = harness.state().selected().unwrap();
    assert!(run.diagnosis.as_ref().unwrap().findings.is_empty());
    assert!(!run.diagnosis.running());
}

#[test]
fn a_hidden_lag_is_named_and_a_rejection_diagnoses_again_without_it() {
    let mut config = SimConfig::new(Regime::Approach);
    config.duration_s = 60.0;
    config.seed = 5;
    config.effects = vec!["sensor_lag:gyro".parse().unwrap()];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lagged.csv");
    write_run(&simulate(&config).unwrap(), &path).unwrap();
    let mut harness = app(vec![path]);
    diagnose(&mut harness);
    harness.get_by_label("verdict: effect found");
    harness.get_by_label("gyro first-order lag");
    harness.get_by_label("Accept").click();
    harness.run_steps(2);
    harness.get_by_label("accepted");
    assert_eq!(harness.state().selected().unwrap().accepted.len(), 1);
    harness.get_by_label("Reject").click();
    harness.run_steps(4);
    let run = harness.state().selected().unwrap();
    let report = run.diagnosis.as_ref().unwrap();
    assert!(
        report
            .findings
            .iter()
            .all(|f| f.effect != imu_attest::effect::Effect::SensorLag),
        "{:?} rejected {:?} diagnosing {}",
        report
            .findings
            .iter()
            .map(|f| (&f.block, &f.effect))
            .collect::<Vec<_>>(),
        run.rejected,
        run.diagnosis.running()
    );
    harness.get_by_label_contains("rejected: gyro sensor_lag");
    // The app stays usable: the Bode tab still draws the identification.
    harness.get_by_label("Bode").click();
    harness.run_steps(2);
}
