//! `imu-attest inspect RUN...`: validates runs and prints what each holds (rows, rate, duration,
//! blocks, sidecar, notices). The quickest way for a lab to check a recording against the format.

use std::fmt::Write as _;
use std::path::Path;

use super::{Args, CliError};
use crate::ident::dead_output::held_value;
use crate::ident::signals::channel_names;
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
    // Columns that never move: what `identify` will refuse, said before it is run.
    let outputs = run.blocks().into_iter().flat_map(|block| {
        let why = format!(
            "a dead or disconnected channel; identify refuses the {} block",
            block.name()
        );
        let columns = run.outputs(block).into_iter().flatten();
        columns
            .zip(channel_names(block).1)
            .map(move |(c, name)| (c, name, why.clone()))
    });
    let still = "that stand axis is held still, and no block's response to it can be identified \
                 from this run";
    let angles = run
        .angles
        .iter()
        .zip(["roll", "yaw", "pitch"])
        .map(|(c, name)| (c, name, still.to_owned()));
    for (column, name, why) in outputs.chain(angles) {
        if let Some(value) = held_value(column) {
            let _ = writeln!(out, "  warning: {name} never moves (always {value}): {why}");
        }
    }
}
