//! `imu-attest batch DIR|RUN... [--settings S.json] [--diagnose] --out TABLE.csv|.json`: a
//! campaign (see `crate::batch`). Bad runs are rows with their reason, and the table is written
//! with every row; the command exits 0 when every run was identified (blocks refused beside
//! identified ones included), 2 when a run failed (its row says why; the summary line on stderr
//! counts them) or for bad arguments.

use std::path::{Path, PathBuf};

use super::identify::read_settings;
use super::{Args, CliError};
use crate::batch::{batch, runs_in, write_table};
use crate::run::sidecar_path;

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let diagnose = args.flag("diagnose");
    let out = PathBuf::from(args.required("out")?);
    args.reject_unknown()?;
    if args.positional.is_empty() {
        return Err(CliError::Input("batch takes a folder or at least one RUN".into()));
    }
    let mut paths = Vec::new();
    for p in &args.positional {
        let path = Path::new(p);
        if path.is_dir() {
            let found =
                runs_in(path).map_err(|e| CliError::Input(format!("{p}: cannot read the folder: {e}")))?;
            if found.is_empty() {
                return Err(CliError::Input(format!(
                    "{p}: no run files (*.csv, *.csv.gz) in this folder"
                )));
            }
            paths.extend(found);
        } else {
            paths.push(path.to_path_buf());
        }
    }
    let mut inputs: Vec<PathBuf> = paths.iter().flat_map(|p| [p.clone(), sidecar_path(p)]).collect();
    inputs.extend(settings_path);
    crate::output::ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;

    let bar = super::progress::bar(paths.len() as u64, "batch {wide_bar} {pos}/{len} runs {elapsed}");
    let rows = batch(&paths, &settings, diagnose, &|done, _| {
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    write_table(&out, &rows).map_err(|e| CliError::Input(e.to_string()))?;
    let count = |status: &str| {
        rows.iter()
            .filter(|r| matches!(r.get("status"), Some(crate::batch::table::Cell::Text(s)) if s == status))
            .count()
    };
    let (failed, refused) = (count("error"), count("refused"));
    // Blocks refused beside identified ones are counted only when there are any.
    let refused = if refused > 0 {
        format!(", {refused} blocks refused")
    } else {
        String::new()
    };
    let summary = format!(
        "batch: {} runs, {} rows, {failed} failed{refused}; table written to {}",
        paths.len(),
        rows.len(),
        out.display()
    );
    if failed > 0 {
        // The table holds every row, the failed runs' with their reasons; the status tells a
        // script that not every run was identified.
        return Err(CliError::Input(format!(
            "{summary} (exit status 2: the failed runs' rows say why)"
        )));
    }
    eprintln!("imu-attest: {summary}");
    Ok(())
}
