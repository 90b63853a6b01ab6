//! `imu-attest discrepancy` through the binary: the contract's report (section 5) with its field
//! names, the hidden effect named, `--model` honoured, and exit status 2 with one line for bad
//! input, leaving no output file.

use std::path::{Path, PathBuf};
use std::process::Output;

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, load};

use crate::binary;
use crate::binary::approach;
use binary::imu_attest;

fn simulated_run(dir: &Path, name: &str, effect: Option<&str>) -> PathBuf {
    let run = dir.join(format!("{name}.csv"));
    approach::approach_run(&run, "7", effect);
    run
}

/// `discrepancy RUN --out OUT` with default settings, which must succeed: its stderr.
fn discrepancy(run: &Path, out: &Path) -> String {
    let o = imu_attest(&[
        "discrepancy",
        run.to_str().expect("a UTF-8 path"),
        "--out",
        out.to_str().expect("a UTF-8 path"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn one_line_error(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    err
}

#[test]
fn report_names_the_hidden_effect_with_the_contract_fields() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path(), "lagged", Some("sensor_lag:accel"));
    let model = dir.path().join("model.json");
    let o = imu_attest(&[
        "identify",
        run.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("report.json");
    let o = imu_attest(&[
        "discrepancy",
        run.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["schema"], "imu-attest/discrepancy/1");
    assert_eq!(v["verdict"], "effect_found");
    let first = &v["findings"][0];
    for key in [
        "block",
        "effect",
        "name",
        "parameters",
        "gap_before_db",
        "gap_after_db",
        "evidence",
    ] {
        assert!(first.get(key).is_some(), "finding lacks '{key}': {first}");
    }
    assert_eq!(
        (first["block"].as_str(), first["effect"].as_str()),
        (Some("accel"), Some("sensor_lag"))
    );
    assert!(first["gap_after_db"].as_f64().unwrap() < first["gap_before_db"].as_f64().unwrap());
    // The evidence says how much of the misfit the hidden lag is: most of it, not a sliver.
    let evidence = first["evidence"].as_str().unwrap_or_default();
    assert!(
        evidence.contains("% of the misfit's power") && !evidence.contains("small"),
        "{evidence}"
    );
    // The given model's own gap, as it is, is reported per channel.
    let given = &v["blocks"]["accel"]["given_model_gap_db"];
    assert_eq!(given.as_array().map(Vec::len), Some(3), "{given}");
    // The model's settings are the diagnosis's, its estimate included.
    assert_eq!(v["settings"]["estimate"], "h1", "{}", v["settings"]);
    // What the tone search could have seen, per block: written and said.
    for block in ["gyro", "accel"] {
        let limit = &v["blocks"][block]["tone_limit"];
        let (f, a) = (&limit["frequency_hz"], &limit["amplitude"]);
        assert!(limit["chi2_needed"].as_f64().is_some_and(|c| c > 0.0), "{limit}");
        assert_eq!(f.as_array().map(Vec::len), a.as_array().map(Vec::len), "{limit}");
        let said = format!("imu-attest: note: {block} block: the tone search's limit");
        assert!(String::from_utf8_lossy(&o.stderr).contains(&said), "{said}");
    }
    // And of the effects linear in the model it did not name: the gyro's g-sensitivity.
    let limits = v["blocks"]["gyro"]["size_limits"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let g = limits
        .iter()
        .find(|l| l["effect"] == "g_sensitivity")
        .unwrap_or_else(|| panic!("{limits:?}"));
    assert_eq!(g["component"].as_array().map(Vec::len), Some(9), "{g}");
    assert!(g["any_direction"].as_f64().is_some_and(|a| a > 0.0), "{g}");
    let said = "imu-attest: note: gyro block: no gyro g-sensitivity named; its evidence would have reached";
    assert!(String::from_utf8_lossy(&o.stderr).contains(said), "{said}");
}

#[test]
fn bad_input_exits_2_with_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path(), "clean", None);
    let out = dir.path().join("report.json");
    let (run_s, out_s) = (run.to_str().unwrap(), out.to_str().unwrap());

    // Output over an input.
    let err = one_line_error(&imu_attest(&["discrepancy", run_s, "--out", run_s]));
    assert!(err.contains("input"), "{err}");

    // A model file that is not one.
    let bad_model = dir.path().join("bad.json");
    std::fs::write(&bad_model, "{\"schema\": \"imu-attest/model/1\", \"blocks\": 3}").unwrap();
    let err = one_line_error(&imu_attest(&[
        "discrepancy",
        run_s,
        "--model",
        bad_model.to_str().unwrap(),
        "--out",
        out_s,
    ]));
    assert!(err.contains("bad.json"), "{err}");

    // A model file whose accepted lag is no filter: a damping below zero (refused where it is
    // read: file, line and column), a damping without its lag's time constant.
    let model = dir.path().join("model.json");
    let o = imu_attest(&["identify", run_s, "--out", model.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut m: serde_json::Value = serde_json::from_slice(&std::fs::read(&model).unwrap()).unwrap();
    for (lag, said) in [
        (
            r#""lag_s": 0.002, "lag_damping": -0.5,"#,
            "lag_damping must be finite and positive",
        ),
        (
            r#""lag_damping": 0.7,"#,
            "damping without its time constant lag_s",
        ),
    ] {
        let effects = format!(
            r#"{{"accepted": [], {lag} "identified": {{"K": [[1,0,0],[0,1,0],[0,0,1]], "tau_s": 0.004,
            "order": 0}}, "band_hz": [0.5, 40], "chi2_per_dof": [1, 1], "gap_db": [[0,0,0],[0,0,0]]}}"#
        );
        m["blocks"]["gyro"]["effects"] = serde_json::from_str(&effects).unwrap();
        let edited = dir.path().join("edited.json");
        std::fs::write(&edited, serde_json::to_string_pretty(&m).unwrap()).unwrap();
        let err = one_line_error(&imu_attest(&[
            "discrepancy",
            run_s,
            "--model",
            edited.to_str().unwrap(),
            "--out",
            out_s,
        ]));
        assert!(err.contains("edited.json") && err.contains(said), "{err}");
    }

    // A band the run cannot hold.
    let settings = dir.path().join("s.json");
    std::fs::write(&settings, r#"{"band_hz": [0.1, 400.0]}"#).unwrap();
    one_line_error(&imu_attest(&[
        "discrepancy",
        run_s,
        "--settings",
        settings.to_str().unwrap(),
        "--out",
        out_s,
    ]));

    // No run at all.
    one_line_error(&imu_attest(&["discrepancy", "--out", out_s]));
    assert!(!out.exists(), "a failed command left an output file");
}

/// A real run whose optical reference is noise above its slow motion (`tests/data/real`, BROAD,
/// CC BY 4.0): the diagnosis's band ends where its inputs are not the motion, the report holds
/// the limit and the band searched, and the command line says so once the report is written.
#[test]
fn the_band_ended_below_the_reference_s_noise_is_said_and_written() {
    let dir = tempfile::tempdir().unwrap();
    let run = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/broad11_slow_translation.csv.gz");
    let out = dir.path().join("report.json");
    let err = discrepancy(&run, &out);
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("imu-attest: note: gyro block: the diagnosis searched 0.10-"))
        .collect();
    assert_eq!(said.len(), 1, "{err}");
    // The real run is explained over its band: nothing is said to be left unexplained.
    assert!(!err.contains("leaves chi2/dof"), "{err}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let gyro = &report["blocks"]["gyro"];
    let top = gyro["band_hz"][1].as_f64().unwrap();
    let limit = &gyro["input_limit"];
    assert_eq!(limit["band_ended"], serde_json::json!(true), "{gyro}");
    assert!(top < 40.0, "{gyro}");
    assert_eq!(
        report["settings"]["band_hz"],
        serde_json::json!("auto"),
        "the band as asked"
    );
    assert!(
        said[0].contains(&format!("{top:.2} Hz, not up to 40.0 Hz")),
        "{}",
        said[0]
    );
}

/// A significant candidate the search refused is written with its reason and said once: on the
/// tapping recording (`tests/data/real`) a first-order lag that would make the three channels'
/// residual power grow, a note (the optical reference's band limit, not a lost finding).
#[test]
fn a_significant_candidate_not_named_is_written_and_said() {
    let dir = tempfile::tempdir().unwrap();
    let run = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/broad25_tapping.csv.gz");
    let out = dir.path().join("report.json");
    let err = discrepancy(&run, &out);
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("significant but not named"))
        .collect();
    assert_eq!(said.len(), 1, "{err}");
    assert!(
        said[0].starts_with("imu-attest: note: gyro block: "),
        "{}",
        said[0]
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let refused = report["blocks"]["gyro"]["not_named"]
        .as_array()
        .expect("not_named written");
    let lag = refused
        .iter()
        .find(|r| r["effect"] == "sensor_lag")
        .expect("the lag refused");
    assert_eq!(lag["reason"]["kind"], "total_grows", "{lag}");
    let (before, after) = (
        lag["reason"]["before_db"].as_f64().unwrap(),
        lag["reason"]["after_db"].as_f64().unwrap(),
    );
    assert!(
        after > before && lag["criterion_gain"].as_f64().unwrap() > 0.0,
        "{lag}"
    );
    assert!(
        report["findings"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f["effect"] != "sensor_lag"),
        "a refused effect named"
    );
    // The certificate says it too, as a note (a plain paragraph, not a warning's).
    let html = dir.path().join("certificate.html");
    let o = imu_attest(&["report", run.to_str().unwrap(), "--out", html.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("<p>gyro block: significant but not named"),
        "not in the certificate as a note"
    );
}

/// Angles measured through a causal 20 Hz filter (`simulate --angle-filter-hz`): until 30 Nov no
/// effect could take it, the search named effects the run does not have and the model with them
/// left chi2/dof 5.1-5.3, which each block's warning said. The stand's band limit
/// (`reference_band_limit`) now explains it: named on both blocks, causal, its corner at the
/// filter's, chi2/dof near 1 after, and no "leaves chi2/dof" said. With the band limit rejected
/// (the app's Reject; the library's options) the rest is as before, and the words the command
/// line prints for it (`Report::unexplained`) say it once per block. The hidden sensor lag's
/// run, which its finding explains, says nothing of the kind.
#[test]
fn what_the_findings_leave_unexplained_is_said() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("filtered.csv");
    let o = imu_attest(&[
        "simulate",
        "--regime",
        "cruise",
        "--duration",
        "120",
        "--seed",
        "1",
        "--angle-filter-hz",
        "20",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("report.json");
    let err = discrepancy(&run, &out);
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert!(!err.contains("leaves chi2/dof"), "{err}");
    for block in ["gyro", "accel"] {
        let after = report["blocks"][block]["chi2_per_dof"][1].as_f64().unwrap();
        assert!(after < 2.0, "{block}: {after}");
        let limit = report["findings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["block"] == block && f["effect"] == "reference_band_limit")
            .unwrap_or_else(|| panic!("{block}: no band limit: {report}"));
        let corner = limit["parameters"]["corner_hz"].as_f64().unwrap();
        assert!(
            limit["parameters"]["causal"] == true && (corner - 20.0).abs() < 1.0,
            "{block}: {limit}"
        );
    }
    let loaded = load(&run, &LoadOptions::default()).unwrap();
    let rejected = DiagnoseOptions {
        rejected: vec![
            (Block::Gyro, Effect::ReferenceBandLimit),
            (Block::Accel, Effect::ReferenceBandLimit),
        ],
        ..DiagnoseOptions::default()
    };
    let report = diagnose_run(&loaded, &Settings::default(), &rejected).unwrap();
    let said = report.unexplained();
    for block in ["gyro", "accel"] {
        let after = report.blocks[block].chi2_per_dof[1];
        assert!(after > 2.0, "{block}: {after}");
        let mine: Vec<&String> = said
            .iter()
            .filter(|l| l.starts_with(&format!("{block}: with its ")))
            .collect();
        assert_eq!(mine.len(), 1, "{said:?}");
        assert!(
            mine[0].contains(&format!("still leaves chi2/dof {after:.2}")),
            "{}",
            mine[0]
        );
        assert!(mine[0].contains("sizes not certifiable"), "{}", mine[0]);
    }
    let lagged = simulated_run(dir.path(), "lagged", Some("sensor_lag:accel"));
    let err = discrepancy(&lagged, &out);
    assert!(!err.contains("leaves chi2/dof"), "{err}");
}
