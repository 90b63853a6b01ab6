//! The command line (contract section 3).
//!
//! Exit status: 0 done; 2 bad input or bad arguments (one clear line on stderr); 1 internal error.

mod args;
mod batch;
mod bench;
mod compare;
mod discrepancy;
mod identify;
mod inspect;
mod progress;
mod report;
mod simulate;

use std::process::ExitCode;

pub use args::Args;

/// A command's failure, classified by exit status.
#[derive(Debug)]
pub enum CliError {
    /// Bad arguments or bad input: exit status 2.
    Input(String),
    /// A failure of the program itself: exit status 1.
    Internal(anyhow::Error),
}

impl CliError {
    fn exit_code(&self) -> ExitCode {
        match self {
            CliError::Input(_) => ExitCode::from(2),
            CliError::Internal(_) => ExitCode::from(1),
        }
    }
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CliError::Input(m) => f.write_str(m),
            CliError::Internal(e) => write!(f, "internal error: {e:#}"),
        }
    }
}

/// Usage text.
pub const USAGE: &str = "\
usage:
  imu-attest [gui] [RUN...]                       open the GUI (with these runs loaded)
  imu-attest simulate --regime NAME [--duration S] [--rate HZ] [--seed N]
                      [--effect ID[:block][@scale]]... [--blocks gyro,accel]
                      [--stand real] [--angle-latency S] [--angle-band-hz HZ] [--angle-rate-hz HZ]
                      [--angle-filter-hz HZ] [--coloured-angle-noise RAD] [--coloured-angle-corner-hz HZ]
                      [--sensor-noise default|white] [--random-walk K] [--sensor-filter-hz HZ]
                      [--tone-hz F] [--tone-gate from:T|pulsed:ON,OFF]
                      [--sine roll|yaw|pitch:HZ:DEG]...
                      [--fault glitch|hold|clip|wrap|slip[:CHANNEL]]... --out RUN.csv
  imu-attest identify RUN [--settings S.json] [--effects E.json] --out MODEL.json
                                                  E.json: accepted effects ({\"effects\": [{block,
                                                  effect}]}, or a discrepancy report's findings)
  imu-attest discrepancy RUN [--settings S.json] [--model MODEL.json] --out REPORT.json
  imu-attest compare RUN RUN... [--settings S.json] [--diagnose] --out COMPARISON.json
                                                  --diagnose: each run's findings too, compared
                                                  pair by pair (sizes within their deviations?)
  imu-attest report RUN... [--settings S.json] [--model MODEL.json] [--spec SPEC.json]
                      --out REPORT.html           the certificate: model, noise terms (Allan),
                                                  diagnosis, pass/fail against SPEC
  imu-attest batch DIR|RUN... [--settings S.json] [--diagnose] --out TABLE.csv|.json
                                                  a campaign: every run identified (two at a
                                                  time), one row per run and block
  imu-attest inspect RUN...                       check runs against the format, summarise them
  imu-attest bench [RUN] [--minutes M] [--rate HZ] [--segment L] [--batch-runs N] [--json]
                                                  time the identifier's stages (default: a
                                                  simulated 30-minute run at 1 kHz)
";

/// Entry point of the binary: runs the command named by the process arguments.
#[must_use]
pub fn main() -> ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let outcome = run(&argv);
    // `bench` runs whole commands in child processes and reads their peak memory here.
    if std::env::var_os("IMU_ATTEST_PEAK_RSS").is_some()
        && let Some(bytes) = crate::bench::memory::peak_rss_bytes()
    {
        eprintln!("imu-attest: peak_rss_mb={:.1}", bytes as f64 / 1e6);
    }
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("imu-attest: {e}");
            e.exit_code()
        }
    }
}

/// Runs one command line (without the program name).
///
/// # Errors
/// [`CliError::Input`] for bad arguments or input, [`CliError::Internal`] otherwise.
pub fn run(argv: &[String]) -> Result<(), CliError> {
    let (command, rest) = match argv.split_first() {
        Some((c, rest)) if !c.starts_with('-') => (c.as_str(), rest),
        Some((c, _)) if c == "-h" || c == "--help" => (c.as_str(), &argv[1..]),
        _ => ("gui", argv),
    };
    let known = command == "gui" || USAGE.contains(&format!("  imu-attest {command} "));
    if known && rest.iter().any(|a| a == "--help" || a == "-h") {
        // `imu-attest identify --help`: that command's lines of the usage, not "needs a value".
        eprint!("{}", usage_of(command));
        return Ok(());
    }
    match command {
        "simulate" => simulate::run(&Args::parse(rest)?),
        "inspect" => inspect::run(&Args::parse(rest)?),
        "identify" => identify::run(&Args::parse(rest)?),
        "discrepancy" => discrepancy::run(&Args::parse(rest)?),
        "compare" => compare::run(&Args::parse_with_flags(rest, &["diagnose"])?),
        "report" => report::run(&Args::parse(rest)?),
        "batch" => batch::run(&Args::parse_with_flags(rest, &["diagnose"])?),
        "bench" => bench::run(rest),
        "gui" => gui(rest),
        "help" | "--help" | "-h" => {
            eprint!("{USAGE}");
            Ok(())
        }
        other if looks_like_run(other) => gui(argv),
        other => Err(CliError::Input(format!(
            "unknown command '{other}' (try 'imu-attest help')"
        ))),
    }
}

/// The lines of [`USAGE`] for `command` (its line and the continuation lines under it), or the
/// whole usage for a command it does not list.
fn usage_of(command: &str) -> String {
    let start = format!("  imu-attest {command} ");
    let start = if command == "gui" {
        "  imu-attest [gui] ".to_owned()
    } else {
        start
    };
    let mut lines = USAGE.lines().skip_while(|l| !l.starts_with(&start));
    let Some(first) = lines.next() else {
        return USAGE.to_owned();
    };
    let mut out = format!("usage:\n{first}\n");
    for line in lines.take_while(|l| !l.starts_with("  imu-attest ")) {
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// A bare argument naming a run file opens the GUI with it (`imu-attest cruise.csv`).
fn looks_like_run(arg: &str) -> bool {
    crate::batch::is_run_file(std::path::Path::new(arg))
}

/// `imu-attest [gui] [RUN...]`: opens the app with these runs, or the bundled sample run.
fn gui(paths: &[String]) -> Result<(), CliError> {
    if let Some(flag) = paths.iter().find(|p| p.starts_with('-')) {
        return Err(CliError::Input(format!("gui: unknown option '{flag}'")));
    }
    #[cfg(feature = "gui")]
    return crate::gui::run_app(paths.iter().map(std::path::PathBuf::from).collect())
        .map_err(|e| CliError::Internal(anyhow::Error::new(e)));
    #[cfg(not(feature = "gui"))]
    Err(CliError::Input(
        "this build has no app (built without the `gui` feature); use the commands".into(),
    ))
}
