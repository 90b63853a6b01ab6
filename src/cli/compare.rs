//! `imu-attest compare RUN RUN... [--settings S.json] --out COMPARISON.json`: identifies each run
//! with the same settings and writes [`crate::compare::Comparison`] (schema
//! `imu-attest/comparison/1`).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::identify::{identify_model, read_settings};
use super::{Args, CliError};
use crate::compare::compare;
use crate::output::{ensure_not_input, write_atomic};
use crate::run::sidecar_path;

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let out = PathBuf::from(args.required("out")?);
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
    let models = runs
        .iter()
        .map(|r| identify_model(r, &settings, &[]))
        .collect::<Result<Vec<_>, _>>()?;
    let comparison = compare(&models).map_err(|e| CliError::Input(e.to_string()))?;
    write_atomic(&out, |w| {
        serde_json::to_writer_pretty(&mut *w, &comparison).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(|e| CliError::Input(e.to_string()))
}
