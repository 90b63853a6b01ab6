//! The app shows what the identifier can and cannot vouch for (issue 13): the self-check's
//! warnings in Results, the band used, why each order candidate was rejected (and its held-out
//! chi2), and the same
//! refusal as `identify` for a run whose stand axis was held still, and a block the run cannot
//! identify said beside the one it can. AccessKit (`egui_kittest`), no GPU; the worker runs
//! synchronously.

use std::path::{Path, PathBuf};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::view::compare::significance_label;
use imu_attest::gui::view::results::{band_label, k_heading};
use imu_attest::gui::{App, WorkerMode};
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::rng::Rng;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

use crate::common::gui as gui_common;

fn app(paths: Vec<PathBuf>) -> Harness<'static, App> {
    gui_common::app(gui_common::options(paths, WorkerMode::Synchronous), 4)
}

fn real(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"))
}

/// The bytes `imu-attest identify RUN --out OUT` writes (exit 0 asserted).
fn identify_file(run: &Path, out: &Path) -> Vec<u8> {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .arg("identify")
        .arg(run)
        .arg("--out")
        .arg(out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(out).expect("written")
}

#[test]
fn results_show_the_band_the_warnings_and_the_rejected_orders_of_a_real_run() {
    let harness = app(vec![real("broad07_fast_rotation")]);
    let run = &harness.state().runs()[0];
    let id = run.identification.as_ref().expect("identified");
    let m = id.model.blocks.get("gyro").expect("gyro");
    // The settings ask for both blocks; the gyro-only run says it has no accelerometer.
    assert_eq!(
        harness
            .query_all_by_label(imu_attest::gui::view::controls::NOT_IN_THIS_RUN)
            .count(),
        1
    );
    // The band found from the data, shown as such.
    assert!(m.band_hz[1] < 20.0, "{:?}", m.band_hz);
    harness.get_by_label(&band_label("gyro", m, true));
    // The reference was interpolated from 120 Hz: the gain's rise across the band is on screen.
    let warning = m
        .fit
        .warnings
        .iter()
        .find(|w| w.to_string().contains("with no phase of its own"))
        .expect("the gain-rise warning");
    harness.get_by_label(&format!("warning: {warning}"));
    // Each rejected candidate says why.
    let rejected = m
        .fit
        .candidates
        .iter()
        .find_map(|c| c.rejected.clone())
        .expect("a rejected candidate");
    assert!(harness.get_all_by_label(&format!("no: {rejected}")).count() >= 1);
    // Each candidate's held-out chi2 (fitted to one half of the record, predicting the other).
    harness.get_by_label("held-out χ²");
    for c in &m.fit.candidates {
        let h = c.held_out_chi2.expect("the record is halved");
        assert!(
            harness.get_all_by_label(&format!("{h:.1}")).count() >= 1,
            "order {}",
            c.order
        );
    }
    harness.get_by_label_contains("auto: lowest BIC among the admissible orders");
    // The reference was interpolated from 120 Hz: the gain rises across the band, and K is shown
    // as the gain at low frequency, with how far the model's even gain rises at the band's top.
    let even = m.even_gain.expect("an even gain in the delay-only model");
    let heading = k_heading(m);
    assert!(heading.starts_with("K at low frequency"), "{heading}");
    let top = (even.at(m.band_hz[1]) - 1.0) * 100.0;
    assert!((3.0..20.0).contains(&top), "{top}");
    assert!(heading.contains(&format!("{top:+.2} %")), "{heading}");
    harness.get_by_label(&heading);
}

#[test]
fn a_run_with_a_still_stand_axis_is_refused_with_the_message_of_identify() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 60.0;
    config.seed = 31;
    let mut sim = simulate(&config).expect("simulated");
    // Yaw held still: only the angle sensor's noise remains.
    let mean = sim.angles[1].iter().sum::<f64>() / sim.angles[1].len() as f64;
    let sigma = sim.sidecar.angle_noise_rad;
    let mut rng = Rng::new(5);
    for v in &mut sim.angles[1] {
        *v = mean + sigma * rng.normal();
    }
    let path = dir.path().join("still_yaw.csv");
    write_run(&sim, &path).expect("written");
    let expected = identify_run(
        &load(&path, &LoadOptions::default()).expect("loads"),
        &Settings::default(),
    )
    .expect_err("identify refuses it")
    .to_string();
    assert!(expected.contains("not excited"), "{expected}");

    let harness = app(vec![path]);
    let run = &harness.state().runs()[0];
    assert!(run.identification.is_none(), "no model is shown for a still axis");
    let shown = run.identification.error.clone().expect("an error");
    assert!(shown.contains(&expected), "app: {shown}\nidentify: {expected}");
    assert!(harness.get_all_by_label_contains("not excited").count() >= 1);
}

/// A run without its sidecar (lever arms zero): the gyro's results are shown, and the
/// accelerometer's refusal above them in the words of `identify`; the diagnosis says the block
/// was not diagnosed.
#[test]
fn a_refused_block_is_said_beside_the_identified_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 60.0;
    config.seed = 4;
    let sim = simulate(&config).expect("simulated");
    let with = dir.path().join("with_sidecar.csv");
    write_run(&sim, &with).expect("written");
    let path = dir.path().join("no_sidecar.csv");
    write_run(&sim, &path).expect("written");
    std::fs::remove_file(path.with_extension("json")).expect("sidecar removed");

    let mut harness = app(vec![path, with]);
    let id = harness.state().runs()[0]
        .identification
        .as_ref()
        .expect("identified");
    assert_eq!(id.model.blocks.keys().collect::<Vec<_>>(), ["gyro"]);
    let words = id.model.refused_blocks["accel"].words("accel", &["gyro"]);
    assert!(words.contains("axis fy not excited"), "{words}");
    harness.get_by_label(&format!("warning: {words}"));
    harness.get_by_label_contains("gyro τ =");
    harness.get_by_label("Bode").click();
    harness.run_steps(2);
    harness.get_by_label("accel block not identified (Results says why): no W_u to draw");

    harness.get_by_label("Missing effects").click();
    harness.run_steps(2);
    harness.get_by_label("Find missing effects").click();
    harness.run_steps(4);
    harness.get_by_label_contains("accel block not diagnosed: the run cannot identify it");

    // Compared with the same run and its sidecar: the accelerometer is in no pair, and says why.
    harness.get_by_label("Compare").click();
    harness.run_steps(2);
    harness.get_by_label("compare no_sidecar.csv").click();
    harness.run_steps(1);
    harness.get_by_label("compare with_sidecar.csv").click();
    harness.run_steps(2);
    harness.get_by_label(
        "no_sidecar.csv: the accel block was not identified (its Results say why): no pair with this run compares it",
    );
    let c = harness.state().comparison().expect("compared").clone();
    assert_eq!(
        significance_label(&c, "accel"),
        "accel: no pair of runs both identified it"
    );
    assert!(significance_label(&c, "gyro").ends_with("significant differences"));
}

/// A diagnosis that finishes after a newer one was requested (threaded mode: the older was
/// already running) never replaces the newer one: the app drops it and waits.
#[test]
fn a_stale_diagnosis_never_replaces_a_newer_one() {
    use imu_attest::gui::{Command, sample_run_path};
    let options = gui_common::options(vec![sample_run_path().expect("sample run")], WorkerMode::Manual);
    let mut harness = gui_common::app(options, 2);
    while harness.state_mut().run_worker_jobs() > 0 {
        harness.run_steps(2);
    }
    let id = harness.state().runs()[0].id;
    // The first diagnosis runs; its result waits in the channel while a second is requested.
    harness.state_mut().push_command(Command::Diagnose(id));
    harness.step();
    assert_eq!(harness.state_mut().run_worker_jobs(), 1);
    harness.state_mut().push_command(Command::Diagnose(id));
    harness.run_steps(2);
    let run = &harness.state().runs()[0];
    assert!(run.diagnosis.is_none(), "the first (stale) report was dropped");
    assert!(run.diagnosis.running(), "the newer one is still awaited");
    let newest = run.diagnosis.requested;
    assert_eq!(harness.state_mut().run_worker_jobs(), 1);
    harness.run_steps(2);
    let run = &harness.state().runs()[0];
    assert!(run.diagnosis.is_some() && !run.diagnosis.running());
    assert_eq!(run.diagnosis.generation, newest);
}

/// The app and `identify` give the same model file, byte for byte, for the same run and
/// settings: one pipeline behind both (issue 12). A real run and the bundled sample.
#[test]
fn the_app_exports_the_model_file_identify_writes() {
    use imu_attest::gui::{Command, sample_run_path};
    let dir = tempfile::tempdir().expect("temp dir");
    for (k, path) in [sample_run_path().expect("sample"), real("broad25_tapping")]
        .into_iter()
        .enumerate()
    {
        let mut harness = app(vec![path.clone()]);
        // The sample has both blocks; the real run only a gyro.
        assert_eq!(
            harness
                .query_all_by_label(imu_attest::gui::view::controls::NOT_IN_THIS_RUN)
                .count(),
            k
        );
        let exported = dir.path().join(format!("app{k}.json"));
        harness
            .state_mut()
            .push_command(Command::ExportModel(Some(exported.clone())));
        harness.run_steps(2);
        let (a, b) = (
            std::fs::read(&exported).expect("exported"),
            identify_file(&path, &dir.path().join(format!("cli{k}.json"))),
        );
        assert!(
            a == b,
            "{}: the app's export differs from identify's file",
            path.display()
        );
    }
}

/// A glitch in the recording is shown with the run, in plain words, and the exported model holds
/// it as `identify`'s does.
#[test]
fn a_recording_fault_is_shown_and_exported() {
    use imu_attest::gui::Command;
    use imu_attest::sim::fault::FaultSpec;
    let dir = tempfile::tempdir().expect("temp dir");
    let mut config = SimConfig::new(Regime::Approach);
    config.duration_s = 60.0;
    config.seed = 33;
    config.faults = vec!["glitch:gy".parse::<FaultSpec>().expect("a fault spec")];
    let path = dir.path().join("glitched.csv");
    write_run(&simulate(&config).expect("simulated"), &path).expect("written");
    let mut harness = app(vec![path.clone()]);
    let summary = harness.state().runs()[0].summary().cloned().expect("loaded");
    assert!(!summary.recording_faults.is_empty(), "the glitch is found");
    let sentence = summary.recording_faults[0].to_string();
    assert!(sentence.contains("gy"), "{sentence}");
    harness.get_by_label(&format!("recording fault: {sentence}"));
    // The Time series view marks it on its channel's plot (named in the key above the plot).
    harness.get_by_label("Time series").click();
    harness.run_steps(3);
    harness.get_by_label(&summary.recording_faults[0].short_label());
    let exported = dir.path().join("m.json");
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(exported.clone())));
    harness.run_steps(2);
    let text = std::fs::read_to_string(&exported).expect("exported");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(
        v["recording_faults"].as_array().map(Vec::len),
        Some(summary.recording_faults.len())
    );
    // With the glitch bridged on both paths, the app's file is identify's, byte for byte.
    let written = identify_file(&path, &dir.path().join("cli.json"));
    assert!(written == text.as_bytes(), "app and identify differ");
}

/// A block whose clock drifts: the results show the stretches' delays with the drift named.
#[test]
fn results_show_the_stretches_and_name_a_drifting_clock() {
    use imu_attest::gui::view::stationarity::stationarity_label;
    let dir = tempfile::tempdir().expect("temp dir");
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 240.0;
    config.seed = 35;
    config.effects = vec!["clock_drift:gyro@2".parse().expect("an effect spec")];
    let path = dir.path().join("drift.csv");
    write_run(&simulate(&config).expect("simulated"), &path).expect("written");
    let harness = app(vec![path]);
    let id = harness.state().runs()[0]
        .identification
        .value
        .clone()
        .expect("identified");
    let gyro = id.model.blocks.get("gyro").expect("gyro");
    let st = gyro.stationarity.as_ref().expect("240 s is cut into stretches");
    let label = stationarity_label("gyro", st);
    assert!(label.contains("the delay drifts"), "{label}");
    harness.get_by_label(&label);
    let accel = id.model.blocks.get("accel").expect("accel");
    let label = stationarity_label("accel", accel.stationarity.as_ref().expect("cut"));
    assert!(label.contains("no significant drift"), "{label}");
    harness.get_by_label(&label);
}

/// A span set in the app: the results say so, and the export is `identify --settings` with the
/// same span, byte for byte.
#[test]
fn a_span_set_in_the_app_is_identify_s_span() {
    use imu_attest::gui::{Command, sample_run_path};
    let dir = tempfile::tempdir().expect("temp dir");
    let path = sample_run_path().expect("sample");
    let mut harness = app(vec![path.clone()]);
    let settings = Settings {
        span_s: Some([20.0, 100.0]),
        ..Settings::default()
    };
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings.clone())));
    harness.run_steps(6);
    harness.get_by_label("gyro analysed over t = 20.00 to 100.00 s of the record");
    let exported = dir.path().join("app.json");
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(exported.clone())));
    harness.run_steps(2);
    let settings_path = dir.path().join("span.json");
    std::fs::write(&settings_path, serde_json::to_vec(&settings).expect("json")).expect("written");
    let out = dir.path().join("cli.json");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .arg("identify")
        .arg(&path)
        .arg("--settings")
        .arg(&settings_path)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let app_file = std::fs::read(&exported).expect("exported");
    assert!(
        app_file == std::fs::read(&out).expect("written"),
        "the app's span differs from identify's"
    );
    let v: serde_json::Value = serde_json::from_slice(&app_file).expect("json");
    assert_eq!(v["settings"]["span_s"], serde_json::json!([20.0, 100.0]));
}
