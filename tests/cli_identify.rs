//! `imu-attest identify` through the binary: the contract's model file (section 4), exactly its
//! field names, a lossless round trip, and exit status 2 with one line for bad input.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::{Path, PathBuf};

use imu_attest::model::{MODEL_SCHEMA, Model};

use crate::binary;
use crate::binary::approach;
use binary::imu_attest;

fn simulated_run(dir: &Path) -> PathBuf {
    simulated_run_as(dir, "cruise.csv", &["--seed", "4"])
}

/// A 60 s cruise run written to `dir/file` by `simulate` with `extra` arguments.
fn simulated_run_as(dir: &Path, file: &str, extra: &[&str]) -> PathBuf {
    let run = dir.join(file);
    let mut args = vec!["simulate", "--regime", "cruise", "--duration", "60"];
    args.extend_from_slice(extra);
    args.extend(["--out", run.to_str().unwrap()]);
    let o = imu_attest(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    run
}

/// `identify RUN --settings SETTINGS --out OUT`.
fn identify_with(run: &Path, settings: &Path, out: &Path) -> std::process::Output {
    imu_attest(&[
        "identify",
        run.to_str().unwrap(),
        "--settings",
        settings.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

/// `identify RUN --out OUT` with the default settings.
fn identify_default(run: &Path, out: &Path) -> std::process::Output {
    imu_attest(&["identify", run.to_str().unwrap(), "--out", out.to_str().unwrap()])
}

/// The stderr of a refusal: exit status 2, one line, nothing written to `out`.
fn one_line_refusal(o: &std::process::Output, out: &Path) -> String {
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(!out.exists(), "nothing written: {stderr}");
    stderr
}

fn keys(v: &serde_json::Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

#[test]
fn model_file_has_the_contract_fields_and_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let settings = dir.path().join("s.json");
    std::fs::write(
        &settings,
        r#"{"welch": {"segment_len": 2048}, "order": 0, "lambda": "auto"}"#,
    )
    .unwrap();
    let out = dir.path().join("model.json");
    let o = identify_with(&run, &settings, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema"], MODEL_SCHEMA);
    assert_eq!(keys(&v), ["blocks", "schema", "settings", "source"]);
    assert_eq!(keys(&v["source"]), ["file", "regime", "sample_rate_hz", "sha256"]);
    assert_eq!(v["source"]["file"], "cruise.csv");
    assert_eq!(v["source"]["sha256"].as_str().unwrap().len(), 64);
    // Settings echoed as used: the file's values and the defaults of what it left out.
    assert_eq!(v["settings"]["welch"]["segment_len"], 2048);
    assert_eq!(v["settings"]["lambda"], "auto");
    assert_eq!(v["settings"]["order"], 0);
    assert_eq!(v["settings"]["band_hz"], "auto");
    assert_eq!(v["settings"]["estimate"], "h1");
    assert_eq!(v["settings"]["blocks"], serde_json::json!(["gyro", "accel"]));
    for (block, inputs, outputs) in [
        ("gyro", ["wx", "wy", "wz"], ["gx", "gy", "gz"]),
        ("accel", ["fx", "fy", "fz"], ["ax", "ay", "az"]),
    ] {
        let b = &v["blocks"][block];
        for field in [
            "inputs",
            "outputs",
            "K",
            "tau_s",
            "order",
            "frequency_hz",
            "W_u",
            "noise_psd",
            "coherence",
            "fit",
        ] {
            assert!(b.get(field).is_some(), "{block} lacks {field}");
        }
        assert_eq!(b["inputs"], serde_json::json!(inputs));
        assert_eq!(b["outputs"], serde_json::json!(outputs));
        let n = b["frequency_hz"].as_array().unwrap().len();
        assert!(n > 100);
        assert_eq!(b["W_u"]["re"].as_array().unwrap().len(), n);
        assert_eq!(b["W_u"]["im"][0].as_array().unwrap().len(), 3);
        assert_eq!(b["noise_psd"]["re"][0][0].as_array().unwrap().len(), 3);
        assert_eq!(b["coherence"].as_array().unwrap().len(), n);
        assert_eq!(b["coherence"][0].as_array().unwrap().len(), 3);
        let f0 = b["frequency_hz"][0].as_f64().unwrap();
        assert!(f0 >= 0.1, "band starts at {f0}");
        // The band used is in the file, and the bins lie inside it.
        let band = [
            b["band_hz"][0].as_f64().unwrap(),
            b["band_hz"][1].as_f64().unwrap(),
        ];
        let last = b["frequency_hz"][n - 1].as_f64().unwrap();
        assert!(band[0] >= 0.1 && band[1] <= 40.0 && band[0] < band[1], "{band:?}");
        assert!(f0 >= band[0] && last <= band[1], "{band:?} vs {f0}..{last}");
        // The H1 fit does not go through the causal stage, so the input's factor is not computed
        // (a causal fit's numbers: `tests/gui_app_ident.rs`).
        assert!(b["fit"].get("input_factor_error").is_none(), "{}", b["fit"]);
        assert!(b["fit"].get("causal_grid_refinement").is_none(), "{}", b["fit"]);
        let noise_factor_error = b["fit"]["noise_factor_error"].as_f64().unwrap();
        assert!(noise_factor_error < 1e-6, "{noise_factor_error:e}");
        // K near identity, a few-ms delay: a sanity check, not the accuracy test.
        assert!((b["K"][0][0].as_f64().unwrap() - 1.0).abs() < 0.01);
        assert!(b["tau_s"].as_f64().unwrap() > 0.0 && b["tau_s"].as_f64().unwrap() < 0.01);
    }
    let model: Model = serde_json::from_str(&text).unwrap();
    let again = serde_json::to_string_pretty(&model).unwrap();
    assert_eq!(
        serde_json::from_str::<serde_json::Value>(&again).unwrap(),
        v,
        "lossless round trip"
    );

    // A file written before the causal stage was skipped for H1 (both factor errors in one array,
    // the causal grid always, a number in every `regularised` warning) still reads.
    let mut older = v.clone();
    let fit = older["blocks"]["gyro"]["fit"].as_object_mut().unwrap();
    fit.remove("noise_factor_error");
    fit.insert("factor_errors".into(), serde_json::json!([2.5e-12, 3.5e-13]));
    fit.insert("causal_grid_refinement".into(), 4.into());
    fit.insert(
        "warnings".into(),
        serde_json::json!([{"kind": "regularised", "spectrum": "input", "bins": 4,
                             "band_bins": 64, "factor_error": 1.2e-12}]),
    );
    let older: Model = serde_json::from_value(older).expect("an older model file reads");
    let fit = &older.blocks["gyro"].fit;
    assert_eq!(fit.causal_grid_refinement, Some(4));
    assert_eq!((fit.input_factor_error, fit.noise_factor_error), (None, None));
    assert!(
        fit.warnings[0]
            .to_string()
            .ends_with("(factor reconstruction error 1.2e-12)")
    );
}

#[test]
fn bad_settings_and_inputs_exit_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let out = dir.path().join("m.json");
    let run_s = run.to_str().unwrap();
    let out_s = out.to_str().unwrap();
    let cases: Vec<(&str, &str)> = vec![
        (r#"{"band_hz": [0.1, 400]}"#, "band_hz"),
        (r#"{"weight_A": [[1,2,0],[2,1,0],[0,0,1]]}"#, "positive definite"),
        (
            r#"{"weight_A": [[2,0,0],[0,2,0],[0,0,2]], "lambda": [2, 0, 0]}"#,
            "singular",
        ),
        (r#"{"order": 9}"#, "order"),
        (
            r#"{"estimate": "w0"}"#,
            "s.json:1:17: estimate: unknown variant `w0`, expected `h1` or `causal_wiener`",
        ),
        (r#"{"welch": {"segment_len": 65536}}"#, "too few samples"),
        (r#"{"colour": "blue"}"#, "unknown field"),
        // A misspelt Welch field is refused, not ignored (the default segment used silently).
        (r#"{"welch": {"segment": 1024}}"#, "unknown field `segment`"),
        (
            "{\n  \"lambda\": [1, 2]\n}",
            "s.json:3:1: lambda: lambda must be three numbers",
        ),
    ];
    for (text, needle) in cases {
        let s = dir.path().join("s.json");
        std::fs::write(&s, text).unwrap();
        let o = identify_with(&run, &s, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{text}: {err}");
        assert!(err.contains(needle), "{text}: expected '{needle}' in {err}");
    }
    // Never over an input: the run, its sidecar, the settings.
    for target in [run.clone(), dir.path().join("cruise.json")] {
        let before = std::fs::read(&target).unwrap();
        let o = imu_attest(&["identify", run_s, "--out", target.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains("input"));
        assert_eq!(std::fs::read(&target).unwrap(), before);
    }
    let o = imu_attest(&[
        "identify",
        dir.path().join("none.csv").to_str().unwrap(),
        "--out",
        out_s,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists(), "no partial output");
}

#[test]
fn effects_accepted_from_a_list_or_a_discrepancy_report() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("lagged.csv");
    approach::approach_run(&run, "5", Some("sensor_lag:gyro"));
    let identify_run = |run: &Path, effects: &Path, out: &Path| {
        imu_attest(&[
            "identify",
            run.to_str().unwrap(),
            "--effects",
            effects.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let identify = |effects: &Path, out: &Path| identify_run(&run, effects, out);
    // A list.
    let list = dir.path().join("effects.json");
    std::fs::write(
        &list,
        r#"{"effects": [{"block": "gyro", "effect": "sensor_lag"}]}"#,
    )
    .unwrap();
    let from_list = dir.path().join("from_list.json");
    let o = identify(&list, &from_list);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model: Model = serde_json::from_str(&std::fs::read_to_string(&from_list).unwrap()).unwrap();
    let effects = model.blocks["gyro"]
        .effects
        .as_ref()
        .expect("the gyro's model has the lag");
    assert_eq!(effects.accepted[0].effect, imu_attest::effect::Effect::SensorLag);
    assert!(effects.accepted[0].parameter_std["T_s"].as_f64().unwrap() > 0.0);
    assert!(model.blocks["accel"].effects.is_none());
    // The discrepancy report of the same run names the lag: as an effects file it gives the same model.
    let report = dir.path().join("report.json");
    let o = imu_attest(&[
        "discrepancy",
        run.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let from_report = dir.path().join("from_report.json");
    let o = identify(&report, &from_report);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(&from_list).unwrap(),
        std::fs::read_to_string(&from_report).unwrap()
    );
    // A bad file: exit 2, one line naming the file, line and column; nothing written.
    std::fs::write(
        &list,
        "{\"effects\": [\n  {\"block\": \"gyro\", \"effect\": \"lagg\"}]}",
    )
    .unwrap();
    let bad = dir.path().join("bad.json");
    let o = identify(&list, &bad);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("effects.json: line 2, column") && err.contains("effects[0].effect"),
        "{err}"
    );
    assert!(!bad.exists());
    // An effect on a block the run does not have is said, not silently dropped.
    let gyro_only = simulated_run_as(dir.path(), "gyro_only.csv", &["--seed", "2", "--blocks", "gyro"]);
    std::fs::write(
        &list,
        r#"{"effects": [{"block": "accel", "effect": "lever_arm_error"}]}"#,
    )
    .unwrap();
    let out = dir.path().join("gyro_only_model.json");
    let o = identify_run(&gyro_only, &list, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("lever_arm_error not added: the run has no accel block"),
        "{err}"
    );
    // The effects file is an input: never written over.
    let o = identify(&list, &list);
    assert_eq!(o.status.code(), Some(2));
}

/// A run without a gyro block has no witness of the motion, so the stand's angle-noise colour
/// cannot be estimated: the accelerometer's model says so (on the command line and in the file).
/// The same block identified alone from a run that has a gyro does not: the gyro is the witness
/// whether or not it is identified.
#[test]
fn an_accelerometer_only_run_says_its_angle_noise_colour_is_unknown() {
    let dir = tempfile::tempdir().unwrap();
    let read = |path: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    };
    // The accelerometer's angle-noise warning in a model file, if any.
    let warning_in = |model: &Path| -> Option<serde_json::Value> {
        read(model)["blocks"]["accel"]["fit"]["warnings"]
            .as_array()?
            .iter()
            .find(|w| w["kind"] == "angle_noise_colour_unknown")
            .cloned()
    };
    let accel_only = simulated_run_as(
        dir.path(),
        "accel_only.csv",
        &["--seed", "3", "--blocks", "accel", "--stand", "real"],
    );
    let out = dir.path().join("accel_only_model.json");
    let o = imu_attest(&[
        "identify",
        accel_only.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("accel block: no sound gyro in this run to check the stand's angle noise against"),
        "{err}"
    );
    let warning = warning_in(&out).expect("the accelerometer-only model says it");
    let sidecar = read(&accel_only.with_extension("json"));
    assert_eq!(warning["declared"], true, "{warning}");
    // The sidecar's one declared level, on every axis.
    assert_eq!(
        warning["angle_noise_rad"],
        serde_json::Value::from(vec![sidecar["angle_noise_rad"].clone(); 3]),
        "{warning}"
    );

    let both = simulated_run_as(dir.path(), "both.csv", &["--seed", "3", "--stand", "real"]);
    let settings = dir.path().join("accel.json");
    std::fs::write(&settings, r#"{"blocks": ["accel"]}"#).unwrap();
    let out = dir.path().join("both_model.json");
    let o = identify_with(&both, &settings, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("no gyro block"));
    assert_eq!(warning_in(&out), None);
}

/// `run`'s CSV with the outputs of `columns` replaced by white noise (a dead block), written to
/// `dir/file` with `run`'s sidecar.
fn with_dead_columns(dir: &Path, run: &Path, file: &str, columns: &[&str]) -> PathBuf {
    let text = std::fs::read_to_string(run).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let dead_columns: Vec<usize> = columns
        .iter()
        .map(|c| header.iter().position(|h| h == c).unwrap())
        .collect();
    let mut rng = imu_attest::rng::Rng::new(8);
    let mut dead = header.join(",") + "\n";
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_owned).collect();
        for &c in &dead_columns {
            cells[c] = format!("{:.6e}", 1e-3 * rng.normal());
        }
        dead += &(cells.join(",") + "\n");
    }
    let dead_run = dir.join(file);
    std::fs::write(&dead_run, dead).unwrap();
    std::fs::copy(run.with_extension("json"), dead_run.with_extension("json")).unwrap();
    dead_run
}

fn model_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A run whose accelerometer outputs are noise alone (a dead block beside a good gyro): the
/// gyro is identified, exactly as on its own, and the accelerometer is refused beside it, in
/// the model file (`refused_blocks`) and in a warning; with both blocks dead, or the gyro alone
/// (a gyro's refusal is the run's), the run is refused in one line that does not offer to leave
/// a block out.
#[test]
fn a_dead_block_is_refused_beside_the_identified_one() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let dead_run = with_dead_columns(dir.path(), &run, "dead_accel.csv", &["ax", "ay", "az"]);
    let out = dir.path().join("m.json");
    let o = identify_default(&dead_run, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "imu-attest: warning: accel block not identified, the result holds the gyro block only: no usable band"
        ),
        "{stderr}"
    );
    let model = model_json(&out);
    assert_eq!(keys(&model["blocks"]), ["gyro"]);
    assert_eq!(keys(&model["refused_blocks"]), ["accel"]);
    let refused = &model["refused_blocks"]["accel"];
    assert_eq!(refused["kind"], "no_usable_band");
    assert!(refused.get("axis").is_none(), "{refused}");
    assert!(
        refused["reason"]
            .as_str()
            .unwrap()
            .starts_with("accel block: no usable band")
    );

    // The gyro alone: the same model of the gyro, nothing refused.
    let settings = dir.path().join("gyro.json");
    std::fs::write(&settings, r#"{"blocks": ["gyro"]}"#).unwrap();
    let alone = dir.path().join("alone.json");
    let o = identify_with(&dead_run, &settings, &alone);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let alone = model_json(&alone);
    assert!(alone.get("refused_blocks").is_none());
    for field in ["K", "tau_s", "order", "fit"] {
        assert_eq!(
            alone["blocks"]["gyro"][field], model["blocks"]["gyro"][field],
            "{field}"
        );
    }

    // Both blocks dead, or the gyro alone beside a good accelerometer: the run is refused (the
    // gyro witnesses every block's angle noise), and leaving a block out would not help.
    for (file, columns) in [
        ("dead_both.csv", &["ax", "ay", "az", "gx", "gy", "gz"][..]),
        ("dead_gyro.csv", &["gx", "gy", "gz"][..]),
    ] {
        let dead = with_dead_columns(dir.path(), &run, file, columns);
        let out = dir.path().join("none.json");
        let stderr = one_line_refusal(&identify_default(&dead, &out), &out);
        assert!(
            stderr.contains(&format!("{file}: gyro block: no usable band")),
            "{stderr}"
        );
        assert!(!stderr.contains("leave this block out"), "{stderr}");
    }
}

/// The loader's notices reach the user (contract section 2): an ignored column on a run that is
/// identified, and a missing sidecar beside the refusal it explains (its zero lever arm leaves
/// the accelerometer's vertical input flat; the gyro is identified).
#[test]
fn notices_are_printed_beside_what_they_explain() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let text = std::fs::read_to_string(&run).unwrap();
    let mut with_extra = String::new();
    for (i, line) in text.lines().enumerate() {
        with_extra += line;
        with_extra += if i == 0 { ",temp_c\n" } else { ",21.5\n" };
    }
    let extra = dir.path().join("extra.csv");
    std::fs::write(&extra, with_extra).unwrap();
    std::fs::copy(run.with_extension("json"), extra.with_extension("json")).unwrap();
    let out = dir.path().join("m.json");
    let o = identify_default(&extra, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("imu-attest: note: extra.csv: unknown column 'temp_c' kept and ignored"),
        "{stderr}"
    );
    assert!(!stderr.contains("no sidecar"), "{stderr}");
    assert!(model_json(&out).get("refused_blocks").is_none());

    std::fs::remove_file(extra.with_extension("json")).unwrap();
    std::fs::remove_file(&out).unwrap();
    let o = identify_default(&extra, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    for part in [
        "imu-attest: note: extra.csv: no sidecar extra.json",
        "lever arms zero",
        "imu-attest: warning: accel block not identified, the result holds the gyro block only: axis fy not excited",
        "accel_lever_arm_m",
    ] {
        assert!(stderr.contains(part), "{part}: {stderr}");
    }
    let model = model_json(&out);
    assert_eq!(keys(&model["blocks"]), ["gyro"]);
    assert_eq!(model["refused_blocks"]["accel"]["kind"], "not_excited");
    assert_eq!(model["refused_blocks"]["accel"]["axis"], "fy");
}

/// A refusal on a single-block run does not offer to leave its only block out: the first 4.4 s
/// of a real recording are the rest before the motion (no usable band).
#[test]
fn a_single_block_refusal_does_not_offer_to_leave_the_block_out() {
    let dir = tempfile::tempdir().unwrap();
    let run = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/broad07_fast_rotation.csv.gz");
    let settings = dir.path().join("rest.json");
    std::fs::write(&settings, r#"{"span_s": [21.6, 26.0]}"#).unwrap();
    let out = dir.path().join("m.json");
    let stderr = one_line_refusal(&identify_with(&run, &settings, &out), &out);
    assert!(stderr.contains("gyro block: no usable band"), "{stderr}");
    assert!(stderr.trim_end().ends_with("or give band_hz"), "{stderr}");
    assert!(!stderr.contains("leave this block out"), "{stderr}");
}

/// `imu-attest COMMAND --help` (or `-h`) prints that command's usage and exits 0, for every
/// command; it said "option --help needs a value" and exited 2. A misspelt command with
/// `--help` is still an unknown command (exit 2).
#[test]
fn each_command_s_help_prints_its_usage() {
    let commands = [
        "simulate",
        "identify",
        "discrepancy",
        "compare",
        "report",
        "batch",
        "inspect",
        "bench",
        "gui",
    ];
    for command in commands {
        for flag in ["--help", "-h"] {
            let o = imu_attest(&[command, flag]);
            let text = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{command} {flag}: {text}");
            let line = if command == "gui" {
                "imu-attest [gui] ".to_owned()
            } else {
                format!("imu-attest {command} ")
            };
            assert!(text.contains(&line), "{command}: {text}");
            let others = text.matches("  imu-attest ").count();
            assert_eq!(others, 1, "{command}: its own usage only: {text}");
        }
    }
    let o = imu_attest(&["idnetify", "--help"]);
    let text = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("unknown command 'idnetify'"), "{text}");
}
