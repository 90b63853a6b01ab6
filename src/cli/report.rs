//! `imu-attest report RUN... [--settings S.json] [--model MODEL.json] [--spec SPEC.json]
//! --out REPORT.html`: the certificate (see `crate::report`). With `--spec`, prints the summary
//! of the verdicts (`3 fail, 1 undecided, 12 pass`) on standard output; the exit status stays 0
//! whatever the verdicts (a failed limit is a finding, not an error).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::discrepancy::read_model;
use super::identify::read_settings;
use super::{Args, CliError};
use crate::ident::session::Session;
use crate::report::spec::Spec;
use crate::report::{render, run_report, utc_now, write_page};
use crate::run::sidecar_path;

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let model_path = args.get("model").map(PathBuf::from);
    let spec_path = args.get("spec").map(PathBuf::from);
    let out = PathBuf::from(args.required("out")?);
    args.reject_unknown()?;
    if args.positional.is_empty() {
        return Err(CliError::Input("report takes at least one RUN".into()));
    }
    if model_path.is_some() && args.positional.len() > 1 {
        return Err(CliError::Input(
            "--model goes with one RUN (the run it was identified from)".into(),
        ));
    }
    let mut inputs: Vec<PathBuf> = Vec::new();
    for p in &args.positional {
        inputs.push(PathBuf::from(p));
        inputs.push(sidecar_path(Path::new(p)));
    }
    inputs.extend(settings_path.clone());
    inputs.extend(model_path.clone());
    inputs.extend(spec_path.clone());
    crate::output::ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;
    let spec = spec_path
        .as_deref()
        .map(Spec::read)
        .transpose()
        .map_err(|e| CliError::Input(e.to_string()))?;
    let given = model_path.as_deref().map(read_model).transpose()?;

    let mut reports = Vec::new();
    // Notes and warnings, printed once the page is written (a refusal stays one line).
    let mut messages = Vec::new();
    for path in &args.positional {
        let path = Path::new(path);
        let run = Arc::new(super::progress::load_run(path)?);
        let model = given.clone();
        if let Some(m) = &model
            && m.source.sha256 != run.source.sha256
        {
            return Err(CliError::Input(format!(
                "{}: the model was identified from another file ({}, sha256 {}...)",
                path.display(),
                m.source.file,
                m.source.sha256.get(..12).unwrap_or_default()
            )));
        }
        let settings = match (&settings_path, &model) {
            (None, Some(m)) => m.settings.clone(),
            _ => settings.for_run(&run),
        };
        let bar = super::progress::bar(1, "{spinner} reporting {msg} {elapsed}");
        bar.set_message(path.display().to_string());
        let notices = run.notices.clone();
        let report = run_report(&mut Session::new(run), &settings, model);
        bar.finish_and_clear();
        let report = report.map_err(|e| {
            if e.is_input_error() {
                CliError::Input(super::progress::with_notes(
                    format!("{}: {e}", path.display()),
                    &notices,
                ))
            } else {
                CliError::Internal(anyhow::anyhow!("{}: {e}", path.display()))
            }
        })?;
        messages.extend(super::progress::note_lines(path, &notices));
        for (name, b) in &report.model.blocks {
            for w in &b.fit.warnings {
                messages.push(format!(
                    "imu-attest: warning: {}: {name} block: {w}",
                    path.display()
                ));
            }
        }
        messages.extend(super::identify::refusal_lines(
            &report.model.refused_blocks,
            report.model.blocks.keys(),
            &format!("imu-attest: warning: {}: ", path.display()),
        ));
        if let Ok(diagnosis) = &report.diagnosis {
            let shown = path.display().to_string();
            messages.extend(super::discrepancy::input_limit_lines(diagnosis, Some(&shown)));
            messages.extend(super::discrepancy::unexplained_lines(diagnosis, Some(&shown)));
        }
        reports.push(report);
    }
    let (page, checks) = render(&reports, spec.as_ref(), &utc_now());
    write_page(&out, &page).map_err(|e| CliError::Input(e.to_string()))?;
    super::identify::print_messages(&messages);
    if spec.is_some() {
        print_summary(&crate::report::spec::summary(&checks));
    }
    Ok(())
}

#[expect(
    clippy::print_stdout,
    reason = "the summary line is the command's standard output"
)]
fn print_summary(line: &str) {
    println!("{line}");
}
