//! The blocks of a run that its model does not hold because the run cannot identify them (an
//! accelerometer with no band where its outputs follow the inputs, or an input axis not
//! excited; either block with a dead output channel: `IdentError::is_refusal`), each with the refusal in words: written beside the identified
//! blocks, so that one block the run cannot identify does not take the others with it
//! (`Model::refused_blocks`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::ident::IdentError;
use crate::ident::identify::Refusal;

/// Why a block was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RefusalKind {
    /// An input axis carries (almost) no power in the band.
    NotExcited,
    /// The outputs are nowhere coherent with the inputs computed from the angles.
    NoUsableBand,
    /// An output channel holds one value throughout (a dead or disconnected sensor axis).
    DeadOutput,
}

/// A refused block's entry in the model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefusedBlock {
    /// Why.
    pub kind: RefusalKind,
    /// The input axis held still (`fy`, `wz`, ...), for `not_excited`; the flat output channels
    /// (`gz`, or `gy,gz`), for `dead_output`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<String>,
    /// The refusal in words, with what to do about it: what the command line prints.
    pub reason: String,
}

impl RefusedBlock {
    /// The entry of a refusal; `None` for an error that is not one ([`IdentError::is_refusal`]).
    #[must_use]
    pub fn of(error: &IdentError) -> Option<Self> {
        let (kind, axis) = match error {
            IdentError::NotExcited { axis, .. } => (RefusalKind::NotExcited, Some((*axis).to_owned())),
            IdentError::NoUsableBand { .. } => (RefusalKind::NoUsableBand, None),
            IdentError::DeadOutput { channels, .. } => {
                let names: Vec<&str> = channels.iter().map(|(name, _)| *name).collect();
                (RefusalKind::DeadOutput, Some(names.join(",")))
            }
            _ => return None,
        };
        Some(Self {
            kind,
            axis,
            reason: error.to_string(),
        })
    }

    /// The refusal in words, as the command line and the app say it: that the block named
    /// `block` is not identified, which blocks (`kept`) the result holds, and why.
    #[must_use]
    pub fn words(&self, block: &str, kept: &[&str]) -> String {
        let prefix = format!("{block} block: ");
        let why = self.reason.strip_prefix(&prefix).unwrap_or(&self.reason);
        format!(
            "{block} block not identified, the result holds the {} block only: {why}",
            kept.join(" and ")
        )
    }
}

/// The model file's `refused_blocks` of an identification's refusals, keyed by block name.
#[must_use]
pub fn refused_blocks(refused: &[Refusal]) -> BTreeMap<String, RefusedBlock> {
    refused
        .iter()
        .filter_map(|r| Some((r.block.name().to_owned(), RefusedBlock::of(&r.error)?)))
        .collect()
}
