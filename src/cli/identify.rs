//! `imu-attest identify RUN [--settings S.json] --out MODEL.json` (contract sections 3 and 4).

use std::path::{Path, PathBuf};

use super::{Args, CliError};
use crate::ident::IdentError;
use crate::ident::identify::identify_run;
use crate::ident::settings::Settings;
use crate::model::Model;
use crate::output::{OutputError, ensure_not_input};
use crate::run::sidecar_path;

/// Reads `--settings` (or the defaults).
pub(super) fn read_settings(args: &Args) -> Result<(Settings, Option<PathBuf>), CliError> {
    match args.get("settings") {
        None => Ok((Settings::default(), None)),
        Some(p) => {
            let path = PathBuf::from(p);
            let bytes =
                std::fs::read(&path).map_err(|e| CliError::Input(format!("{p}: cannot read: {e}")))?;
            let settings = Settings::from_json(&bytes, &path).map_err(|e| CliError::Input(e.to_string()))?;
            Ok((settings, Some(path)))
        }
    }
}

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let out = PathBuf::from(args.required("out")?);
    args.reject_unknown()?;
    let [run_path] = args.positional.as_slice() else {
        return Err(CliError::Input(format!(
            "identify takes one RUN, got {}",
            args.positional.len()
        )));
    };
    let run_path = Path::new(run_path);
    let mut inputs = vec![run_path.to_path_buf(), sidecar_path(run_path)];
    inputs.extend(settings_path);
    ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;

    let run = super::progress::load_run(run_path)?;
    let settings = Settings {
        blocks: settings.blocks_for(&run.blocks()),
        ..settings
    };
    // Settings that do not fit this run are the user's input; anything else is ours.
    let id = identify_run(&run, &settings).map_err(|e| match e {
        IdentError::Settings(_)
        | IdentError::MissingBlock(_)
        | IdentError::EmptyBand { .. }
        | IdentError::NotExcited { .. } => CliError::Input(format!("{}: {e}", run_path.display())),
        other => CliError::Internal(anyhow::anyhow!("{}: {other}", run_path.display())),
    })?;
    for block in &id.blocks {
        for warning in &block.warnings {
            eprintln!("imu-attest: warning: {} block: {warning}", block.block.name());
        }
    }
    let model = Model::from_identification(&run, &settings, &id);
    model.write_file(&out).map_err(|e| match e {
        OutputError::NonFinite { .. } => CliError::Internal(anyhow::anyhow!("model not written: {e}")),
        other => CliError::Input(other.to_string()),
    })
}
