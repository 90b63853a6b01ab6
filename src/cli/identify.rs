//! `imu-attest identify RUN [--settings S.json] --out MODEL.json` (contract sections 3 and 4).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::{Args, CliError};
use std::sync::Arc;

use crate::block::Block;
use crate::diagnose::accepted::read_accepted;
use crate::diagnose::extend::extended_model;
use crate::effect::Effect;
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::model::{Model, RefusedBlock};
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

/// Reads `--effects` (none when absent).
/// Accepted effects and the file they came from.
type EffectsArg = (Vec<(Block, Effect)>, Option<PathBuf>);

fn read_effects(args: &Args) -> Result<EffectsArg, CliError> {
    let Some(p) = args.get("effects") else {
        return Ok((Vec::new(), None));
    };
    let path = PathBuf::from(p);
    let bytes = std::fs::read(&path).map_err(|e| CliError::Input(format!("{p}: cannot read: {e}")))?;
    let accepted = read_accepted(&bytes, &path).map_err(|e| CliError::Input(e.to_string()))?;
    Ok((accepted, Some(path)))
}

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let (settings, settings_path) = read_settings(args)?;
    let (accepted, effects_path) = read_effects(args)?;
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
    inputs.extend(effects_path);
    ensure_not_input(&out, &inputs).map_err(|e| CliError::Input(e.to_string()))?;

    let (model, messages) = identify_model(run_path, &settings, &accepted)?;
    model.write_file(&out).map_err(|e| match e {
        OutputError::NonFinite { .. } => CliError::Internal(anyhow::anyhow!("model not written: {e}")),
        other => CliError::Input(other.to_string()),
    })?;
    print_messages(&messages);
    Ok(())
}

/// The lines a successful command prints on stderr: printed only once its output is written, so
/// that a refusal (exit status 2) stays one line.
pub(super) fn print_messages(messages: &[String]) {
    for line in messages {
        eprintln!("{line}");
    }
}

/// Loads and identifies one run into its checked model and the lines to print when the command
/// succeeds ([`identify_in`]), the `accepted` effects in its blocks' models.
pub(super) fn identify_model(
    run_path: &Path,
    settings: &Settings,
    accepted: &[(Block, Effect)],
) -> Result<(Model, Vec<String>), CliError> {
    let run = Arc::new(super::progress::load_run(run_path)?);
    identify_in(run_path, &mut Session::new(run), settings, accepted, false)
}

/// Identifies the run of `session` (loaded from `run_path`) into its checked model, with the
/// lines to print on stderr once the command's output is written: the loader's notices, the
/// fit's warnings, recording faults (a refusal carries the notices on its one line instead), each
/// warning naming the run with `name_run` (commands over several runs print them together). The
/// session keeps its stages for what comes next (`compare --diagnose`).
pub(super) fn identify_in(
    run_path: &Path,
    session: &mut Session,
    settings: &Settings,
    accepted: &[(Block, Effect)],
    name_run: bool,
) -> Result<(Model, Vec<String>), CliError> {
    let settings = settings.for_run(session.run());
    let notices = session.run().notices.clone();
    // Settings that do not fit this run are the user's input; anything else is ours.
    let bar = super::progress::bar(1, "identifying {wide_bar} {pos}/{len} {msg} {elapsed}");
    let model = extended_model(session, &settings, accepted, &mut |step| {
        bar.set_length(step.total as u64);
        bar.set_position(step.done as u64);
        bar.set_message(match step.block {
            Some(block) => format!("{} {}", block.name(), step.stage),
            None => step.stage.to_owned(),
        });
    });
    bar.finish_and_clear();
    let model = model.map_err(|e| {
        if e.is_input_error() {
            CliError::Input(super::progress::with_notes(
                format!("{}: {e}", run_path.display()),
                &notices,
            ))
        } else {
            CliError::Internal(anyhow::anyhow!("{}: {e}", run_path.display()))
        }
    })?;
    let mut messages = super::progress::note_lines(run_path, &notices);
    let warning = if name_run {
        format!(
            "imu-attest: warning: {}: ",
            super::progress::display_name(run_path)
        )
    } else {
        "imu-attest: warning: ".to_owned()
    };
    for (name, block) in &model.blocks {
        for w in &block.fit.warnings {
            messages.push(format!("{warning}{name} block: {w}"));
        }
        for n in block.effects.iter().flat_map(|e| &e.not_added) {
            messages.push(format!(
                "{warning}{name} block: {} not added: {}",
                n.effect, n.reason
            ));
        }
    }
    messages.extend(refusal_lines(
        &model.refused_blocks,
        model.blocks.keys(),
        &warning,
    ));
    for (block, effect) in accepted {
        if model.refused_blocks.contains_key(block.name()) {
            messages.push(format!(
                "{warning}{effect} not added: the {} block was not identified",
                block.name()
            ));
        } else if !model.blocks.contains_key(block.name()) {
            messages.push(format!(
                "{warning}{effect} not added: the run has no {} block",
                block.name()
            ));
        }
    }
    for fault in &model.recording_faults {
        messages.push(format!("{warning}{fault}"));
    }
    model
        .check_finite()
        .map_err(|e| CliError::Internal(anyhow::anyhow!("model not written: {e}")))?;
    Ok((model, messages))
}

/// The warning of each refused block ([`RefusedBlock::words`]), after `warning`.
pub(super) fn refusal_lines<'a>(
    refused: &BTreeMap<String, RefusedBlock>,
    kept: impl Iterator<Item = &'a String>,
    warning: &str,
) -> Vec<String> {
    let kept: Vec<&str> = kept.map(String::as_str).collect();
    refused
        .iter()
        .map(|(name, r)| format!("{warning}{}", r.words(name, &kept)))
        .collect()
}
