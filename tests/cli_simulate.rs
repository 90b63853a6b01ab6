//! `imu-attest simulate` through the real binary: contract-conformant files, determinism, and one
//! clear line with exit status 2 for every bad argument.
#![expect(
    clippy::unwrap_used,
    reason = "test helpers panic on the unexpected, like the tests"
)]

use std::io::Read;
use std::path::Path;

use crate::binary;
use binary::imu_attest;

fn read_csv(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut s = String::new();
        flate2::read::GzDecoder::new(&bytes[..])
            .read_to_string(&mut s)
            .unwrap();
        s
    } else {
        String::from_utf8(bytes).unwrap()
    }
}

#[test]
fn writes_a_contract_run_with_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cruise.csv");
    let o = imu_attest(&[
        "simulate",
        "--regime",
        "cruise",
        "--duration",
        "12",
        "--rate",
        "400",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = read_csv(&out);
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,roll,yaw,pitch,gx,gy,gz,ax,ay,az");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 12 * 400);
    assert!(
        rows.iter()
            .all(|r| r.len() == 10 && r.iter().all(|v| v.is_finite()))
    );
    for w in rows.windows(2) {
        assert!((w[1][0] - w[0][0] - 0.0025).abs() < 1.5e-6, "uniform sampling");
    }
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("cruise.json")).unwrap()).unwrap();
    assert_eq!(sidecar["format"], "stand-run/1");
    assert_eq!(sidecar["regime"], "cruise");
    assert_eq!(sidecar["accel_lever_arm_m"].as_array().unwrap().len(), 3);
    assert_eq!(sidecar["gyro_lever_arm_m"].as_array().unwrap().len(), 3);
    assert!(sidecar["g_mps2"].as_f64().unwrap() > 9.8);
    assert!(sidecar["angle_noise_rad"].as_f64().unwrap() > 0.0);
    for block in ["gyro", "accel"] {
        let b = &sidecar["truth"][block];
        assert_eq!(b["K"].as_array().unwrap().len(), 3, "{block}");
        assert!(b["tau_s"].as_f64().unwrap() > 0.0);
        assert!(b["noise"]["white_asd"].is_array());
    }
}

#[test]
fn same_seed_same_bytes_and_gzip_holds_the_same_text() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_owned();
    let args = |out: String, seed: &str| {
        let o = imu_attest(&[
            "simulate",
            "--regime",
            "approach",
            "--duration",
            "8",
            "--seed",
            seed,
            "--effect",
            "vibration_tone:accel",
            "--out",
            &out,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    args(p("a.csv"), "5");
    args(p("b.csv"), "5");
    args(p("c.csv.gz"), "5");
    args(p("d.csv"), "6");
    let bytes = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
    assert_eq!(bytes("a.csv"), bytes("b.csv"));
    assert_eq!(bytes("a.json"), bytes("b.json"));
    assert_eq!(bytes("a.json"), bytes("c.json"));
    assert_eq!(
        read_csv(&dir.path().join("c.csv.gz")),
        String::from_utf8(bytes("a.csv")).unwrap()
    );
    assert_ne!(bytes("a.csv"), bytes("d.csv"));
}

#[test]
fn every_regime_and_every_effect_simulates() {
    let dir = tempfile::tempdir().unwrap();
    for regime in ["cruise", "turbulent_cruise", "approach"] {
        for effect in [
            "g_sensitivity",
            "sensor_lag",
            "axis_time_skew",
            "scale_nonlinearity",
            "vibration_tone",
            "lever_arm_error",
            "platform_resonance",
        ] {
            let out = dir.path().join(format!("{regime}-{effect}.csv"));
            let o = imu_attest(&[
                "simulate",
                "--regime",
                regime,
                "--duration",
                "4",
                "--effect",
                effect,
                "--out",
                out.to_str().unwrap(),
            ]);
            assert!(
                o.status.success(),
                "{regime} {effect}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let sidecar: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.with_extension("json")).unwrap()).unwrap();
            let listed: Vec<&str> = ["gyro", "accel"]
                .iter()
                .flat_map(|b| {
                    sidecar["truth"][b]["effects"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|e| e["effect"].as_str().unwrap())
                })
                .collect();
            assert!(listed.contains(&effect), "{regime} {effect}: {listed:?}");
            // The loader (contract section 2) accepts it.
            let run = imu_attest::run::load(&out, &imu_attest::run::LoadOptions::default()).unwrap();
            assert_eq!(run.len(), 2000);
            assert!((run.sample_rate_hz - 500.0).abs() < 1e-6);
            assert_eq!(run.blocks().len(), 2);
            assert_eq!(run.sidecar.regime, regime);
            assert!(run.sidecar.found);
        }
    }
}

#[test]
fn bad_arguments_exit_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.csv");
    let out = out.to_str().unwrap();
    let missing_dir = dir.path().join("nope").join("x.csv");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["simulate", "--regime", "storm", "--out", out],
            "unknown regime 'storm'",
        ),
        (vec!["simulate", "--out", out], "missing --regime"),
        (vec!["simulate", "--regime", "cruise"], "missing --out"),
        (
            vec!["simulate", "--regime", "cruise", "--duration", "-3", "--out", out],
            "duration",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--duration",
                "abc",
                "--out",
                out,
            ],
            "--duration abc",
        ),
        (
            vec!["simulate", "--regime", "cruise", "--rate", "50", "--out", out],
            "too low",
        ),
        (
            vec![
                "simulate", "--regime", "cruise", "--effect", "wobble", "--out", out,
            ],
            "unknown effect 'wobble'",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--effect",
                "g_sensitivity:accel",
                "--out",
                out,
            ],
            "does not apply",
        ),
        (
            vec!["simulate", "--regime", "cruise", "--sed", "1", "--out", out],
            "unknown option --sed",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--angle-rate-hz",
                "0",
                "--out",
                out,
            ],
            "--angle-rate-hz: '0'",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--angle-rate-hz",
                "NaN",
                "--out",
                out,
            ],
            "--angle-rate-hz: 'NaN'",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--angle-rate-hz",
                "500",
                "--out",
                out,
            ],
            "between 0 and the run's rate (500 Hz)",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--angle-filter-hz",
                "-20",
                "--out",
                out,
            ],
            "--angle-filter-hz: '-20' is not a positive number of Hz",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--angle-band-hz",
                "inf",
                "--out",
                out,
            ],
            "--angle-band-hz: 'inf' is not a positive number of Hz",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--sensor-filter-hz",
                "0",
                "--out",
                out,
            ],
            "--sensor-filter-hz: '0' is not a positive number of Hz",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--out",
                missing_dir.to_str().unwrap(),
            ],
            "cannot write",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--sine",
                "heave:2:1",
                "--out",
                out,
            ],
            "--sine heave:2:1: unknown axis 'heave'",
        ),
        (
            vec!["simulate", "--regime", "cruise", "--sine", "roll:2", "--out", out],
            "is not AXIS:HZ:DEG",
        ),
        (
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--sine",
                "roll:300:1",
                "--out",
                out,
            ],
            "not below the Nyquist frequency 250 Hz",
        ),
        (vec!["frobnicate"], "unknown command"),
    ];
    for (args, needle) in cases {
        let o = imu_attest(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: one line, got {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    assert!(!Path::new(out).exists());
}
