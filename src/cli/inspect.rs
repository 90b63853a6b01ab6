//! `imu-attest inspect RUN...`: validates runs and prints what each holds (rows, rate, duration,
//! blocks, sidecar, notices). The quickest way for a lab to check a recording against the format.

use std::fmt::Write as _;
use std::path::Path;

use super::{Args, CliError};
use crate::run::Run;

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    args.reject_unknown()?;
    if args.positional.is_empty() {
        return Err(CliError::Input("inspect needs at least one RUN".into()));
    }
    let mut report = String::new();
    for path in &args.positional {
        let run = super::progress::load_run(Path::new(path))?;
        summarise(&run, &mut report);
    }
    eprint!("{report}");
    Ok(())
}

fn summarise(run: &Run, out: &mut String) {
    let blocks: Vec<&str> = run.blocks().iter().map(|b| b.name()).collect();
    let _ = writeln!(
        out,
        "{}: {} samples, {:.6} Hz, {:.3} s, blocks [{}], regime '{}', sha256 {}",
        run.source.file_name,
        run.len(),
        run.sample_rate_hz,
        run.duration_s(),
        blocks.join(", "),
        run.sidecar.regime,
        run.source.sha256
    );
    for notice in &run.notices {
        let _ = writeln!(out, "  note: {notice}");
    }
}
