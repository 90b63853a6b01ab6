//! The Validation tab (issue 16): a model's predicted outputs over the measured ones, with the
//! fit in percent, for the selected run's own model and for another run's. AccessKit
//! (`egui_kittest`), no GPU; the worker runs synchronously.

use std::path::PathBuf;

use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::view::validation::fit_label;
use imu_attest::gui::{WorkerMode, sample_run_path};

use crate::common::gui as gui_common;

#[test]
fn the_model_predicts_its_own_run_and_another_run_s_outputs() {
    let approach = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sample_runs/approach.csv.gz");
    let paths = vec![sample_run_path().expect("sample run"), approach];
    let mut harness = gui_common::app(gui_common::options(paths, WorkerMode::Synchronous), 4);
    harness.get_by_label("Validation").click();
    harness.run_steps(4);
    let own = harness.state().runs()[0]
        .validation
        .value
        .clone()
        .expect("predicted with the run's own model");
    // A simulated gyro whose outputs are the motion plus little noise: the model explains
    // nearly all of them below its band top.
    for i in 0..3 {
        assert!(own.fit_percent[i] > 90.0, "{:?}", own.fit_percent);
        harness.get_by_label(&fit_label(&own, i));
    }
    assert!(own.key.model_run == harness.state().runs()[0].id);
    for [measured, predicted, residual] in &own.channels {
        assert_eq!(measured.values().len(), predicted.values().len());
        for ((y, p), r) in measured
            .values()
            .iter()
            .zip(predicted.values())
            .zip(residual.values())
        {
            assert!(
                (y - p - r).abs() <= 1e-12 * (1.0 + y.abs()),
                "residual = measured - predicted"
            );
        }
    }

    // The approach run's model predicting the cruise run: the two sample runs are simulated units
    // whose delays differ by 1.7 ms (their sidecars' truth, 4.42 and 2.70 ms): a phase error of
    // 0.1 rad at 10 Hz, so the other unit's model predicts clearly worse, and says whose it is.
    harness.get_by_label("model from").click();
    harness.run_steps(2);
    harness.get_by_label("model of approach.csv.gz").click();
    harness.run_steps(4);
    let other = harness.state().runs()[0]
        .validation
        .value
        .clone()
        .expect("predicted with the other run's model");
    assert_eq!(other.model_file, "approach.csv.gz");
    assert_ne!(other.key.model_run, own.key.model_run);
    for i in 0..3 {
        assert!(
            other.fit_percent[i] < own.fit_percent[i] - 3.0,
            "{:?} vs {:?}",
            other.fit_percent,
            own.fit_percent
        );
        harness.get_by_label(&fit_label(&other, i));
    }
}
