//! `imu-attest bench [RUN] [--minutes M] [--rate HZ] [--segment L] [--json]` (issue 6): times the
//! identifier's stages on RUN, or on a simulated run of M minutes at HZ (default 30 min at 1 kHz)
//! written to a temporary CSV. Prints a table, or with `--json` one JSON object on one line.
//!
//! Without `--segment` the segment is the identifier's own choice (4096, halved for a run too
//! short to hold 12 segments, `ident::settings::welch_for_record`); the report gives the segment
//! used. `--segment L` is kept as given.
//!
//! Whole commands are timed in child processes after the stages: `identify` and `discrepancy` on
//! the run, and with `--batch-runs N` a campaign: N runs of 300 s at 500 Hz simulated into a
//! temporary folder (three regimes, seeds 1..N; not timed) and `batch` over it.

use std::io::Write as _;
use std::path::Path;

use super::{Args, CliError};
use crate::bench::input::{BENCH_REGIME, TempRun};
use crate::bench::{BenchError, run_bench};
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
    let segment: Option<usize> = args
        .get("segment")
        .map(|_| args.parsed_or("segment", 0))
        .transpose()?;
    let batch_runs: usize = args.parsed_or("batch-runs", 0)?;
    args.reject_unknown()?;
    let mut settings = Settings::default();
    if let Some(segment_len) = segment {
        settings.welch.segment_len = segment_len;
        settings.welch.segment_auto = false;
    }
    let temp;
    let path = match args.positional.as_slice() {
        [] => {
            let (minutes, rate) = (
                minutes.unwrap_or(DEFAULT_MINUTES),
                rate.unwrap_or(DEFAULT_RATE_HZ),
            );
            temp = simulate(minutes, rate)?;
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
    let command_settings = settings.clone();
    let report = run_bench(&path, settings, &mut |name, count| {
        bar.set_length(count as u64);
        bar.set_message(name);
        if name != "load" {
            bar.inc(1);
        }
    });
    bar.finish_and_clear();
    let mut report = report.map_err(|e| classify(&path, e))?;
    for name in ["identify", "discrepancy"] {
        report.commands.push(time_command(
            name,
            std::slice::from_ref(&path),
            &command_settings,
        )?);
    }
    if batch_runs > 0 {
        report.commands.push(time_batch(batch_runs)?);
    }
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

/// Runs `imu-attest NAME RUN --settings S --out TEMP` in a child process with the bench's
/// settings: its wall time and the peak memory it reports at exit (`IMU_ATTEST_PEAK_RSS`).
fn time_command(
    name: &'static str,
    runs: &[std::path::PathBuf],
    settings: &Settings,
) -> Result<crate::bench::CommandFigure, CliError> {
    use std::process::{Command, Stdio};
    let exe = std::env::current_exe().map_err(|e| CliError::Internal(e.into()))?;
    let dir = std::env::temp_dir().join(format!("imu-attest-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| CliError::Internal(e.into()))?;
    let out = dir.join(format!("{name}.json"));
    let settings_path = dir.join("settings.json");
    let bytes = serde_json::to_vec(settings).map_err(|e| CliError::Internal(e.into()))?;
    std::fs::write(&settings_path, bytes).map_err(|e| CliError::Internal(e.into()))?;
    let start = std::time::Instant::now();
    let output = Command::new(exe)
        .arg(name)
        .args(runs)
        .arg("--settings")
        .arg(&settings_path)
        .arg("--out")
        .arg(&out)
        .env("IMU_ATTEST_PEAK_RSS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| CliError::Internal(e.into()))?;
    let wall_s = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(CliError::Internal(anyhow::anyhow!(
            "bench: {name}: {}",
            stderr.trim()
        )));
    }
    let peak_rss_mb = stderr
        .lines()
        .find_map(|l| l.strip_prefix("imu-attest: peak_rss_mb="))
        .and_then(|v| v.trim().parse().ok());
    Ok(crate::bench::CommandFigure {
        name,
        wall_s,
        peak_rss_mb,
    })
}

/// Simulates `n` runs of 300 s at 500 Hz (three regimes, seeds `1..=n`) into a temporary folder
/// and times `batch` over it.
fn time_batch(n: usize) -> Result<crate::bench::CommandFigure, CliError> {
    use std::process::{Command, Stdio};
    let exe = std::env::current_exe().map_err(|e| CliError::Internal(e.into()))?;
    let dir = std::env::temp_dir().join(format!("imu-attest-bench-batch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| CliError::Internal(e.into()))?;
    let regimes = ["cruise", "approach", "turbulent_cruise"];
    for seed in 1..=n {
        let path = dir.join(format!("run{seed:04}.csv"));
        let status = Command::new(&exe)
            .args([
                "simulate",
                "--regime",
                regimes[seed % 3],
                "--duration",
                "300",
                "--rate",
                "500",
            ])
            .args(["--seed", &seed.to_string(), "--out"])
            .arg(&path)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .map_err(|e| CliError::Internal(e.into()))?;
        if !status.success() {
            let _ = std::fs::remove_dir_all(&dir);
            return Err(CliError::Internal(anyhow::anyhow!(
                "bench: simulating campaign run {seed} failed"
            )));
        }
    }
    let figure = time_command("batch", std::slice::from_ref(&dir), &Settings::default());
    let _ = std::fs::remove_dir_all(&dir);
    figure
}

/// Simulates the benchmark run in a child process (`imu-attest simulate`), so that the
/// simulation's memory is not in this process's peak; its progress bars show on a terminal.
fn simulate(minutes: f64, rate_hz: f64) -> Result<TempRun, CliError> {
    use std::io::IsTerminal as _;
    use std::process::{Command, Stdio};
    let temp = TempRun::unwritten();
    let exe = std::env::current_exe().map_err(|e| CliError::Internal(e.into()))?;
    let interactive = std::io::stderr().is_terminal();
    let output = Command::new(exe)
        .args(["simulate", "--regime", BENCH_REGIME.name()])
        .args([
            "--duration",
            &(minutes * 60.0).to_string(),
            "--rate",
            &rate_hz.to_string(),
        ])
        .arg("--out")
        .arg(temp.path())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(if interactive {
            Stdio::inherit()
        } else {
            Stdio::piped()
        })
        .output()
        .map_err(|e| CliError::Internal(e.into()))?;
    match output.status.code() {
        Some(0) => Ok(temp),
        code => {
            let stderr = String::from_utf8_lossy(&output.stderr);
            let message = stderr.trim().trim_start_matches("imu-attest: ");
            let message = format!("bench: simulating the run: {message}");
            Err(if code == Some(2) {
                CliError::Input(message)
            } else {
                CliError::Internal(anyhow::anyhow!(message))
            })
        }
    }
}

/// Bad input (the run, the settings for it, the size asked) exits 2; anything else is ours.
fn classify(path: &Path, e: BenchError) -> CliError {
    match e {
        BenchError::Load(_) | BenchError::Simulate(_) => CliError::Input(e.to_string()),
        BenchError::Ident(ref i) if i.is_input_error() => CliError::Input(format!("{}: {e}", path.display())),
        other => CliError::Internal(anyhow::anyhow!("{}: {other}", path.display())),
    }
}
