//! `imu-attest compare` through the binary: the comparison file (schema, runs, pairwise
//! differences with a significance flag), agreement with `identify`, and exit status 2 with one
//! line and no output for bad input.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::{Path, PathBuf};

use imu_attest::compare::{COMPARISON_SCHEMA, Comparison};
use imu_attest::model::Model;

mod binary;
use binary::imu_attest;

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample_runs")
        .join(name)
}

fn order0_settings(dir: &Path) -> PathBuf {
    let settings = dir.join("s.json");
    std::fs::write(&settings, r#"{"order": 0}"#).unwrap();
    settings
}

#[test]
fn compares_two_regimes_and_agrees_with_identify() {
    let dir = tempfile::tempdir().unwrap();
    let settings = order0_settings(dir.path());
    let (cruise, approach) = (sample("cruise.csv.gz"), sample("approach.csv.gz"));
    let out = dir.path().join("comparison.json");
    let o = imu_attest(&[
        "compare",
        cruise.to_str().unwrap(),
        approach.to_str().unwrap(),
        "--settings",
        settings.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["schema"], COMPARISON_SCHEMA);
    let c: Comparison = serde_json::from_value(value).unwrap();
    let regimes: Vec<&str> = c.runs.iter().map(|r| r.source.regime.as_str()).collect();
    assert_eq!(regimes, ["cruise", "approach"]);
    let blocks: Vec<&str> = c.differences.iter().map(|d| d.block.as_str()).collect();
    assert_eq!(blocks, ["accel", "gyro"]);
    for d in &c.differences {
        let (a, b) = (&c.runs[0].blocks[&d.block], &c.runs[1].blocks[&d.block]);
        for i in 0..3 {
            for j in 0..3 {
                let delta = d.k[i][j];
                assert!((delta.diff - (b.k[i][j] - a.k[i][j])).abs() < 1e-15);
                if let Some(std) = delta.std {
                    assert_eq!(delta.significant, Some(delta.diff.abs() > 3.0 * std));
                }
            }
        }
        let flagged =
            d.k.iter()
                .flatten()
                .chain([&d.tau_s])
                .any(|x| x.significant == Some(true));
        assert_eq!(d.significant, flagged);
    }

    // The first run's figures are what `identify` writes for it with the same settings.
    let model_path = dir.path().join("cruise_model.json");
    let o = imu_attest(&[
        "identify",
        cruise.to_str().unwrap(),
        "--settings",
        settings.to_str().unwrap(),
        "--out",
        model_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model: Model = serde_json::from_slice(&std::fs::read(&model_path).unwrap()).unwrap();
    for (name, block) in &model.blocks {
        assert_eq!(c.runs[0].blocks[name].k, block.k, "{name}");
        assert_eq!(
            c.runs[0].blocks[name].tau_s.to_bits(),
            block.tau_s.to_bits(),
            "{name}"
        );
    }
}

#[test]
fn a_bad_run_or_a_single_run_exits_2_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.csv");
    std::fs::write(
        &bad,
        "t,roll,yaw,pitch,gx,gy,gz\n0,0,0,0,0,0,0\n0.002,0,abc,0,0,0,0\n",
    )
    .unwrap();
    let out = dir.path().join("comparison.json");
    let cruise = sample("cruise.csv.gz");
    for args in [
        vec![cruise.to_str().unwrap(), bad.to_str().unwrap()],
        vec![cruise.to_str().unwrap()],
    ] {
        let mut argv = vec!["compare"];
        argv.extend(args);
        argv.extend(["--out", out.to_str().unwrap()]);
        let o = imu_attest(&argv);
        assert_eq!(o.status.code(), Some(2), "{argv:?}");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(!out.exists(), "no output for bad input");
    }
    let o = imu_attest(&[
        "compare",
        cruise.to_str().unwrap(),
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("broken.csv"));
}
