//! Noise figures of an identified model's blocks on its run: the residual of each block's
//! structural model (`K`, delay and, at higher orders, its poles) over the analysed span.

use std::ops::Range;

use rayon::prelude::*;

use super::{BlockNoise, NoiseWarning, block_noise};
use crate::block::Block;
use crate::ident::IdentError;
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::ident::signals::{BlockSignals, channel_names};
use crate::ident::warnings::IdentWarning;
use crate::model::{BlockModel, Model};

use super::reference::{AccelGeometry, ReferencePsd, reference_psd};
use super::residual::{residual, settle_samples};

/// The noise figures of `model`'s block on `signals` over `span` (sample indices); `reference`
/// is the reference's part of each channel, if known.
#[must_use]
pub fn model_block_noise(
    model: &BlockModel,
    signals: &BlockSignals,
    span: Range<usize>,
    sample_rate_hz: f64,
    reference: Option<&[ReferencePsd; 3]>,
) -> Option<BlockNoise> {
    let cut = |c: &[Vec<f64>; 3]| {
        c.each_ref()
            .map(|x| x.get(span.clone()).map(<[f64]>::to_vec).unwrap_or_default())
    };
    let (input, output) = (cut(&signals.input), cut(&signals.output));
    let len = input[0].len();
    let settle = settle_samples(model.tau_s, &model.poles, sample_rate_hz, len);
    let r = residual(&input, &output, sample_rate_hz, settle, |f| model.response(f));
    let mut noise = block_noise(
        signals.block,
        channel_names(signals.block).1,
        &r,
        sample_rate_hz,
        reference,
    )?;
    // The model's own misfit: the identified fit's, or with accepted effects the joint fit's.
    let misfit = model.fit.warnings.iter().find_map(|w| match w {
        IdentWarning::PoorFit { .. } => Some(model.fit.chi2_per_dof),
        IdentWarning::PoorFitWithEffects { chi2_per_dof, .. } => Some(*chi2_per_dof),
        _ => None,
    });
    if let Some(chi2_per_dof) = misfit {
        noise
            .warnings
            .insert(0, NoiseWarning::ModelMisfit { chi2_per_dof });
    }
    Some(noise)
}

/// Fills `noise` of every block of `model` (identified from `session`'s run under `settings`).
///
/// # Errors
/// The session's errors for the block's signals or the span.
pub fn attach_noise(model: &mut Model, session: &mut Session, settings: &Settings) -> Result<(), IdentError> {
    let span = session.span(settings)?;
    let run = session.run().clone();
    let motion = session.motion()?;
    let geometry = AccelGeometry::of(&run);
    let mut jobs = Vec::new();
    for block in Block::BOTH {
        if model.blocks.contains_key(block.name()) {
            jobs.push((block, session.signals(block)?));
        }
    }
    // The blocks in parallel: each is a whole-record residual and its Allan curves.
    let blocks = &model.blocks;
    let results: Vec<(Block, Option<BlockNoise>)> = jobs
        .par_iter()
        .filter_map(|(block, signals)| {
            let entry = blocks.get(block.name())?;
            let reference = reference_psd(*block, &entry.k, &motion.euler, &motion.error_psd, geometry);
            Some((
                *block,
                model_block_noise(entry, signals, span.clone(), run.sample_rate_hz, Some(&reference)),
            ))
        })
        .collect();
    for (block, noise) in results {
        if let Some(entry) = model.blocks.get_mut(block.name()) {
            entry.noise = noise;
        }
    }
    Ok(())
}
