//! Loads one run and reports how long it took, for measuring the loader:
//! `cargo build --release --example load_run && /usr/bin/time -v target/release/examples/load_run big.csv`
//! (`Maximum resident set size` is the peak memory).
//!
//! `load_run --generate big.csv 1800000` first writes a benchmark run: 1000 Hz, 10 columns, t with
//! 4 decimals from t = 1000 s, the nine channels N(0, 0.1) with 7 significant digits (about 122 bytes a row, 220 MB for 1.8 million rows).

use std::io::{BufWriter, Write as _};
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Instant;

use imu_attest::rng::Rng;
use imu_attest::run::{LoadOptions, load_with_progress};

/// Writes the benchmark run described in the module docs.
fn generate(path: &PathBuf, rows: usize) -> std::io::Result<()> {
    let mut out = BufWriter::with_capacity(1 << 20, std::fs::File::create(path)?);
    writeln!(out, "t,roll,yaw,pitch,gx,gy,gz,ax,ay,az")?;
    let mut rng = Rng::new(1);
    for i in 0..rows {
        write!(out, "{:.4}", 1000.0 + i as f64 / 1000.0)?;
        for _ in 0..9 {
            write!(out, ",{:.6e}", 0.1 * rng.normal())?;
        }
        writeln!(out)?;
    }
    out.flush()
}

fn main() -> std::process::ExitCode {
    let mut args = std::env::args().skip(1).peekable();
    let generating = args.next_if_eq("--generate").is_some();
    let Some(path) = args.next().map(PathBuf::from) else {
        eprintln!("usage: load_run [--generate] FILE [REPEATS | ROWS]");
        return std::process::ExitCode::from(2);
    };
    if generating {
        let rows = args.next().and_then(|r| r.parse().ok()).unwrap_or(1_800_000);
        if let Err(e) = generate(&path, rows) {
            eprintln!("{}: {e}", path.display());
            return std::process::ExitCode::from(1);
        }
        return std::process::ExitCode::SUCCESS;
    }
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
