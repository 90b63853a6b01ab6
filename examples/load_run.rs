//! Loads one run and reports how long it took and the peak memory, for measuring the loader:
//! `cargo build --release --example load_run && /usr/bin/time -v target/release/examples/load_run big.csv`
//! (`Maximum resident set size` is the peak memory).

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Instant;

use imu_attest::run::{LoadOptions, load_with_progress};

fn main() -> std::process::ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next().map(PathBuf::from) else {
        eprintln!("usage: load_run FILE [REPEATS]");
        return std::process::ExitCode::from(2);
    };
    let repeats: usize = args.next().and_then(|r| r.parse().ok()).unwrap_or(1);
    for _ in 0..repeats {
        let mut calls = 0_usize;
        let start = Instant::now();
        let result = load_with_progress(&path, &LoadOptions::default(), &mut |_| {
            calls += 1;
            ControlFlow::Continue(())
        });
        let seconds = start.elapsed().as_secs_f64();
        match result {
            Ok(run) => {
                let columns = 4 + 3 * run.blocks().len() + run.extra.len();
                let decoded = (run.len() * columns * 8) as f64;
                eprintln!(
                    "{}: {} rows x {columns} columns in {seconds:.3} s ({:.0} MB/s), {calls} progress calls, \
                     decoded {:.0} MB, sha256 {}",
                    path.display(),
                    run.len(),
                    run.source.size_bytes as f64 / seconds / 1e6,
                    decoded / 1e6,
                    run.source.sha256
                );
            }
            Err(e) => {
                eprintln!("{e} (after {seconds:.3} s)");
                return std::process::ExitCode::from(2);
            }
        }
    }
    std::process::ExitCode::SUCCESS
}
