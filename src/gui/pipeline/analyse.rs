//! The analysis of one loaded run on the worker: the core's staged, cached pipeline
//! ([`Session`]) computes, this module turns each stage's new result into what the app draws and
//! sends it. The session redoes only what a changed setting touches (a change of A, Lambda or
//! the order: the Wiener estimate and the structural fit), starting warm from the previous
//! factorisations and fits; [`Analysis::polish`] then redoes a warm result from scratch.

use std::sync::Arc;

use super::display::Spectra;
use super::identified::Identification;
use super::stages::{self, Measured, Motion};
use super::{Event, FailureKind, RunId, RunSummary, Stage};
use crate::block::Block;
use crate::diagnose::extend::{prepare_for_effects, starts_match};
use crate::diagnose::suspect::{attach, suspicions};
use crate::diagnose::{DiagnoseError, Prepared, prepare};
use crate::effect::Effect;
use crate::ident::IdentError;
use crate::ident::identify::RunIdentification;
use crate::ident::session::{Session, Start};
use crate::ident::settings::Settings;
use crate::ident::warnings::IdentWarning;
use crate::model::Model;
use crate::noise::reference::AccelGeometry;

/// The accepted effects' starting points with the settings and effects they were made for.
pub(super) type EffectStart = (Settings, Vec<(Block, Effect)>, Arc<Vec<Prepared>>);

/// The effects suspected of an identification (`crate::diagnose::suspect::suspicions`).
pub(super) type Suspected = (Arc<RunIdentification>, Vec<(Block, IdentWarning)>);

/// A loaded run: the core's session and the display snapshots of its stages.
pub(super) struct RunCache {
    pub summary: Arc<RunSummary>,
    pub measured: Arc<Measured>,
    /// The core's pipeline of this run.
    pub session: Session,
    pub motion: Option<Arc<Motion>>,
    pub spectra: Option<Arc<Spectra>>,
    /// The span of `spectra`.
    pub spectra_span: Option<[f64; 2]>,
    pub identification: Option<Arc<Identification>>,
    /// Effects accepted into the model (the latest analysis job's).
    pub accepted: Vec<(Block, Effect)>,
    /// The diagnosis's starting point under the settings it was made for (blocks resolved):
    /// reused by a rejection's rerun.
    pub prepared: Option<(Settings, Arc<Prepared>)>,
    /// The accepted effects' starting points (`prepare_for_effects`) under the settings and
    /// effects they were made for: a retune or a refit from scratch with the same settings and
    /// effects reuses them where they start from the model's bands (`starts_match`).
    pub effect_prepared: Option<EffectStart>,
    /// The effects suspected of the identification they were tested on
    /// (`crate::diagnose::suspect`): an Accept or a Reject does not test them again.
    pub suspected: Option<Suspected>,
}

impl RunCache {
    pub fn new(summary: Arc<RunSummary>, measured: Arc<Measured>, session: Session) -> Self {
        Self {
            summary,
            measured,
            session,
            motion: None,
            spectra: None,
            spectra_span: None,
            identification: None,
            accepted: Vec::new(),
            prepared: None,
            effect_prepared: None,
            suspected: None,
        }
    }

    /// The diagnosis's starting point for `settings`, computed once per settings.
    ///
    /// # Errors
    /// The diagnosis's (the identification's, a record too short for it).
    pub fn prepared(&mut self, settings: &Settings) -> Result<Arc<Prepared>, DiagnoseError> {
        let settings = settings.for_run(self.session.run());
        if let Some((s, p)) = &self.prepared
            && *s == settings
        {
            return Ok(p.clone());
        }
        let p = Arc::new(prepare(&mut self.session, &settings)?);
        self.prepared = Some((settings, p.clone()));
        Ok(p)
    }
}

/// The stage an identification error belongs to.
fn stage_of(e: &IdentError) -> Stage {
    match e {
        IdentError::Observer(_) => Stage::Motion,
        IdentError::Spectra(_) => Stage::Spectra,
        IdentError::Factor(_) => Stage::Factorisation,
        _ => Stage::Identify,
    }
}

/// One analysis job's context.
pub(super) struct Analysis<'a> {
    pub run: RunId,
    pub generation: u64,
    pub send: &'a dyn Fn(Event),
}

impl Analysis<'_> {
    fn fail(&self, error: &IdentError) {
        (self.send)(Event::Failed {
            run: self.run,
            generation: self.generation,
            stage: stage_of(error),
            message: error.to_string(),
            kind: FailureKind::of(error.is_input_error()),
        });
    }

    /// Brings every stage of `cache` up to date with `settings`, sending each new result.
    pub fn analyse(&self, cache: &mut RunCache, settings: &Settings, stage: &mut Stage) {
        let (run, generation) = (self.run, self.generation);
        // The spectra shown are the identification's: on the segment used for this run.
        let settings = &settings.for_run(cache.session.run());
        *stage = Stage::Motion;
        if cache.motion.is_none() {
            match cache.session.motion() {
                Ok(estimate) => {
                    let m = Arc::new(stages::motion(&estimate, &cache.measured, cache.session.run()));
                    cache.motion = Some(m.clone());
                    (self.send)(Event::Motion {
                        run,
                        generation,
                        motion: m,
                    });
                }
                Err(e) => return self.fail(&e),
            }
        }
        *stage = Stage::Spectra;
        let same = |s: &&Arc<Spectra>| s.welch == settings.welch && cache.spectra_span == settings.span_s;
        let spectra = match cache.spectra.as_ref().filter(same) {
            Some(s) => s.clone(),
            None => match cache.session.spectra(settings, &cache.summary.blocks) {
                Ok(core) => {
                    let s = Arc::new(stages::spectra(core, &settings.welch));
                    cache.spectra = Some(s.clone());
                    cache.spectra_span = settings.span_s;
                    s
                }
                Err(e) => return self.fail(&e),
            },
        };
        (self.send)(Event::Spectra {
            run,
            generation,
            spectra,
        });
        *stage = Stage::Identify;
        let result = cache.session.identify(settings, Start::Warm, &mut |step| {
            if step.stage == "factorisation" {
                *stage = Stage::Factorisation;
            } else if step.stage == "fit" {
                *stage = Stage::Identify;
            }
        });
        match result {
            Ok(core) => self.identified(cache, &core),
            Err(e) => self.fail(&e),
        }
    }

    /// Sends the identification `core` (the display snapshot kept when it is the same), its
    /// model extended by the accepted effects.
    fn identified(&self, cache: &mut RunCache, core: &Arc<RunIdentification>) {
        let same = cache
            .identification
            .as_ref()
            .filter(|i| Arc::ptr_eq(&i.core, core) && i.accepted == cache.accepted)
            .cloned();
        let identification = if let Some(i) = same {
            i
        } else {
            let Some((settings, _)) = cache.session.identification() else {
                return;
            };
            let settings = settings.clone();
            let mut model = Model::from_identification(cache.session.run(), &settings, core);
            // Tested on a settled identification only (a retune's is shown at once, and its
            // settled refit follows within the second: `polish`), once per identification, as
            // `identify` tests it (a block extended by accepted effects drops them:
            // `Model::set_effects`).
            if !core.provisional() {
                let found = match &cache.suspected {
                    Some((id, found)) if Arc::ptr_eq(id, core) => found.clone(),
                    _ => {
                        let found = suspicions(&model, &cache.session, &settings, core);
                        cache.suspected = Some((core.clone(), found.clone()));
                        found
                    }
                };
                attach(&mut model, found);
            }
            let prepared = if cache.accepted.is_empty() {
                None
            } else {
                let accepted = cache.accepted.clone();
                let cached = cache
                    .effect_prepared
                    .as_ref()
                    .filter(|(s, a, p)| {
                        *s == settings && *a == accepted && starts_match(p, &model, &accepted)
                    })
                    .map(|(_, _, p)| p.clone());
                let fresh = |cache: &mut RunCache| {
                    let p = Arc::new(prepare_for_effects(
                        &mut cache.session,
                        &settings,
                        &model,
                        &accepted,
                    )?);
                    cache.effect_prepared = Some((settings.clone(), accepted.clone(), p.clone()));
                    Ok::<_, DiagnoseError>(p)
                };
                match cached.map_or_else(|| fresh(cache), Ok) {
                    Ok(p) => Some(p),
                    Err(e) => {
                        return (self.send)(Event::Failed {
                            run: self.run,
                            generation: self.generation,
                            stage: Stage::Identify,
                            message: format!("the accepted effects cannot be added: {e}"),
                            kind: FailureKind::of(e.is_input_error()),
                        });
                    }
                }
            };
            let extension = prepared
                .as_deref()
                .map(|p| (p.as_slice(), cache.accepted.as_slice()));
            let geometry = AccelGeometry::of(cache.session.run());
            let i = Arc::new(Identification::extended(
                settings,
                core.clone(),
                model,
                extension,
                geometry,
            ));
            cache.identification = Some(i.clone());
            i
        };
        (self.send)(Event::Identified {
            run: self.run,
            generation: self.generation,
            identification,
        });
    }

    /// Redoes a provisional identification from scratch and sends it again, under the same
    /// generation. Nothing to do if the session's identification is not provisional.
    pub fn polish(&self, cache: &mut RunCache) {
        match cache.session.polish() {
            None => {}
            Some(Ok(core)) => self.identified(cache, &core),
            Some(Err(e)) => self.fail(&e),
        }
    }
}
