//! A block's output channel that never moves (a dead or disconnected sensor axis): the block is
//! refused with the channel named, the run's other blocks are identified as if the block were not
//! there (a flat gyro is no witness of the angle noise), a run with nothing else exits 2 on the
//! command line, and `inspect` says it first. Before, such a run failed deep in the fit with exit
//! status 1, "internal error: ... row weight of output 2 at bin 0 is not finite".

use crate::common::sim as sim_common;

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_session};
use imu_attest::ident::IdentError;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::Model;
use imu_attest::model::refused::RefusalKind;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;

/// A 60 s cruise run of `seed` with its gyro's `gz` written as zeros throughout but for one spike
/// (a channel "all equal but one" passed the first version of the check).
fn with_dead_gz(seed: u64) -> Run {
    let (_, mut run) = sim_common::simulated_run_of(60.0, Regime::Cruise, seed, &[]);
    let gz = &mut run.gyro.as_mut().expect("a gyro")[2];
    gz.fill(0.0);
    gz[12_345] = 0.5;
    run
}

#[test]
fn a_flat_gyro_channel_refuses_the_gyro_and_leaves_the_accelerometer_as_without_a_gyro() {
    let run = with_dead_gz(7);
    let id = identify_run(&run, &Settings::default()).expect("the accelerometer is identified");
    assert_eq!(
        id.blocks.iter().map(|b| b.block).collect::<Vec<_>>(),
        [Block::Accel]
    );
    let [refusal] = id.refused.as_slice() else {
        panic!("{:?}", id.refused)
    };
    assert_eq!(refusal.block, Block::Gyro);
    let IdentError::DeadOutput { channels, .. } = &refusal.error else {
        panic!("{}", refusal.error)
    };
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0].0, "gz");

    // The accelerometer's model is the one of the same run without a gyro: the flat gyro is not
    // the observer's witness (it would read the stand's yaw... pitch motion as angle noise).
    let mut without = run.clone();
    without.gyro = None;
    let alone = identify_run(
        &without,
        &Settings {
            blocks: vec![Block::Accel],
            ..Settings::default()
        },
    )
    .expect("identified");
    let (a, b) = (&alone.blocks[0].structural, &id.blocks[0].structural);
    assert_eq!(
        (a.k, a.tau_s.to_bits(), a.order),
        (b.k, b.tau_s.to_bits(), b.order)
    );
    // With a working gyro the observer has its witness, and the accelerometer's model differs.
    let (_, whole) = sim_common::simulated_run_of(60.0, Regime::Cruise, 7, &[]);
    let witnessed = identify_run(&whole, &Settings::default()).expect("identified");
    let accel = witnessed
        .blocks
        .iter()
        .find(|x| x.block == Block::Accel)
        .expect("accel");
    assert_ne!(
        accel.structural.k, b.k,
        "the test must tell the witness from none"
    );

    let model = Model::from_identification(&run, &Settings::default().for_run(&run), &id);
    let entry = &model.refused_blocks["gyro"];
    assert_eq!(entry.kind, RefusalKind::DeadOutput);
    assert_eq!(entry.axis.as_deref(), Some("gz"));
    assert!(
        entry.reason.contains("gz (always 0) never moves"),
        "{}",
        entry.reason
    );

    let run = Arc::new(run);
    let settings = Settings::default().for_run(&run);
    let report = diagnose_session(&mut Session::new(run), &settings, &DiagnoseOptions::default())
        .expect("the accelerometer is diagnosed");
    assert_eq!(report.blocks.keys().collect::<Vec<_>>(), ["accel"]);
    assert_eq!(report.refused_blocks["gyro"].kind, RefusalKind::DeadOutput);
}

#[test]
fn a_run_whose_only_block_has_a_flat_channel_is_refused_as_the_user_s_input() {
    let (_, mut run) = sim_common::simulated_run_of(60.0, Regime::Cruise, 8, &[]);
    run.accel = None;
    run.gyro.as_mut().expect("a gyro")[1].fill(0.0123);
    let err = identify_run(&run, &Settings::default()).expect_err("nothing left to identify");
    let IdentError::DeadOutput { block, channels, .. } = &err else {
        panic!("{err}")
    };
    assert_eq!((*block, channels.len(), channels[0].0), ("gyro", 1, "gy"));
    assert!(err.is_input_error());
    let words = err.to_string();
    assert!(words.contains("output gy (always 0.0123) never moves"), "{words}");
    assert!(
        !words.contains("leave this block out"),
        "nothing would be left: {words}"
    );
}

fn binary(args: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .args(args)
        .output()
        .expect("the binary runs");
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// `path`'s CSV with the column `name` written as `value` in every row.
fn flatten_column(path: &Path, name: &str, value: &str) {
    let text = std::fs::read_to_string(path).expect("written");
    let mut lines = text.lines();
    let header = lines.next().expect("a header");
    let at = header.split(',').position(|c| c == name).expect("the column");
    let mut out = format!("{header}\n");
    for line in lines {
        let cells: Vec<&str> = line
            .split(',')
            .enumerate()
            .map(|(i, c)| if i == at { value } else { c })
            .collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    std::fs::write(path, out).expect("written");
}

#[test]
fn the_command_line_says_it_in_inspect_and_exits_2_in_identify() {
    let dir = tempfile::tempdir().expect("a directory");
    let run = dir.path().join("dead.csv");
    let run_s = run.to_str().expect("utf-8");
    let (code, err) = binary(&[
        "simulate",
        "--regime",
        "cruise",
        "--duration",
        "30",
        "--blocks",
        "gyro",
        "--out",
        run_s,
    ]);
    assert_eq!(code, Some(0), "{err}");
    flatten_column(&run, "gz", "0");

    let (code, err) = binary(&["inspect", run_s]);
    assert_eq!(code, Some(0), "inspect checks the format: {err}");
    assert!(
        err.contains("warning: gz never moves (always 0): a dead or disconnected channel"),
        "{err}"
    );

    let out = dir.path().join("m.json");
    let (code, err) = binary(&["identify", run_s, "--out", out.to_str().expect("utf-8")]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("dead.csv") && err.contains("output gz (always 0) never moves"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
}
