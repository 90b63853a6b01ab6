//! Numerical edges and output faults through the real binary and the library (issue 7):
//! - a run with one stand axis held still is diagnosed by name, not identified;
//! - the simulated regimes are far from that diagnosis (the criterion's margin, measured);
//! - settings the identifier cannot use are refused with one clear line (exit status 2);
//! - an unwritable destination leaves no file and says so; a run is never written over its own
//!   sidecar; no NaN or infinity reaches a run file.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use imu_attest::block::Block;
use imu_attest::ident::IdentError;
use imu_attest::ident::band::AUTO_LIMITS_HZ;
use imu_attest::ident::excitation::{MIN_EXCITATION, excitation};
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::signals::block_signals;
use imu_attest::ident::spectra::block_spectra;
use imu_attest::rng::Rng;
use imu_attest::run::{LoadOptions, Run, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, SimulatedRun, simulate};
use imu_attest::spectral::WelchPlanner;
use imu_attest::stand::observer::{ObserverSettings, observe};

fn imu_attest(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .args(args)
        .output()
        .unwrap()
}

/// The stderr of a run that must fail with exit status 2 and one line.
fn one_line_failure(o: &Output, context: &str) -> String {
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{context}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{context}: {stderr}");
    stderr
}

fn simulated(regime: Regime, seed: u64) -> SimulatedRun {
    let mut config = SimConfig::new(regime);
    config.duration_s = 60.0;
    config.seed = seed;
    simulate(&config).unwrap()
}

/// Holds stand axis `axis` (0 roll, 1 yaw, 2 pitch) still: its angle becomes its mean plus the
/// angle sensor's noise, as a recording of an axis locked in place would show.
fn hold_still(sim: &mut SimulatedRun, axis: usize, seed: u64) {
    let angle = &mut sim.angles[axis];
    let mean = angle.iter().sum::<f64>() / angle.len() as f64;
    let sigma = sim.sidecar.angle_noise_rad;
    let mut rng = Rng::new(seed);
    for v in angle.iter_mut() {
        *v = mean + sigma * rng.normal();
    }
}

fn written(dir: &Path, name: &str, sim: &SimulatedRun) -> PathBuf {
    let path = dir.join(name);
    write_run(sim, &path).unwrap();
    path
}

/// The smallest over largest principal input power of each block, over the default band.
fn excitation_ratios(run: &Run) -> Vec<(Block, f64, &'static str)> {
    let settings = Settings::default();
    let observer = ObserverSettings {
        angle_noise_rad: run.sidecar.angle_noise_rad,
        ..ObserverSettings::default()
    };
    let motion = observe(
        run.angles.each_ref().map(Vec::as_slice),
        run.sample_rate_hz,
        &observer,
    )
    .unwrap();
    let mut planner = WelchPlanner::new();
    run.blocks()
        .into_iter()
        .map(|block| {
            let signals = block_signals(run, &motion.euler, block).unwrap();
            let spectra = block_spectra(&mut planner, &signals, run.sample_rate_hz, &settings.welch).unwrap();
            let e = excitation(&spectra, AUTO_LIMITS_HZ).unwrap();
            let (inputs, _) = imu_attest::ident::signals::channel_names(block);
            (block, e.ratio, inputs[e.weakest_axis])
        })
        .collect()
}

/// Every regime excites every input direction of both blocks well above the criterion (measured
/// 6e-3 at the lowest, the accelerometer in turbulent cruise; the criterion is 1e-3).
#[test]
fn simulated_regimes_are_far_above_the_excitation_criterion() {
    let dir = tempfile::tempdir().unwrap();
    for (k, regime) in Regime::ALL.into_iter().enumerate() {
        let path = written(
            dir.path(),
            &format!("r{k}.csv"),
            &simulated(regime, 11 + k as u64),
        );
        let run = load(&path, &LoadOptions::default()).unwrap();
        for (block, ratio, axis) in excitation_ratios(&run) {
            eprintln!("{regime} {block:?}: weakest/strongest input power {ratio:.2e} (axis {axis})");
            assert!(ratio > 4.0 * MIN_EXCITATION, "{regime} {block:?}: {ratio:.2e}");
        }
    }
}

/// Each stand axis held still in turn: the library names the input axis it leaves without power,
/// and `identify` exits with status 2 and one plain line instead of writing numbers.
#[test]
fn an_axis_held_still_is_diagnosed_instead_of_identified() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.json");
    for (axis, name) in [(0, "roll"), (1, "yaw"), (2, "pitch")] {
        let mut sim = simulated(Regime::Cruise, 21);
        hold_still(&mut sim, axis, 5);
        let path = written(dir.path(), &format!("still_{name}.csv"), &sim);
        let run = load(&path, &LoadOptions::default()).unwrap();
        let ratios = excitation_ratios(&run);
        eprintln!("{name} held still: {ratios:?}");
        let err = identify_run(&run, &Settings::default()).unwrap_err();
        let IdentError::NotExcited {
            block,
            axis: input_axis,
            low_hz,
            high_hz,
            relative_power,
            others,
        } = &err
        else {
            panic!("{name} held still: {err}")
        };
        assert_eq!(*block, "gyro", "the gyro block comes first: {err}");
        assert!(
            !*others,
            "a still stand axis takes the accelerometer's inputs too: leaving the gyro out would not help: {err}"
        );
        // The gyro's input for a still stand axis is the body rate along that platform axis.
        assert_eq!(*input_axis, ["wx", "wy", "wz"][axis], "{err}");
        assert_eq!(
            [low_hz.to_bits(), high_hz.to_bits()],
            AUTO_LIMITS_HZ.map(f64::to_bits)
        );
        // Measured 3e-5 to 5e-5: well below the criterion.
        assert!(*relative_power < MIN_EXCITATION / 10.0, "{relative_power:.2e}");

        let o = imu_attest(&["identify", path.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let stderr = one_line_failure(&o, name);
        let expected = format!("axis {input_axis} not excited between 0.1 and 40 Hz");
        assert!(stderr.contains(&expected), "{stderr}");
        assert!(stderr.contains(&format!("still_{name}.csv")), "{stderr}");
        assert!(!out.exists(), "no model written");
    }
}

/// Settings the identifier cannot use, each refused in one line naming what is wrong.
#[test]
fn unusable_settings_are_refused_through_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let run = written(dir.path(), "cruise.csv", &simulated(Regime::Cruise, 4));
    let out = dir.path().join("m.json");
    // 60 s at 500 Hz: 30000 samples, Nyquist 250 Hz.
    let cases = [
        (
            r#"{"band_hz": [0, 40]}"#,
            "band_hz [0, 40] is not inside (0, 250] Hz",
        ),
        (r#"{"band_hz": [-1, 40]}"#, "band_hz [-1, 40]"),
        (r#"{"band_hz": [10, 10]}"#, "low < high"),
        (r#"{"band_hz": [40, 0.1]}"#, "low < high"),
        (r#"{"band_hz": [0.1, 251]}"#, "(0, 250] Hz"),
        (r#"{"band_hz": [0.1, 1e999]}"#, "band_hz"),
        (
            r#"{"weight_A": [[1,0,0],[0,1,0],[0,0.5,1]]}"#,
            "weight_A is not symmetric positive definite: not symmetric",
        ),
        (
            r#"{"weight_A": [[1,0,0],[0,1,0],[0,0,-1]]}"#,
            "weight_A is not symmetric positive definite: smallest eigenvalue",
        ),
        (
            r#"{"weight_A": [[1,0,0],[0,0,0],[0,0,1]]}"#,
            "not symmetric positive definite",
        ),
        (
            r#"{"weight_A": [[1,0,0],[0,4,0],[0,0,1]], "lambda": [0, 4, 0]}"#,
            "lambda [0.0, 4.0, 0.0] makes I - A^-1 Lambda singular",
        ),
        (
            r#"{"welch": {"segment_len": 30002}}"#,
            "too few samples for the chosen spectral segment: 30000 samples",
        ),
        (
            r#"{"welch": {"segment_len": 1000000}}"#,
            "too few samples for the chosen spectral segment",
        ),
    ];
    for (text, needle) in cases {
        let s = dir.path().join("s.json");
        std::fs::write(&s, text).unwrap();
        let o = imu_attest(&[
            "identify",
            run.to_str().unwrap(),
            "--settings",
            s.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = one_line_failure(&o, text);
        assert!(err.contains(needle), "{text}: expected '{needle}' in {err}");
        assert!(!out.exists(), "{text}: nothing written");
    }
}

/// An unwritable destination (its folder is a regular file, or does not exist): exit status 2,
/// one line that says nothing was written, and no file anywhere. Root ignores permissions, so
/// these are the unwritable folders a test run as root can make.
#[test]
fn unwritable_destinations_leave_nothing_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let run = written(dir.path(), "cruise.csv", &simulated(Regime::Cruise, 4));
    let plain = dir.path().join("plain");
    std::fs::write(&plain, b"a file, not a folder").unwrap();
    let before: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    for folder in [plain.clone(), dir.path().join("missing")] {
        let model = folder.join("m.json");
        let simulated_run = folder.join("s.csv");
        for args in [
            vec![
                "identify",
                run.to_str().unwrap(),
                "--out",
                model.to_str().unwrap(),
            ],
            vec![
                "simulate",
                "--regime",
                "cruise",
                "--duration",
                "2",
                "--out",
                simulated_run.to_str().unwrap(),
            ],
        ] {
            let o = imu_attest(&args);
            let err = one_line_failure(&o, &format!("{args:?}"));
            assert!(err.contains("cannot write"), "{args:?}: {err}");
            assert!(err.contains("nothing was written"), "{args:?}: {err}");
        }
    }
    assert_eq!(std::fs::read(&plain).unwrap(), b"a file, not a folder");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        before.len(),
        "no stray file"
    );
}

/// `simulate --out x.json` would write the run and then its sidecar over it: refused.
#[test]
fn simulate_never_writes_the_run_over_its_own_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.json");
    let o = imu_attest(&[
        "simulate",
        "--regime",
        "cruise",
        "--duration",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = one_line_failure(&o, "--out run.json");
    assert!(
        err.contains("the run and its sidecar would be the same file"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A simulated run with a non-finite sample is not written (nor is its sidecar).
#[test]
fn non_finite_samples_never_reach_a_run_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 2.0;
    let mut sim = simulate(&config).unwrap();
    sim.gyro.as_mut().unwrap()[1][17] = f64::NAN;
    let err = write_run(&sim, &dir.path().join("bad.csv")).unwrap_err();
    assert!(err.to_string().contains("column 'gy' row 17"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    sim.gyro.as_mut().unwrap()[1][17] = 0.0;
    sim.time_s[3] = f64::INFINITY;
    assert!(write_run(&sim, &dir.path().join("bad.csv")).is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
