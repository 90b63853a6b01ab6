//! `imu-attest bench` through the real binary on a tiny simulated run: one line of valid JSON
//! with every key, finite positive times; bad arguments exit 2 with one line. No timed assertion.
use std::process::{Command, Output};

fn imu_attest(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .args(args)
        .output()
        .expect("binary runs")
}

#[test]
fn tiny_run_gives_one_json_line_with_every_key() {
    let out = imu_attest(&["bench", "--minutes", "0.25", "--rate", "200", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["samples"], 3000, "{v}");
    assert_eq!(v["rate_hz"].as_f64().map(f64::round), Some(200.0), "{v}");
    // Gyro [w; g] and accelerometer [f; a]: twelve distinct channels.
    assert_eq!(v["channels"], 12, "{v}");
    assert!(
        v["segment_len"]
            .as_u64()
            .is_some_and(|l| l >= 64 && l * 4 <= 3000),
        "{v}"
    );
    let stages = v["stages_s"].as_object().unwrap();
    for name in [
        "load",
        "observer",
        "spectra",
        "factorisation",
        "identify",
        "structural_fit",
        "retune",
        "retune_order",
        "retune_cold",
        "retune_order0",
        "rewelch",
        "diagnose",
        "noise",
        "suspect",
        "open_to_model",
    ] {
        let t = stages.get(name).and_then(serde_json::Value::as_f64);
        assert!(
            t.is_some_and(|t| t.is_finite() && t > 0.0),
            "stage {name}: {t:?} in {v}"
        );
    }
    for key in ["peak_rss_mb", "load_peak_rss_mb"] {
        if cfg!(target_os = "linux") {
            let mb = v[key].as_f64();
            assert!(mb.is_some_and(|m| m.is_finite() && m > 0.0), "{key}: {mb:?}");
        }
    }
    // Whole commands in child processes: wall time and their own peak memory.
    for command in ["identify", "discrepancy"] {
        let c = &v["commands"][command];
        assert!(c["wall_s"].as_f64().is_some_and(|t| t > 0.0), "{command}: {v}");
        if cfg!(target_os = "linux") {
            assert!(
                c["peak_rss_mb"].as_f64().is_some_and(|m| m > 1.0),
                "{command}: {v}"
            );
        }
    }
}

#[test]
fn the_table_names_every_stage() {
    let out = imu_attest(&["bench", "--minutes", "0.25", "--rate", "200", "--segment", "256"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let table = String::from_utf8(out.stdout).unwrap();
    for name in [
        "load",
        "spectra",
        "retune",
        "diagnose",
        "3000 samples",
        "segment 256",
    ] {
        assert!(table.contains(name), "{name} missing from\n{table}");
    }
}

#[test]
fn bad_arguments_exit_2_with_one_line() {
    for args in [
        &["bench", "run.csv", "--minutes", "1"][..],
        &["bench", "--minutes", "x"],
        &["bench", "--speed", "3"],
        &["bench", "a.csv", "b.csv"],
        &["bench", "--minutes", "0.001", "--rate", "200"],
        &["bench", "/nonexistent/run.csv"],
    ] {
        let out = imu_attest(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    }
}

#[test]
fn a_campaign_is_timed_on_request() {
    let out = imu_attest(&[
        "bench",
        "--minutes",
        "0.25",
        "--rate",
        "200",
        "--batch-runs",
        "2",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let batch = &v["commands"]["batch"];
    assert!(batch["wall_s"].as_f64().is_some_and(|t| t > 0.0), "{v}");
    if cfg!(target_os = "linux") {
        assert!(batch["peak_rss_mb"].as_f64().is_some_and(|m| m > 1.0), "{v}");
    }
}
