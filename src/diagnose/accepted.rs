//! The file of accepted effects `identify --effects E.json` reads: either a list
//! `{"effects": [{"block": "gyro", "effect": "sensor_lag"}, ...]}` or a discrepancy report (its
//! `findings`, every other field ignored), so that `discrepancy RUN --out R.json` followed by
//! `identify RUN --effects R.json` accepts everything the diagnosis found.

use std::path::Path;

use serde::Deserialize;

use crate::block::Block;
use crate::effect::Effect;
use crate::ident::settings::json_problem;

/// Why an effects file was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EffectsFileError {
    /// Not JSON, or an entry that is not `{block, effect}` of known names.
    #[error("{file}: line {line}, column {column}: {detail}")]
    Parse {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong, with the JSON path.
        detail: String,
    },
    /// Neither an `effects` nor a `findings` list.
    #[error("{file}: neither an \"effects\" list nor a discrepancy report's \"findings\"")]
    NoList {
        /// The file.
        file: String,
    },
    /// An effect named on a block it cannot apply to.
    #[error("{file}: {list}[{index}]: {effect} is not an effect of the {block} block")]
    WrongBlock {
        /// The file.
        file: String,
        /// `effects` or `findings`.
        list: &'static str,
        /// The entry.
        index: usize,
        /// The effect.
        effect: Effect,
        /// The block named.
        block: &'static str,
    },
}

#[derive(Deserialize)]
struct Entry {
    block: Block,
    effect: Effect,
}

#[derive(Deserialize)]
struct File {
    #[serde(default)]
    effects: Option<Vec<Entry>>,
    #[serde(default)]
    findings: Option<Vec<Entry>>,
}

/// The accepted `(block, effect)` pairs of an effects file, in its order.
///
/// # Errors
/// [`EffectsFileError`] naming the file and, for a parse error, the line and column.
pub fn read_accepted(bytes: &[u8], file: &Path) -> Result<Vec<(Block, Effect)>, EffectsFileError> {
    let name = file.display().to_string();
    let parse_error = |path: String, inner: &serde_json::Error| {
        let (line, column, detail) = json_problem(&path, inner);
        EffectsFileError::Parse {
            file: name.clone(),
            line,
            column,
            detail,
        }
    };
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let parsed: File = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| parse_error(e.path().to_string(), e.inner()))?;
    de.end().map_err(|e| parse_error(".".into(), &e))?;
    let (list, entries) = match (parsed.effects, parsed.findings) {
        (Some(e), _) => ("effects", e),
        (None, Some(f)) => ("findings", f),
        (None, None) => return Err(EffectsFileError::NoList { file: name }),
    };
    let mut out: Vec<(Block, Effect)> = Vec::new();
    for (index, e) in entries.iter().enumerate() {
        if !e.effect.blocks().contains(&e.block) {
            return Err(EffectsFileError::WrongBlock {
                file: name,
                list,
                index,
                effect: e.effect,
                block: e.block.name(),
            });
        }
        if !out.contains(&(e.block, e.effect)) {
            out.push((e.block, e.effect));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Vec<(Block, Effect)>, EffectsFileError> {
        read_accepted(text.as_bytes(), Path::new("e.json"))
    }

    #[test]
    fn a_list_or_a_reports_findings() {
        assert_eq!(
            read(
                r#"{"effects": [{"block": "gyro", "effect": "sensor_lag"}, {"block": "accel", "effect": "lever_arm_error"}]}"#
            ),
            Ok(vec![
                (Block::Gyro, Effect::SensorLag),
                (Block::Accel, Effect::LeverArmError)
            ])
        );
        let report = r#"{"schema": "imu-attest/discrepancy/1", "verdict": "effect_found", "findings": [
            {"block": "accel", "effect": "platform_resonance", "name": "x", "parameters": {"axis": "fy"}},
            {"block": "accel", "effect": "platform_resonance", "name": "y"}]}"#;
        assert_eq!(read(report), Ok(vec![(Block::Accel, Effect::PlatformResonance)]));
        assert_eq!(read(r#"{"effects": []}"#), Ok(vec![]));
    }

    #[test]
    fn bad_files_are_refused_with_where_and_why() {
        let err =
            read("{\"effects\": [\n {\"block\": \"gyro\", \"effect\": \"lag\"}]}").expect_err("unknown");
        let text = err.to_string();
        assert!(text.starts_with("e.json: line 2, column"), "{text}");
        assert!(
            text.contains("effects[0].effect") && text.contains("lag"),
            "{text}"
        );
        let err =
            read(r#"{"effects": [{"block": "accel", "effect": "g_sensitivity"}]}"#).expect_err("wrong block");
        assert_eq!(
            err.to_string(),
            "e.json: effects[0]: g_sensitivity is not an effect of the accel block"
        );
        assert!(matches!(
            read(r#"{"model": 1}"#),
            Err(EffectsFileError::NoList { .. })
        ));
        assert!(matches!(
            read("{\"effects\": [}"),
            Err(EffectsFileError::Parse { line: 1, .. })
        ));
    }
}
