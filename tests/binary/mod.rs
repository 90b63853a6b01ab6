//! Running the `imu-attest` binary from the command-line tests.

pub mod approach;

use std::process::{Command, Output};

/// Runs `imu-attest` with `args` and waits for it.
pub fn imu_attest(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .args(args)
        .output()
        .expect("the binary runs")
}
