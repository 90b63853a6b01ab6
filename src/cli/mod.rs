//! The command line (contract section 3). Exit status: 0 done, 2 bad input or arguments, 1 internal.

use std::process::ExitCode;

/// Entry point of the binary.
#[must_use]
pub fn main() -> ExitCode {
    eprintln!("imu-attest: no command yet");
    ExitCode::from(2)
}
