//! The app's identification, comparison, export and fault handling, driven through AccessKit
//! (`egui_kittest`, no GPU). The worker runs synchronously (or, for the cancel test, only when
//! told), so every assertion sees finished results and nothing depends on timing.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::pipeline::Stage;
use imu_attest::gui::view::compare::significance_label;
use imu_attest::gui::view::results::{k_row_label, tau_label};
use imu_attest::gui::{App, AppOptions, Command, WorkerMode, sample_run_path};
use imu_attest::ident::settings::{Estimate, LambdaSetting, OrderSetting};
use imu_attest::model::{MODEL_SCHEMA, Model};
use imu_attest::run::LoadOptions;

use crate::common::gui as gui_common;
use gui_common::options;

fn app(options: AppOptions) -> Harness<'static, App> {
    gui_common::app(options, 3)
}

fn sample_app() -> Harness<'static, App> {
    app(options(
        vec![sample_run_path().expect("sample run")],
        WorkerMode::Synchronous,
    ))
}

/// The gyro block's shown tau line and first K row, from the app's current identification.
fn gyro_labels(harness: &Harness<'_, App>) -> (String, String) {
    let run = &harness.state().runs()[0];
    let id = run.identification.as_ref().expect("identified");
    let m = id.model.blocks.get("gyro").expect("gyro");
    (tau_label("gyro", m), k_row_label("gyro", m, 0))
}

fn set(harness: &mut Harness<'_, App>, edit: impl FnOnce(&mut imu_attest::ident::settings::Settings)) {
    let mut settings = harness.state().settings().clone();
    edit(&mut settings);
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings)));
    harness.run_steps(3);
}

/// The first run's current identification.
fn identification(harness: &Harness<'_, App>) -> Arc<imu_attest::gui::pipeline::Identification> {
    harness.state().runs()[0]
        .identification
        .value
        .clone()
        .expect("identified")
}

/// A new identification whose spectra and factorisations are the old ones: only the Wiener stage
/// and the fit were redone.
fn assert_only_the_fit_redone(
    before: &imu_attest::gui::pipeline::Identification,
    after: &imu_attest::gui::pipeline::Identification,
) {
    assert!(!std::ptr::eq(before, after), "a new identification");
    for (a, b) in before.blocks().iter().zip(after.blocks()) {
        assert!(Arc::ptr_eq(&a.spectra, &b.spectra), "spectra not redone");
        assert!(
            Arc::ptr_eq(&a.factorisation, &b.factorisation),
            "factorisation not redone"
        );
    }
}

#[test]
fn lambda_and_order_changes_update_k_and_tau_and_redo_only_the_fit() {
    let mut harness = sample_app();
    assert!(
        harness.state().errors().is_empty(),
        "{:?}",
        harness.state().errors()
    );
    let (tau0, k0) = gyro_labels(&harness);
    harness.get_by_label(&tau0);
    harness.get_by_label(&k0);
    let before = identification(&harness);

    set(&mut harness, |s| {
        s.lambda = LambdaSetting::Values([0.2, 0.2, 0.2]);
    });
    let (_, k1) = gyro_labels(&harness);
    assert_ne!(k1, k0, "K follows Lambda");
    harness.get_by_label(&k1);
    assert!(harness.query_by_label(&k0).is_none(), "the old K is gone");
    let after = identification(&harness);
    assert_only_the_fit_redone(&before, &after);

    let chosen = after.model.blocks["gyro"].order;
    let other = if chosen == 2 { 1 } else { 2 };
    set(&mut harness, |s| s.order = OrderSetting::Fixed(other).into());
    let (tau2, _) = gyro_labels(&harness);
    assert_ne!(tau2, tau0);
    harness.get_by_label(&tau2);
    let id = identification(&harness);
    assert_eq!(id.model.blocks["gyro"].order, other);
    // The richer model's poles are shown with their time constants or frequency and damping.
    let poles = imu_attest::gui::view::results::pole_lines("gyro", &id.model.blocks["gyro"]);
    assert_eq!(poles.len(), other);
    for line in &poles {
        harness.get_by_label(line);
    }
    let shown = harness
        .get_all_by_label_contains(&format!("order {other} (fixed)"))
        .count();
    assert_eq!(shown, 2, "both blocks at the fixed order");
}

/// An order per block, picked in the Controls' combo boxes: the accelerometer fixed at 1, the
/// gyro left on auto; Results says which is which, and the exported model's settings keep both.
#[test]
fn an_order_per_block_from_the_controls_reaches_the_model_and_its_file() {
    let mut harness = sample_app();
    let gyro_auto = harness.state().runs()[0]
        .identification
        .as_ref()
        .expect("identified")
        .model
        .blocks["gyro"]
        .order;
    harness.get_by_label("accel order").click();
    harness.run_steps(2);
    harness.get_by_label("accel 1").click();
    harness.run_steps(4);
    let settings = harness.state().settings().clone();
    assert_eq!(
        (settings.order.gyro, settings.order.accel),
        (OrderSetting::Auto, OrderSetting::Fixed(1))
    );
    let id = identification(&harness);
    assert_eq!(id.model.blocks["accel"].order, 1);
    assert_eq!(id.model.blocks["gyro"].order, gyro_auto, "the gyro stays on auto");
    assert_eq!(harness.get_all_by_label_contains("order 1 (fixed)").count(), 1);
    assert_eq!(
        harness
            .get_all_by_label_contains("(auto: lowest BIC among the admissible orders)")
            .count(),
        1
    );
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("per_block.json");
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(out.clone())));
    harness.run_steps(2);
    let text = std::fs::read_to_string(&out).expect("exported");
    let json: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(
        json["settings"]["order"],
        serde_json::json!({"gyro": "auto", "accel": 1}),
        "{}",
        json["settings"]
    );
}

/// The estimate, picked in the Controls' combo box: the paper's causal Wiener instead of the
/// default `H1`. The `H1` fit has no causal stage; the causal one adds it to the same
/// factorisation (the spectra and the disturbance's factor are not redone), and back to `H1`
/// nothing but the fit is redone. Results names the estimate Lambda applies to, and the exported
/// model's settings keep it.
#[test]
fn the_estimate_from_the_controls_refits_and_is_named_in_results_and_the_model() {
    let mut harness = sample_app();
    let before = identification(&harness);
    assert_eq!(harness.state().settings().estimate, Estimate::H1);
    assert_eq!(
        harness
            .get_all_by_label_contains("on the H1 (measured cross-spectrum) estimate")
            .count(),
        before.blocks().len()
    );
    harness.get_by_label("estimate").click();
    harness.run_steps(2);
    harness.get_by_label("causal Wiener W0 (paper)").click();
    harness.run_steps(4);
    assert_eq!(harness.state().settings().estimate, Estimate::CausalWiener);
    let after = identification(&harness);
    assert!(
        !after.provisional(),
        "settled: the causal stage and the fit from scratch"
    );
    for (a, b) in before.blocks().iter().zip(after.blocks()) {
        assert!(Arc::ptr_eq(&a.spectra, &b.spectra), "spectra not redone");
        let (fa, fb) = (&a.factorisation, &b.factorisation);
        assert!(
            fa.causal.is_none(),
            "{}: an H1 fit computes no causal stage",
            a.block
        );
        assert!(fb.causal.is_some(), "{}: the causal stage added", b.block);
        assert!(
            Arc::ptr_eq(&fa.noise_factor, &fb.noise_factor),
            "disturbance factor not redone"
        );
        assert_ne!(
            a.structural.k, b.structural.k,
            "{}: K is fitted to the other estimate",
            a.block
        );
    }
    assert_eq!(
        harness
            .get_all_by_label_contains("on the causal Wiener W0 (paper) estimate")
            .count(),
        after.blocks().len()
    );
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("causal.json");
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(out.clone())));
    harness.run_steps(2);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("exported")).expect("json");
    assert_eq!(json["settings"]["estimate"], "causal_wiener");
    for b in json["blocks"].as_object().expect("blocks").values() {
        let refinement = b["fit"]["causal_grid_refinement"].as_u64().expect("causal grid");
        assert!([2, 4, 8, 16].contains(&refinement), "{refinement}");
        assert!(b["fit"]["input_factor_error"].as_f64().expect("input factor") < 1e-6);
    }

    // Back to H1: the factorisation keeps its causal stage (cached), only the fit is redone.
    harness.get_by_label("estimate").click();
    harness.run_steps(2);
    harness.get_by_label("H1 (measured cross-spectrum)").click();
    harness.run_steps(4);
    assert_eq!(harness.state().settings().estimate, Estimate::H1);
    assert_only_the_fit_redone(&after, &identification(&harness));
}

#[test]
fn a_worker_panic_is_shown_the_last_result_kept_and_the_app_goes_on() {
    let mut harness = sample_app();
    let good = harness.state().runs()[0]
        .identification
        .value
        .clone()
        .expect("identified");
    let id = harness.state().runs()[0].id;
    harness
        .state_mut()
        .push_command(Command::InjectPanic(id, Stage::Identify));
    harness.run_steps(2);
    let app = harness.state();
    let run = &app.runs()[0];
    assert!(
        app.errors()
            .iter()
            .any(|e| e.contains("panic") && e.contains("identification")),
        "{:?}",
        app.errors()
    );
    assert!(Arc::ptr_eq(run.identification.as_ref().expect("kept"), &good));
    assert!(!run.busy(), "not spinning forever after a failure");
    harness.get_by_label_contains("showing the last good result");
    harness.get_by_label(&gyro_labels(&harness).0);
    // Still responsive: a new order is identified and clears the failure.
    set(&mut harness, |s| s.order = OrderSetting::Fixed(0).into());
    let run = &harness.state().runs()[0];
    assert!(run.identification.error.is_none());
    assert_eq!(
        run.identification.as_ref().expect("new").model.blocks["gyro"].order,
        0
    );
}

#[test]
fn an_observer_failure_is_said_in_the_time_series_until_an_analysis_goes_through() {
    let mut harness = sample_app();
    harness.get_by_label("Time series").click();
    harness.run_steps(2);
    let id = harness.state().runs()[0].id;
    harness
        .state_mut()
        .push_command(Command::InjectPanic(id, Stage::Motion));
    harness.run_steps(2);
    assert!(harness.state().runs()[0].motion.error.is_some());
    harness.get_by_label_contains("observer failed");
    assert!(
        harness.query_by_label_contains("observer running").is_none(),
        "not a spinner for ever"
    );
    set(&mut harness, |s| s.order = OrderSetting::Fixed(0).into());
    assert!(harness.state().runs()[0].motion.error.is_none());
    assert!(harness.query_by_label_contains("observer failed").is_none());
}

#[test]
fn two_runs_are_compared_side_by_side() {
    let approach = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sample_runs/approach.csv.gz");
    let paths = vec![sample_run_path().expect("sample run"), approach];
    let mut harness = app(options(paths, WorkerMode::Synchronous));
    harness.run_steps(2);
    harness.get_by_label("Compare").click();
    harness.run_steps(2);
    harness.get_by_label("compare cruise.csv.gz").click();
    harness.run_steps(1);
    harness.get_by_label("compare approach.csv.gz").click();
    harness.run_steps(2);
    let app = harness.state();
    assert_eq!(app.compared().len(), 2);
    let c = app.comparison().expect("two identified runs").clone();
    let regimes: Vec<&str> = c.runs.iter().map(|r| r.source.regime.as_str()).collect();
    assert_eq!(regimes, ["cruise", "approach"]);
    for (run, compared) in app.runs().iter().zip(&c.runs) {
        let model = &run.identification.as_ref().expect("identified").model;
        for (name, b) in &model.blocks {
            assert_eq!(compared.blocks[name].k, b.k);
            assert_eq!(compared.blocks[name].tau_s.to_bits(), b.tau_s.to_bits(), "copied");
        }
    }
    harness.get_by_label(&significance_label(&c, "gyro"));
    harness.get_by_label("approach.csv.gz - cruise.csv.gz");
    // K elements named as everywhere else; no order note for models of one order.
    harness.get_by_label("K gx/wy");
    assert!(
        harness
            .query_by_label(imu_attest::gui::view::compare::ORDERS_DIFFER)
            .is_none()
    );
}

/// Three runs: six columns, wider than the tab. The table scrolls sideways inside the tab: its
/// last column, scrolled to, lies left of the Results panel (before, it ran on under it).
#[test]
fn a_wide_comparison_scrolls_and_never_hides_under_results() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("sample_runs");
    let names = ["cruise", "approach", "turbulent_cruise"];
    let paths = names.map(|n| dir.join(format!("{n}.csv.gz"))).to_vec();
    let mut harness = app(options(paths, WorkerMode::Synchronous));
    harness.run_steps(2);
    harness.get_by_label("Compare").click();
    harness.run_steps(2);
    for n in names {
        harness.get_by_label(&format!("compare {n}.csv.gz")).click();
        harness.run_steps(2);
    }
    assert_eq!(harness.state().comparison().expect("three runs").runs.len(), 3);
    let results_left = harness.get_by_label("Results").rect().min.x;
    let last = "turbulent_cruise.csv.gz - approach.csv.gz";
    harness.get_by_label(last).scroll_to_me();
    harness.run_steps(3);
    let rect = harness.get_by_label(last).rect();
    assert!(
        rect.max.x <= results_left,
        "the last column {rect:?} runs under Results (left edge {results_left})"
    );
}

#[test]
fn an_exported_model_reads_back_and_an_input_is_never_overwritten() {
    let mut harness = sample_app();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cruise_model.json");
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(out.clone())));
    harness.run_steps(2);
    let text = std::fs::read_to_string(&out).expect("written");
    let mut model: Model = serde_json::from_str(&text).expect("a model file");
    assert_eq!(model.schema, MODEL_SCHEMA);
    // The file has the noise terms (computed on the worker at export, as `identify` does);
    // everything else is the model shown.
    assert!(
        model.blocks.values().all(|b| b.noise.is_some()),
        "noise terms exported"
    );
    for b in model.blocks.values_mut() {
        b.noise = None;
    }
    let shown = &harness.state().runs()[0]
        .identification
        .value
        .clone()
        .expect("identified")
        .model;
    assert_eq!(&model, shown);
    harness.get_by_label_contains("model written to");

    let input = harness.state().runs()[0].path.clone();
    let size = std::fs::metadata(&input).expect("input").len();
    harness
        .state_mut()
        .push_command(Command::ExportModel(Some(input.clone())));
    harness.run_steps(2);
    assert!(
        harness.state().errors().iter().any(|e| e.contains("refusing")),
        "{:?}",
        harness.state().errors()
    );
    assert_eq!(std::fs::metadata(&input).expect("input").len(), size);
}

#[test]
fn a_load_is_cancelled_from_its_cancel_button() {
    let mut harness = app(options(
        vec![sample_run_path().expect("sample run")],
        WorkerMode::Manual,
    ));
    assert!(harness.state().runs()[0].busy(), "still loading: the job waits");
    harness.get_by_label("Cancel").click();
    harness.run_steps(2);
    assert_eq!(harness.state_mut().run_worker_jobs(), 1);
    harness.run_steps(2);
    let app = harness.state();
    assert!(app.runs().is_empty(), "nothing loaded");
    assert_eq!(app.errors(), ["loading cruise.csv.gz cancelled"]);
    harness.get_by_label("loading cruise.csv.gz cancelled");
}

#[test]
fn a_run_too_large_for_memory_is_refused_in_the_error_panel() {
    // 100 000 rows of 7 columns: about 5.6 MB decoded.
    let dir = tempfile::tempdir().expect("tempdir");
    let big = dir.path().join("big.csv");
    let mut text = String::from("t,roll,yaw,pitch,gx,gy,gz\n");
    for k in 0..100_000 {
        writeln!(text, "{},0.1,0.2,0.3,0.01,0.02,0.03", f64::from(k) * 0.002).expect("to a string");
    }
    std::fs::write(&big, text).expect("written");
    let mut opts = options(vec![big], WorkerMode::Synchronous);
    opts.load = LoadOptions {
        memory_limit_bytes: Some(1_000_000),
        // Several chunks: the size check runs after the first.
        chunk_bytes: 1 << 16,
        ..LoadOptions::default()
    };
    let harness = app(opts);
    let app = harness.state();
    assert!(app.runs().is_empty());
    assert_eq!(app.errors().len(), 1, "{:?}", app.errors());
    assert!(
        app.errors()[0].contains("only 1 MB available"),
        "{}",
        app.errors()[0]
    );
    harness.get_by_label_contains("only 1 MB available");
}

/// File > Export report: the menu offers it, and the certificate of the selected run is written
/// by the threaded worker (identification, noise terms and diagnosis on its cached session)
/// while the app keeps drawing; the status line says where it went.
#[test]
fn the_report_is_exported_from_the_app_by_the_worker_thread() {
    let mut harness = app(options(
        vec![sample_run_path().expect("sample run")],
        WorkerMode::Thread,
    ));
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Export report (HTML)…");
    harness.key_press(eframe::egui::Key::Escape);
    let deadline = std::time::Instant::now() + std::time::Duration::from_mins(5);
    while harness.state().runs()[0].identification.value.is_none() {
        assert!(std::time::Instant::now() < deadline, "identified in time");
        harness.run_steps(1);
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cruise_report.html");
    harness
        .state_mut()
        .push_command(Command::ExportReport(Some(out.clone())));
    while harness
        .state()
        .status()
        .is_none_or(|s| !s.contains("report written to"))
    {
        assert!(
            std::time::Instant::now() < deadline,
            "report written in time: {:?}",
            harness.state().errors()
        );
        harness.run_steps(1);
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let html = std::fs::read_to_string(&out).expect("written");
    for section in [
        "id=\"block-gyro\"",
        "class=\"noise\"",
        "id=\"diagnosis\"",
        "overlapping Allan deviation",
    ] {
        assert!(html.contains(section), "{section}");
    }
    // Over an input: refused, in the error panel, nothing written.
    let input = harness.state().runs()[0].path.clone();
    let size = std::fs::metadata(&input).expect("input").len();
    harness
        .state_mut()
        .push_command(Command::ExportReport(Some(input.clone())));
    harness.run_steps(2);
    assert!(harness.state().errors().iter().any(|e| e.contains("refusing")));
    assert_eq!(std::fs::metadata(&input).expect("input").len(), size);
}

/// File > Export results table: every loaded run's rows (one per block) with the numbers the app
/// shows, the noise terms added on the worker; over an input it is refused.
#[test]
fn the_results_table_holds_every_loaded_run_with_the_shown_numbers() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs");
    let mut harness = app(options(
        vec![root.join("cruise.csv.gz"), root.join("approach.csv.gz")],
        WorkerMode::Synchronous,
    ));
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Export results table (CSV)…");
    harness.key_press(eframe::egui::Key::Escape);
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("results.csv");
    harness
        .state_mut()
        .push_command(Command::ExportResults(Some(out.clone())));
    harness.run_steps(2);
    harness.get_by_label_contains("results table written to");
    let text = std::fs::read_to_string(&out).expect("written");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "two runs, two blocks each");
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    for run in harness.state().runs() {
        let model = &run.identification.value.as_ref().expect("identified").model;
        for (block, b) in &model.blocks {
            let row = rows
                .iter()
                .find(|r| r[col("run")] == model.source.file && r[col("block")] == block)
                .expect("a row per run and block");
            let k11: f64 = row[col("K_11")].parse().expect("a number");
            assert_eq!(k11.to_bits(), b.k[0][0].to_bits());
            let tau: f64 = row[col("tau_s")].parse().expect("a number");
            assert_eq!(tau.to_bits(), b.tau_s.to_bits());
            assert!(!row[col("random_walk_1")].is_empty(), "noise terms on the worker");
        }
    }
    let input = harness.state().runs()[0].path.clone();
    harness
        .state_mut()
        .push_command(Command::ExportResults(Some(input)));
    harness.run_steps(2);
    assert!(harness.state().errors().iter().any(|e| e.contains("refusing")));
}

/// Without a usable file dialog a path can be typed: File > Open by typing a path loads the run,
/// and the same window writes an export.
#[test]
fn a_typed_path_opens_a_run_and_writes_an_export() {
    use imu_attest::gui::PathPurpose;
    let mut harness = app(options(Vec::new(), WorkerMode::Synchronous));
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Open by typing a path…").click();
    harness.run_steps(4);
    let sample = sample_run_path().expect("sample run");
    harness.get_by_label("path").focus();
    harness.run_steps(1);
    harness
        .get_by_label("path")
        .type_text(&sample.display().to_string());
    harness.run_steps(2);
    harness.get_by_label("OK").click();
    harness.run_steps(4);
    assert_eq!(harness.state().runs().len(), 1, "{:?}", harness.state().errors());
    assert!(harness.query_by_label("OK").is_none(), "the window closes");

    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("typed.csv");
    harness
        .state_mut()
        .push_command(Command::PromptPath(PathPurpose::ExportResults));
    harness.run_steps(2);
    harness.get_by_label("path").focus();
    harness.run_steps(1);
    harness.get_by_label("path").type_text(&out.display().to_string());
    harness.run_steps(2);
    harness.get_by_label("OK").click();
    harness.run_steps(4);
    assert!(
        std::fs::read_to_string(&out)
            .expect("written")
            .starts_with("run,sha256,")
    );
    // Cancel closes it without doing anything.
    harness
        .state_mut()
        .push_command(Command::PromptPath(PathPurpose::ExportModel));
    harness.run_steps(2);
    harness.get_by_label("Cancel").click();
    harness.run_steps(2);
    assert!(harness.query_by_label("Cancel").is_none());
}

/// The stretches are fitted at order 0, so the whole record's delay drawn beside them is its
/// order-0 fit's when the chosen model has poles (whose delay leaves their lag out): the accel
/// fixed at order 1 on the sample gets "whole record, order 0" in its stretch plot's key, the
/// gyro (order 0) keeps "whole record".
#[test]
fn the_stretch_plot_compares_a_model_with_poles_at_order_0() {
    let mut harness = sample_app();
    // "whole record" is also the span control's checkbox.
    let legends = |h: &Harness<'_, App>| h.get_all_by_label("whole record").count() - 1;
    assert_eq!(legends(&harness), 2, "both blocks at order 0");
    assert!(harness.query_by_label("whole record, order 0").is_none());
    set(&mut harness, |s| s.order.accel = OrderSetting::Fixed(1));
    let id = identification(&harness);
    assert_eq!(id.model.blocks["accel"].order, 1);
    assert_eq!(legends(&harness), 1, "the gyro's");
    assert_eq!(
        harness.get_all_by_label("whole record, order 0").count(),
        1,
        "the accel's"
    );
}
