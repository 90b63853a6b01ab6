//! Loads one run and reports how long it took and the peak memory, for measuring the loader:
//! `cargo run --release --example load_run -- big.csv [repeats]`.

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Instant;

use imu_attest::run::{LoadOptions, load_with_progress};

/// Peak resident memory of this process (`VmHWM`), bytes, where `/proc` has it.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

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
                let peak = peak_rss_bytes().map_or(f64::NAN, |b| b as f64);
                eprintln!(
                    "{}: {} rows x {columns} columns in {seconds:.3} s ({:.0} MB/s), {calls} progress calls, \
                     peak RSS {:.0} MB = {:.2} x decoded {:.0} MB, sha256 {}",
                    path.display(),
                    run.len(),
                    run.source.size_bytes as f64 / seconds / 1e6,
                    peak / 1e6,
                    peak / decoded,
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
