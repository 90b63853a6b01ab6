//! The model file as `identify`, `batch` and `report` write it without accepted effects: the
//! paper's model identified from scratch, the effects it may take in without a misfit said
//! ([`super::suspect`]), its noise terms attached ([`crate::noise::of_model::attach_noise`]).
//! With accepted effects, [`super::extend::extended_model`] starts from [`bare_model`].

use crate::ident::IdentError;
use crate::ident::identify::IdentStep;
use crate::ident::session::{Session, Start};
use crate::ident::settings::Settings;
use crate::model::Model;
use crate::noise::of_model::attach_noise;

/// The model file of `session`'s run under `settings` as `identify` writes it without accepted
/// effects: identified from scratch (`progress` before each stage), its noise terms attached.
/// `batch` and `report` write it; `identify` goes through [`super::extend::extended_model`],
/// which with nothing accepted gives this file.
///
/// # Errors
/// The identification's errors.
pub fn identified_model(
    session: &mut Session,
    settings: &Settings,
    progress: &mut dyn FnMut(IdentStep),
) -> Result<Model, IdentError> {
    let mut model = bare_model(session, settings, progress)?;
    attach_noise(&mut model, session, settings)?;
    Ok(model)
}

/// [`identified_model`] before its noise terms are attached, with the effects the model may take
/// in without a misfit said ([`super::suspect`]).
///
/// # Errors
/// The identification's errors.
pub fn bare_model(
    session: &mut Session,
    settings: &Settings,
    progress: &mut dyn FnMut(IdentStep),
) -> Result<Model, IdentError> {
    let run = session.run().clone();
    let id = session.identify(settings, Start::Cold, progress)?;
    // The echo is the settings as used (a caller's unresolved ones would name another segment).
    let settings = settings.for_run(&run);
    let mut model = Model::from_identification(&run, &settings, &id);
    progress(IdentStep {
        block: None,
        stage: "effects suspected",
        done: 0,
        total: 1,
    });
    let found = super::suspect::suspicions(&model, session, &settings, &id);
    super::suspect::attach(&mut model, found);
    Ok(model)
}
