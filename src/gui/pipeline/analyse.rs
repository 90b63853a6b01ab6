//! The analysis of one loaded run, stage by stage, each cached with the key it depends on:
//! observer (the run), spectra (Welch settings), factorisation (the spectra, per block), and the
//! identification (`identify_block_from`: band, A, Lambda, order, blocks) — so a change of A,
//! Lambda or the order redoes only the Wiener and structural fit.

use std::sync::Arc;

use rayon::prelude::*;

use super::display::Spectra;
use super::identified::Identification;
use super::stages::{self, Measured, Motion};
use super::{Event, RunId, RunSummary, Stage};
use crate::block::Block;
use crate::ident::factorisation::{Factorisation, FactorisationSettings, factorise, factorise_from};
use crate::ident::identify::identify_block_from;
use crate::ident::settings::Settings;
use crate::ident::structural::StructuralFit;
use crate::run::Sidecar;
use crate::spectral::WelchPlanner;

/// A loaded run's cached stages.
pub(super) struct RunCache {
    pub summary: Arc<RunSummary>,
    pub sidecar: Sidecar,
    pub measured: Arc<Measured>,
    pub motion: Option<Arc<Motion>>,
    pub spectra: Option<Arc<Spectra>>,
    /// Factorisations of `spectra`'s blocks.
    pub factorisations: Vec<(Block, Arc<Factorisation>)>,
    /// The factorisations before the latest change of the Welch settings: the start of the next
    /// factorisation of their block.
    pub previous_factorisations: Vec<(Block, Arc<Factorisation>)>,
    pub identification: Option<Arc<Identification>>,
    /// Every block's latest structural fit, kept across changes of the Welch settings: the start
    /// of the next fit.
    pub fits: Vec<(Block, Arc<StructuralFit>)>,
}

impl RunCache {
    pub fn new(summary: Arc<RunSummary>, sidecar: Sidecar, measured: Arc<Measured>) -> Self {
        Self {
            summary,
            sidecar,
            measured,
            motion: None,
            spectra: None,
            factorisations: Vec::new(),
            previous_factorisations: Vec::new(),
            identification: None,
            fits: Vec::new(),
        }
    }
}

/// One analysis job's context.
pub(super) struct Analysis<'a> {
    pub run: RunId,
    pub generation: u64,
    pub send: &'a dyn Fn(Event),
}

impl Analysis<'_> {
    fn fail(&self, stage: Stage, message: String) {
        (self.send)(Event::Failed {
            run: self.run,
            generation: self.generation,
            stage,
            message,
            cancelled: false,
        });
    }

    /// Brings every stage of `cache` up to date with `settings`, sending each new result.
    pub fn analyse(
        &self,
        cache: &mut RunCache,
        planner: &mut WelchPlanner,
        settings: &Settings,
        stage: &mut Stage,
    ) {
        let (run, generation) = (self.run, self.generation);
        let fs = cache.summary.sample_rate_hz;
        *stage = Stage::Motion;
        let motion = if let Some(m) = &cache.motion {
            m.clone()
        } else {
            match stages::motion(&cache.measured, fs, &cache.sidecar) {
                Ok(m) => {
                    let m = Arc::new(m);
                    cache.motion = Some(m.clone());
                    (self.send)(Event::Motion {
                        run,
                        generation,
                        motion: m.clone(),
                    });
                    m
                }
                Err(e) => return self.fail(Stage::Motion, e.to_string()),
            }
        };
        *stage = Stage::Spectra;
        let cached = cache
            .spectra
            .as_ref()
            .filter(|s| s.welch == settings.welch)
            .cloned();
        let spectra = if let Some(s) = cached {
            s
        } else {
            match stages::spectra(planner, &cache.measured, &motion, fs, &settings.welch) {
                Ok(s) => {
                    let s = Arc::new(s);
                    cache.spectra = Some(s.clone());
                    if !cache.factorisations.is_empty() {
                        cache.previous_factorisations = std::mem::take(&mut cache.factorisations);
                    }
                    cache.identification = None;
                    s
                }
                Err(e) => return self.fail(Stage::Spectra, e.to_string()),
            }
        };
        (self.send)(Event::Spectra {
            run,
            generation,
            spectra: spectra.clone(),
        });
        *stage = Stage::Identify;
        let summary = &cache.summary;
        if let Err(e) = settings.validate(summary.n_samples, fs, &summary.blocks) {
            return self.fail(Stage::Identify, e.to_string());
        }
        let settings = Settings {
            blocks: settings.blocks_for(&summary.blocks),
            ..settings.clone()
        };
        if let Some(id) = cache.identification.as_ref().filter(|i| i.settings == settings) {
            return (self.send)(Event::Identified {
                run,
                generation,
                identification: id.clone(),
            });
        }
        let mut cores = Vec::new();
        for &block in &settings.blocks {
            let Some(core) = spectra.blocks.iter().find(|b| b.block == block) else {
                return self.fail(Stage::Identify, format!("the run has no {} block", block.name()));
            };
            cores.push((block, core.matrix.core.clone()));
        }
        *stage = Stage::Factorisation;
        // The missing factorisations of all blocks at once: each block's two Wilson factorisations
        // take unequal times, together they keep both cores busy.
        let factorised: Result<Vec<_>, String> = cores
            .into_par_iter()
            .map(|(block, core)| {
                let factorisation = if let Some(known) = of_block(&cache.factorisations, block) {
                    known
                } else {
                    let start = of_block(&cache.previous_factorisations, block);
                    factorise_from(&core, &FactorisationSettings::default(), start.as_deref())
                        .map(Arc::new)
                        .map_err(|e| format!("{}: {e}", block.name()))?
                };
                Ok((block, core, factorisation))
            })
            .collect();
        let factorised = match factorised {
            Ok(factorised) => factorised,
            Err(message) => return self.fail(Stage::Factorisation, message),
        };
        for (block, _, factorisation) in &factorised {
            if of_block(&cache.factorisations, *block).is_none() {
                cache.factorisations.push((*block, factorisation.clone()));
            }
        }
        let prepared: Vec<_> = factorised
            .into_iter()
            .map(|(block, core, factorisation)| (block, core, factorisation, of_block(&cache.fits, block)))
            .collect();
        *stage = Stage::Identify;
        // The blocks in parallel: a retune's wait is the slower block's, not the sum.
        let identified: Result<Vec<_>, String> = prepared
            .into_par_iter()
            .map(|(block, core, factorisation, previous)| {
                identify_block_from(block, core, factorisation, &settings, previous.as_deref())
                    .map_err(|e| format!("{}: {e}", block.name()))
            })
            .collect();
        let blocks = match identified {
            Ok(blocks) => blocks,
            Err(message) => return self.fail(Stage::Identify, message),
        };
        cache.fits = blocks.iter().map(|b| (b.block, b.structural.clone())).collect();
        let identification = Arc::new(Identification::new(summary, settings, blocks));
        cache.identification = Some(identification.clone());
        (self.send)(Event::Identified {
            run,
            generation,
            identification,
        });
    }

    /// Redoes from scratch the factorisations and structural fits of a provisional identification
    /// (see [`Identification::provisional`]) and sends the identification again, under the same
    /// generation. Nothing to do if the cached identification is not provisional.
    pub fn polish(&self, cache: &mut RunCache) {
        let Some(id) = cache.identification.clone().filter(|i| i.provisional()) else {
            return;
        };
        let refitted: Result<Vec<_>, String> = id
            .blocks
            .par_iter()
            .map(|b| {
                if b.structural.fitted.from_scratch() && b.factorisation.from_scratch {
                    return Ok(b.clone());
                }
                let factorisation = if b.factorisation.from_scratch {
                    b.factorisation.clone()
                } else {
                    Arc::new(
                        factorise(&b.spectra, &FactorisationSettings::default())
                            .map_err(|e| format!("{}: {e}", b.block.name()))?,
                    )
                };
                identify_block_from(b.block, b.spectra.clone(), factorisation, &id.settings, None)
                    .map_err(|e| format!("{}: {e}", b.block.name()))
            })
            .collect();
        let blocks = match refitted {
            Ok(blocks) => blocks,
            Err(message) => return self.fail(Stage::Identify, message),
        };
        cache.fits = blocks.iter().map(|b| (b.block, b.structural.clone())).collect();
        cache.factorisations = blocks
            .iter()
            .map(|b| (b.block, b.factorisation.clone()))
            .collect();
        let identification = Arc::new(Identification::new(&cache.summary, id.settings.clone(), blocks));
        cache.identification = Some(identification.clone());
        (self.send)(Event::Identified {
            run: self.run,
            generation: self.generation,
            identification,
        });
    }
}

/// The entry of `block` in a per-block list.
fn of_block<T: Clone>(list: &[(Block, T)], block: Block) -> Option<T> {
    list.iter().find(|(b, _)| *b == block).map(|(_, v)| v.clone())
}
