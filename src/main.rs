//! The `imu-attest` binary: a thin shell over [`imu_attest::cli`].

fn main() -> std::process::ExitCode {
    imu_attest::cli::main()
}
