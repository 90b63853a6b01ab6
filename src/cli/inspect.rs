//! `imu-attest inspect RUN...`: validates runs and prints what each holds (rows, rate, duration,
//! blocks, sidecar, notices). The quickest way for a lab to check a recording against the format.

use std::fmt::Write as _;
use std::path::Path;

use super::{Args, CliError};
use crate::ident::dead_output::moves;
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
    for block in run.blocks() {
        let names = channel_names(block).1;
        for (column, name) in run.outputs(block).into_iter().flatten().zip(names) {
            if !moves(column) {
                let _ = writeln!(
                    out,
                    "  warning: {name} never moves (always {}): a dead or disconnected channel; \
                     identify refuses the {} block",
                    column[0],
                    block.name()
                );
            }
        }
    }
    for (column, name) in run.angles.iter().zip(["roll", "yaw", "pitch"]) {
        if !moves(column) {
            let _ = writeln!(
                out,
                "  warning: {name} never moves (always {}): that stand axis is held still, and no \
                 block's response to it can be identified from this run",
                column[0]
            );
        }
    }
}
