//! `imu-attest discrepancy RUN [--settings S.json] [--model MODEL.json] --out REPORT.json`
//! (contract sections 3 and 5).
//!
//! Settings: `--settings`, else those of `--model`, else the defaults. With `--model`, each
//! block's report adds the gap that model leaves as it is (`given_model_gap_db`); the search
//! itself always starts from the paper's model identified on this run.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::identify::read_settings;
use super::{Args, CliError};
use crate::diagnose::limits::LimitKind;
use crate::diagnose::{DiagnoseOptions, diagnose_session};
use crate::ident::session::Session;
use crate::model::{MODEL_SCHEMA, Model};
use crate::output::{ensure_not_input, write_atomic};
use crate::run::sidecar_path;

pub(super) fn read_model(path: &Path) -> Result<Model, CliError> {
    let shown = path.display();
    let bytes = std::fs::read(path).map_err(|e| CliError::Input(format!("{shown}: cannot read: {e}")))?;
    let de = &mut serde_json::Deserializer::from_slice(&bytes);
    let mut model: Model = serde_path_to_error::deserialize(de).map_err(|e| {
        let inner = e.inner();
        CliError::Input(format!(
            "{shown}:{}:{}: not a model file at '{}': {inner}",
            inner.line(),
            inner.column(),
            e.path()
        ))
    })?;
    if model.schema != MODEL_SCHEMA {
        return Err(CliError::Input(format!(
            "{shown}: schema '{}' is not '{MODEL_SCHEMA}'",
            model.schema
        )));
    }
    for (name, block) in &model.blocks {
        if let Some(Err(e)) = block.effects.as_ref().map(crate::model::ModelEffects::check) {
            return Err(CliError::Input(format!(
                "{shown}: not a model file at 'blocks.{name}.effects': {e}"
            )));
        }
    }
    model.settle_estimate(&bytes);
    Ok(model)
}

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let model_path = args.get("model").map(PathBuf::from);
    let out = PathBuf::from(args.required("out")?);
    args.reject_unknown()?;
    let [run_path] = args.positional.as_slice() else {
        return Err(CliError::Input(format!(
            "discrepancy takes one RUN, got {}",
            args.positional.len()
        )));
    };
    let run_path = Path::new(run_path);
    let mut inputs = vec![run_path.to_path_buf(), sidecar_path(run_path)];
    inputs.extend(settings_path.clone());
    inputs.extend(model_path.clone());
    ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;
    let model = model_path.as_deref().map(read_model).transpose()?;
    let settings = match (&settings_path, &model) {
        (None, Some(m)) => m.settings.clone(),
        _ => settings,
    };

    let run = std::sync::Arc::new(super::progress::load_run(run_path)?);
    let notices = run.notices.clone();
    let report = diagnose_session(
        &mut Session::new(run),
        &settings,
        &DiagnoseOptions {
            given: model.as_ref(),
            rejected: Vec::new(),
        },
    )
    .map_err(|e| {
        if e.is_input_error() {
            CliError::Input(super::progress::with_notes(
                format!("{}: {e}", run_path.display()),
                &notices,
            ))
        } else {
            CliError::Internal(anyhow::anyhow!("{}: {e}", run_path.display()))
        }
    })?;
    let value = serde_json::to_value(&report).map_err(|e| CliError::Internal(e.into()))?;
    if let Some(path) = crate::model::first_non_finite(&value) {
        return Err(CliError::Internal(anyhow::anyhow!(
            "report not written: non-finite number at {path}"
        )));
    }
    write_atomic(&out, |w| {
        serde_json::to_writer_pretty(&mut *w, &value).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(|e| CliError::Input(e.to_string()))?;
    let mut lines = super::progress::note_lines(run_path, &notices);
    lines.extend(super::identify::refusal_lines(
        &report.refused_blocks,
        report.blocks.keys(),
        "imu-attest: warning: ",
    ));
    lines.extend(input_limit_lines(&report, None));
    lines.extend(tone_limit_lines(&report));
    lines.extend(unexplained_lines(&report, None));
    // The recording's faults last, in `identify`'s words, and for a channel that holds samples
    // or clips one more clause: a finding on it may be the fault's (a glitch is bridged before
    // the analysis, so it has none).
    lines.extend(report.recording_faults.iter().map(|f| {
        let clause = if f.spoils_recording() {
            "; a finding on this channel may be the fault's"
        } else {
            ""
        };
        format!("imu-attest: warning: {f}{clause}")
    }));
    super::identify::print_messages(&lines);
    Ok(())
}

/// Each block's input limit ([`crate::diagnose::input_limit`]): a note where the band was ended
/// below it, a warning where the band searched reaches into it; a warning of a step in the
/// block's delay ([`crate::ident::delay_step`]); where the inputs may not be the motion (the
/// angles mostly their noise, or the block's coherence ended: [`crate::diagnose::noisy_angles`]),
/// a note of what was set aside, or a warning that nothing could be confirmed; the significant
/// candidates not named and why ([`crate::diagnose::not_named`]); after `run: ` when the lines of several runs are printed
/// together.
pub(super) fn input_limit_lines(report: &crate::diagnose::Report, run: Option<&str>) -> Vec<String> {
    limit_lines(report, run, |kind| {
        !matches!(kind, LimitKind::ToneLimit | LimitKind::SizeLimit)
    })
}

/// Each block's tone search limit ([`crate::diagnose::tone_limit`]) and size limits
/// ([`crate::diagnose::size_limit`]), notes: what a search that named no tone, or no effect
/// linear in the model, could have seen.
fn tone_limit_lines(report: &crate::diagnose::Report) -> Vec<String> {
    limit_lines(report, None, |kind| {
        matches!(kind, LimitKind::ToneLimit | LimitKind::SizeLimit)
    })
}

/// The limits of every block's search ([`crate::diagnose::Report::limits`]) of the kinds
/// `which` keeps, as notes and warnings; after `run: ` when given.
fn limit_lines(
    report: &crate::diagnose::Report,
    run: Option<&str>,
    which: impl Fn(LimitKind) -> bool,
) -> Vec<String> {
    let run = run.map_or_else(String::new, |r| format!("{r}: "));
    report
        .blocks
        .keys()
        .flat_map(|name| report.limits(name))
        .filter(|l| which(l.kind))
        .map(|l| {
            let kind = if l.warning { "warning" } else { "note" };
            format!("imu-attest: {kind}: {run}{}", l.words)
        })
        .collect()
}

/// What the model with the findings still leaves unexplained ([`crate::diagnose::Report::unexplained`]),
/// one warning per block; after `run: ` when the lines of several runs are printed together.
pub(super) fn unexplained_lines(report: &crate::diagnose::Report, run: Option<&str>) -> Vec<String> {
    let run = run.map_or_else(String::new, |r| format!("{r}: "));
    report
        .unexplained()
        .into_iter()
        .map(|words| format!("imu-attest: warning: {run}{words}"))
        .collect()
}
