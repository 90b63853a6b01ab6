//! Wrapped angle columns (issue 14): a simulated run written with its angles wrapped into
//! (-pi, pi] or [0, 2 pi) loads to the same angles as the unwrapped run and identifies to the same
//! model; the loader says which column wrapped and where.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, Run, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::{SimConfig, SimulatedRun, simulate};

/// Writes `angles` and the run's outputs with full precision (shortest round-trip form).
fn write_csv(dir: &Path, name: &str, sim: &SimulatedRun, angles: &[Vec<f64>; 3]) -> PathBuf {
    let gyro = sim.gyro.as_ref().expect("gyro simulated");
    let accel = sim.accel.as_ref().expect("accel simulated");
    let mut text = "t,roll,yaw,pitch,gx,gy,gz,ax,ay,az\n".to_owned();
    for (i, t) in sim.time_s.iter().enumerate() {
        write!(text, "{t}").expect("a String takes writes");
        for c in angles.iter().chain(gyro).chain(accel) {
            write!(text, ",{}", c[i]).expect("a String takes writes");
        }
        text.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, text).expect("written");
    // The sidecar too: the accelerometer's input depends on its declared lever arm.
    let sidecar = serde_json::to_string(&sim.sidecar).expect("serialisable");
    std::fs::write(path.with_extension("json"), sidecar).expect("written");
    path
}

fn wrap_pi(v: f64) -> f64 {
    let w = v.rem_euclid(TAU);
    if w > PI { w - TAU } else { w }
}

fn load_run(path: &Path) -> Run {
    load(path, &LoadOptions::default()).expect("the run loads")
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn a_wrapped_copy_loads_and_identifies_as_the_unwrapped_run() {
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 60.0;
    config.seed = 14;
    let sim = simulate(&config).expect("simulated");
    // Yaw near pi, so that it crosses +-pi all the time (a yaw offset changes no block input:
    // yaw turns about the vertical, the first rotation of the sequence).
    let mut angles = sim.angles.clone();
    let yaw = &mut angles[1];
    let mean = yaw.iter().sum::<f64>() / yaw.len() as f64;
    for v in yaw.iter_mut() {
        *v += PI - 0.005 - mean;
    }
    let dir = tempfile::tempdir().expect("a temporary directory");
    let plain = write_csv(dir.path(), "plain.csv", &sim, &angles);
    // (-pi, pi]: yaw wraps; [0, 2 pi): roll and pitch wrap at every zero crossing.
    let pi_convention = write_csv(
        dir.path(),
        "pi.csv",
        &sim,
        &angles.clone().map(|c| c.into_iter().map(wrap_pi).collect()),
    );
    let tau_convention = write_csv(
        dir.path(),
        "tau.csv",
        &sim,
        &angles
            .clone()
            .map(|c| c.into_iter().map(|v| v.rem_euclid(TAU)).collect()),
    );
    let reference = load_run(&plain);
    assert!(
        reference.notices.iter().all(|n| !n.contains("wraps")),
        "{:?}",
        reference.notices
    );
    let model = |run: &Run| {
        identify_run(run, &Settings::default())
            .expect("identified")
            .blocks
            .into_iter()
            .map(|b| (b.structural.k, b.structural.tau_s))
            .collect::<Vec<_>>()
    };
    let expected = model(&reference);
    for (path, wrapped) in [
        (pi_convention, &["yaw"][..]),
        (tau_convention, &["roll", "pitch"][..]),
    ] {
        let run = load_run(&path);
        for (axis, name) in ["roll", "yaw", "pitch"].iter().enumerate() {
            let d = max_diff(&run.angles[axis], &reference.angles[axis]);
            assert!(d < 1e-9, "{}: {name} differs by {d:e} rad", path.display());
            let notice = run
                .notices
                .iter()
                .find(|n| n.contains(&format!("column '{name}' wraps")));
            assert_eq!(
                notice.is_some(),
                wrapped.contains(name),
                "{name}: {:?}",
                run.notices
            );
        }
        for ((k, tau), (k0, tau0)) in model(&run).iter().zip(&expected) {
            for i in 0..3 {
                for j in 0..3 {
                    let rel = (k[i][j] - k0[i][j]).abs() / k0[i][i].abs();
                    assert!(
                        rel < 1e-6,
                        "{}: K[{i}][{j}] {} vs {}",
                        path.display(),
                        k[i][j],
                        k0[i][j]
                    );
                }
            }
            assert!(
                (tau - tau0).abs() / tau0.abs() < 1e-6,
                "{}: tau {tau} vs {tau0}",
                path.display()
            );
        }
    }
}

#[test]
fn the_notice_names_the_first_wrap_line() {
    let mut config = SimConfig::new(Regime::Approach);
    config.duration_s = 2.0;
    let sim = simulate(&config).expect("simulated");
    let mut angles = sim.angles.clone();
    // Roll in [0, 2 pi): the first wrap is the first sign change of the roll.
    angles[0] = angles[0].iter().map(|v| v.rem_euclid(TAU)).collect();
    let first = sim.angles[0]
        .windows(2)
        .position(|w| (w[0] < 0.0) != (w[1] < 0.0))
        .expect("the roll crosses zero")
        + 1;
    let count = sim.angles[0]
        .windows(2)
        .filter(|w| (w[0] < 0.0) != (w[1] < 0.0))
        .count();
    let dir = tempfile::tempdir().expect("a temporary directory");
    let run = load_run(&write_csv(dir.path(), "roll.csv", &sim, &angles));
    let expected = format!(
        "column 'roll' wraps around a full turn {count} time{} (the first at line {} of roll.csv): unwrapped",
        if count == 1 { "" } else { "s" },
        first + 2
    );
    assert!(
        run.notices.contains(&expected),
        "{expected} not in {:?}",
        run.notices
    );
    assert!(max_diff(&run.angles[0], &sim.angles[0]) < 1e-9);
}
