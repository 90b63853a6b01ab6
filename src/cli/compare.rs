//! `imu-attest compare RUN RUN... [--settings S.json] [--diagnose] --out COMPARISON.json`:
//! identifies each run with the same settings and writes [`crate::compare::Comparison`] (schema
//! `imu-attest/comparison/1`); with `--diagnose` each run is diagnosed too (as `discrepancy`)
//! and every pair's findings are compared (`findings`, each run's `verdict`).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use std::sync::Arc;

use super::identify::{identify_in, read_settings};
use super::{Args, CliError};
use crate::compare::compare;
use crate::diagnose::{DiagnoseOptions, diagnose_session};
use crate::ident::session::Session;
use crate::output::{ensure_not_input, write_atomic};
use crate::run::sidecar_path;

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let out = PathBuf::from(args.required("out")?);
    let diagnose = args.flag("diagnose");
    args.reject_unknown()?;
    if args.positional.len() < 2 {
        return Err(CliError::Input(format!(
            "compare takes two or more RUNs, got {}",
            args.positional.len()
        )));
    }
    let runs: Vec<&Path> = args.positional.iter().map(Path::new).collect();
    let mut inputs: Vec<PathBuf> = runs
        .iter()
        .flat_map(|r| [r.to_path_buf(), sidecar_path(r)])
        .collect();
    inputs.extend(settings_path);
    ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;
    let mut models = Vec::with_capacity(runs.len());
    // Every run's notes and warnings, printed once the comparison is written: a later run's
    // refusal (exit status 2) stays one line.
    let mut messages = Vec::new();
    let mut reports = Vec::new();
    for r in &runs {
        let mut session = Session::new(Arc::new(super::progress::load_run(r)?));
        // Printed together at the end, each warning names its run (the notes already do).
        let (model, lines) = identify_in(r, &mut session, &settings, &[], true)?;
        models.push(model);
        messages.extend(lines);
        if diagnose {
            let report =
                diagnose_session(&mut session, &settings, &DiagnoseOptions::default()).map_err(|e| {
                    if e.is_input_error() {
                        CliError::Input(format!("{}: {e}", r.display()))
                    } else {
                        CliError::Internal(anyhow::anyhow!("{}: {e}", r.display()))
                    }
                })?;
            let run = super::progress::display_name(r);
            messages.extend(super::discrepancy::input_limit_lines(&report, Some(&run)));
            messages.extend(super::discrepancy::unexplained_lines(&report, Some(&run)));
            reports.push(report);
        }
    }
    let mut comparison = compare(&models).map_err(|e| CliError::Input(e.to_string()))?;
    if diagnose {
        let names: Vec<String> = runs
            .iter()
            .map(|r| {
                r.file_name()
                    .map_or_else(|| r.display().to_string(), |n| n.to_string_lossy().into_owned())
            })
            .collect();
        comparison.add_findings(&reports.iter().collect::<Vec<_>>(), &names);
    }
    for block in crate::block::Block::BOTH.map(crate::block::Block::name) {
        for line in comparison.mount_lines(block) {
            messages.push(format!("imu-attest: {block} block, {line}"));
        }
    }
    write_atomic(&out, |w| {
        serde_json::to_writer_pretty(&mut *w, &comparison).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(|e| CliError::Input(e.to_string()))?;
    super::identify::print_messages(&messages);
    Ok(())
}
