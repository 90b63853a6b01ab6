//! The limits of a block's search, in words: what every front end says beside the findings (the
//! command line's notes and warnings, the app's Missing effects tab, the certificate), made in
//! one place and said in one order: where the inputs stop being the motion
//! ([`super::input_limit`]), a step in the block's delay ([`crate::ident::delay_step`]), where the
//! inputs may not be the motion and a smooth finding is confirmed below (the angles mostly their
//! noise, or the block's coherence ended: [`super::noisy_angles`]), the significant candidates not named
//! ([`super::not_named`]), and what a search that named no tone could have seen
//! ([`super::tone_limit`]), or no effect linear in the model ([`super::size_limit`]).

use super::report::Report;
use crate::block::Block;

/// What a limit is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitKind {
    /// Where the block's inputs stop being the motion.
    InputLimit,
    /// A step in the block's delay through the record.
    DelayStep,
    /// Where the inputs may not be the motion (the angles mostly their noise, or the block's
    /// coherence ended), and what the band below did not confirm.
    NoisyAngles,
    /// Significant candidates the search did not name, and why.
    NotNamed,
    /// The smallest tone the search could have seen.
    ToneLimit,
    /// The smallest size of an effect linear in the model the search could have seen.
    SizeLimit,
}

/// One limit of a block's search, in words (one sentence naming the block, no final stop), and
/// whether it is a warning (else a note).
#[derive(Clone, Debug, PartialEq)]
pub struct Limit {
    /// What it is about.
    pub kind: LimitKind,
    /// The sentence.
    pub words: String,
    /// A warning rather than a note.
    pub warning: bool,
}

impl Report {
    /// The limits of block `name`'s search in the order they are said; empty for a block not in
    /// the report.
    #[must_use]
    pub fn limits(&self, name: &str) -> Vec<Limit> {
        let Some(b) = self.blocks.get(name) else {
            return Vec::new();
        };
        let limit = |kind, words, warning| Limit { kind, words, warning };
        let mut out = Vec::new();
        if let Some(input) = &b.input_limit {
            out.push(limit(
                LimitKind::InputLimit,
                input.words(name),
                input.is_warning(),
            ));
        }
        if let Some(step) = &b.delay_step {
            out.push(limit(LimitKind::DelayStep, step.diagnosis_words(name), true));
        }
        if let Some(noisy) = &b.noisy_angles
            && let Some(words) = noisy.words(name)
        {
            out.push(limit(LimitKind::NoisyAngles, words, noisy.is_warning()));
        }
        if let Some((words, warning)) = self.not_named_words(name) {
            out.push(limit(LimitKind::NotNamed, words, warning));
        }
        if let (Some(block), Some(tone)) = (Block::from_name(name), &b.tone_limit) {
            out.push(limit(LimitKind::ToneLimit, tone.words(block), false));
        }
        if let Some(block) = Block::from_name(name) {
            for size in &b.size_limits {
                out.push(limit(LimitKind::SizeLimit, size.words(block), false));
            }
        }
        out
    }
}
