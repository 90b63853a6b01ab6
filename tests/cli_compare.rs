//! `imu-attest compare` through the binary: the comparison file (schema, runs, pairwise
//! differences with a significance flag), agreement with `identify`, and exit status 2 with one
//! line and no output for bad input.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::{Path, PathBuf};

use imu_attest::block::Block;
use imu_attest::compare::findings::Presence;
use imu_attest::compare::{COMPARISON_SCHEMA, Comparison};
use imu_attest::diagnose::Verdict;
use imu_attest::effect::Effect;
use imu_attest::model::Model;

use crate::binary;
use crate::binary::approach;
use binary::imu_attest;

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample_runs")
        .join(name)
}

/// `dir/broken.csv`, with a cell that is not a number on its third line.
fn broken_run(dir: &Path) -> PathBuf {
    let bad = dir.join("broken.csv");
    std::fs::write(
        &bad,
        "t,roll,yaw,pitch,gx,gy,gz\n0,0,0,0,0,0,0\n0.002,0,abc,0,0,0,0\n",
    )
    .unwrap();
    bad
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
    assert!(value.get("findings").is_none(), "findings only with --diagnose");
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

/// `--diagnose`: each run's verdict and the findings compared. Two units with a hidden gyro
/// lag, the second twice as slow: the lag is named on both and its size differs.
#[test]
fn with_diagnose_the_findings_are_compared() {
    let dir = tempfile::tempdir().unwrap();
    let mut runs = Vec::new();
    for (name, seed, effect) in [
        ("a.csv", "5", "sensor_lag:gyro"),
        ("b.csv", "6", "sensor_lag:gyro@2"),
    ] {
        let path = dir.path().join(name);
        approach::approach_run(&path, seed, Some(effect));
        runs.push(path);
    }
    let out = dir.path().join("comparison.json");
    let o = imu_attest(&[
        "compare",
        runs[0].to_str().unwrap(),
        runs[1].to_str().unwrap(),
        "--diagnose",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c: Comparison = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let verdicts: Vec<_> = c.runs.iter().map(|r| r.verdict).collect();
    assert_eq!(verdicts, [Some(Verdict::EffectFound); 2]);
    let findings = c.findings.expect("findings compared");
    let lag = findings
        .iter()
        .find(|d| d.block == Block::Gyro && d.effect == Effect::SensorLag)
        .expect("the gyro lag compared");
    assert_eq!(lag.runs, [0, 1]);
    assert_eq!(lag.presence, Presence::Both);
    let t = &lag.sizes[0];
    assert_eq!(t.name, "T_s");
    assert!(
        t.b > 1.5 * t.a,
        "the second lag is twice the first: {} vs {}",
        t.a,
        t.b
    );
    assert!((t.delta.diff - (t.b - t.a)).abs() < 1e-15);
    assert_eq!(t.delta.significant, Some(true), "{}", lag.words);
    assert_eq!(lag.consistent, Some(false));
    assert!(
        lag.words.contains("T_s") && lag.words.contains("differs"),
        "{}",
        lag.words
    );
}

#[test]
fn a_bad_run_or_a_single_run_exits_2_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let bad = broken_run(dir.path());
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

/// The three real recordings are one IMU (`tests/data/real/README.md`): its delay is one figure,
/// and broad11 and broad25 share the axis rotation, so their `K` differ only by how the unit sat
/// against the reference. The comparison must not call the short, slow run's delay different
/// (its deviation from stretches on a shorter segment), and must split the `K` difference of the
/// pair with one axis rotation into the mount's rotation and the unit's own figures.
#[test]
fn the_real_unit_s_runs_agree_on_the_delay_and_a_rotation_of_its_axes_is_told_apart() {
    let dir = tempfile::tempdir().unwrap();
    let real = |name: &str| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/real")
            .join(name)
    };
    let runs = [
        real("broad07_fast_rotation.csv.gz"),
        real("broad11_slow_translation.csv.gz"),
        real("broad25_tapping.csv.gz"),
    ];
    let out = dir.path().join("comparison.json");
    let mut args = vec!["compare"];
    args.extend(runs.iter().map(|r| r.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap()]);
    let o = imu_attest(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stderr = String::from_utf8_lossy(&o.stderr);
    let c: Comparison = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    for d in &c.differences {
        assert_ne!(
            d.tau_s.significant,
            Some(true),
            "runs {:?}: {:?}",
            d.runs,
            d.tau_s
        );
    }
    let pair = c
        .differences
        .iter()
        .find(|d| d.runs == [1, 2])
        .expect("broad11 / broad25");
    let split = pair.mount.as_ref().expect("K near the identity: split");
    // The rotation is half the antisymmetric part of K_b K_a^-1 - I (mrad), from the runs' K.
    let k = |run: usize| nalgebra::Matrix3::from_fn(|i, j| c.runs[run].blocks["gyro"].k[i][j]);
    let m = k(2) * k(1).try_inverse().unwrap();
    let theta = [(2, 1), (0, 2), (1, 0)].map(|(i, j)| 500.0 * (m[(i, j)] - m[(j, i)]));
    for (got, want) in split.rotation_mrad.iter().zip(theta) {
        assert!((got.diff - want).abs() < 1e-9, "{} vs {want}", got.diff);
    }
    assert!(split.rotation_significant, "{:?}", split.rotation_mrad);
    assert!(
        split.rotation_mrad[0].diff.abs() > 3.0,
        "{:?}",
        split.rotation_mrad
    );
    assert!(
        stderr.contains("broad25_tapping.csv.gz - broad11_slow_translation.csv.gz: the axes are rotated by"),
        "{stderr}"
    );
    // Printed together, each identification warning names its run (broad07's gain rise).
    assert!(
        stderr.contains("imu-attest: warning: broad07_fast_rotation.csv.gz: gyro block: the gain rises by"),
        "{stderr}"
    );
    assert!(!stderr.contains("imu-attest: warning: gyro block"), "{stderr}");
}

/// A first run identified with notices (no sidecar) and warnings, then a bad second run: exit
/// status 2 with the bad run's one line; the first run's notices are printed only when the
/// comparison is written.
#[test]
fn a_later_run_s_refusal_stays_one_line_after_an_earlier_run_s_notices() {
    let dir = tempfile::tempdir().unwrap();
    let no_sidecar = dir.path().join("no_sidecar.csv.gz");
    std::fs::copy(sample("cruise.csv.gz"), &no_sidecar).unwrap();
    let bad = broken_run(dir.path());
    let settings = dir.path().join("gyro.json");
    std::fs::write(&settings, r#"{"blocks": ["gyro"], "order": 0}"#).unwrap();
    let out = dir.path().join("comparison.json");
    let compare = |runs: [&Path; 2]| {
        imu_attest(&[
            "compare",
            runs[0].to_str().unwrap(),
            runs[1].to_str().unwrap(),
            "--settings",
            settings.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = compare([&no_sidecar, &bad]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("broken.csv"), "{stderr}");
    assert!(!out.exists());
    // Both runs good: the comparison is written and the notices printed.
    let o = compare([&no_sidecar, &sample("cruise.csv.gz")]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("imu-attest: note: no_sidecar.csv.gz: no sidecar no_sidecar.json"),
        "{stderr}"
    );
    assert!(out.exists());
}
