//! `imu-attest bench [RUN] [--minutes M] [--rate HZ] [--segment L] [--json]` (issue 6): times the
//! identifier's stages on RUN, or on a simulated run of M minutes at HZ (default 30 min at 1 kHz)
//! written to a temporary CSV. Prints a table, or with `--json` one JSON object on one line.

use std::io::Write as _;
use std::path::Path;

use super::{Args, CliError};
use crate::bench::input::TempRun;
use crate::bench::{BenchError, run_bench};
use crate::ident::IdentError;
use crate::ident::settings::Settings;

/// Default simulated duration, minutes.
const DEFAULT_MINUTES: f64 = 30.0;
/// Default simulated sample rate, Hz.
const DEFAULT_RATE_HZ: f64 = 1000.0;

pub(super) fn run(argv: &[String]) -> Result<(), CliError> {
    let json = argv.iter().any(|a| a == "--json");
    let rest: Vec<String> = argv.iter().filter(|a| *a != "--json").cloned().collect();
    let args = Args::parse(&rest)?;
    let minutes: Option<f64> = args
        .get("minutes")
        .map(|_| args.parsed_or("minutes", 0.0))
        .transpose()?;
    let rate: Option<f64> = args
        .get("rate")
        .map(|_| args.parsed_or("rate", 0.0))
        .transpose()?;
    let mut settings = Settings::default();
    settings.welch.segment_len = args.parsed_or("segment", settings.welch.segment_len)?;
    args.reject_unknown()?;
    let temp;
    let path = match args.positional.as_slice() {
        [] => {
            temp = simulate(
                minutes.unwrap_or(DEFAULT_MINUTES),
                rate.unwrap_or(DEFAULT_RATE_HZ),
            )?;
            temp.path().to_owned()
        }
        [run] if minutes.is_none() && rate.is_none() => Path::new(run).to_owned(),
        [_] => {
            return Err(CliError::Input(
                "bench: --minutes and --rate size the simulated run; they cannot be given with RUN".into(),
            ));
        }
        more => {
            return Err(CliError::Input(format!(
                "bench takes at most one RUN, got {}",
                more.len()
            )));
        }
    };
    let bar = super::progress::bar(0, "bench {wide_bar} {pos}/{len} {msg} {elapsed}");
    let report = run_bench(&path, settings, &mut |name, count| {
        bar.set_length(count as u64);
        bar.set_message(name);
        if name != "load" {
            bar.inc(1);
        }
    });
    bar.finish_and_clear();
    let report = report.map_err(|e| classify(&path, e))?;
    let text = if json {
        report.to_json() + "\n"
    } else {
        report.to_table()
    };
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .map_err(|e| CliError::Internal(e.into()))
}

/// Simulates the benchmark run, with a spinner and a bar of rows written.
fn simulate(minutes: f64, rate_hz: f64) -> Result<TempRun, CliError> {
    let spinner = super::progress::spinner("simulating the benchmark run");
    let bar = super::progress::bar(0, "writing {wide_bar} {pos}/{len} rows {eta}");
    let temp = TempRun::simulate(minutes, rate_hz, &mut |done, total| {
        spinner.finish_and_clear();
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    spinner.finish_and_clear();
    bar.finish_and_clear();
    temp.map_err(|e| match e {
        BenchError::Simulate(_) => CliError::Input(format!("bench: {e}")),
        other => CliError::Internal(other.into()),
    })
}

/// Bad input (the run, the settings for it, the size asked) exits 2; anything else is ours.
fn classify(path: &Path, e: BenchError) -> CliError {
    match e {
        BenchError::Load(_) | BenchError::Simulate(_) => CliError::Input(e.to_string()),
        BenchError::Ident(
            IdentError::Settings(_) | IdentError::MissingBlock(_) | IdentError::EmptyBand { .. },
        ) => CliError::Input(format!("{}: {e}", path.display())),
        other => CliError::Internal(anyhow::anyhow!("{}: {other}", path.display())),
    }
}
