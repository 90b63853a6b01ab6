//! The missing-effect diagnosis of a loaded run on the worker: the core's diagnosis on the run's
//! session, so the observer, spectra and factorisations the app already holds are used as they
//! are (only the order-0 fit over the diagnosis's band is new). The certificate is made the same
//! way.

use super::analyse::RunCache;
use crate::block::Block;
use crate::diagnose::{DiagnoseError, DiagnoseOptions, Report, diagnose_prepared};
use crate::effect::Effect;
use crate::ident::settings::Settings;

/// Diagnoses the cached run.
///
/// # Errors
/// The diagnosis's error.
pub(super) fn diagnose(
    cache: &mut RunCache,
    settings: &Settings,
    rejected: &[(Block, Effect)],
) -> Result<Report, DiagnoseError> {
    let options = DiagnoseOptions {
        given: None,
        rejected: rejected.to_vec(),
    };
    // A rerun after a rejection starts from the cached identification and whole-record fits.
    Ok(diagnose_prepared(&*cache.prepared(settings)?, &options))
}

/// Writes the cached run's model file to `path` with its noise terms (as `identify` does).
///
/// # Errors
/// The message, and whether it is the user's input.
pub(super) fn export_model(cache: &mut RunCache, path: &std::path::Path) -> Result<(), (String, bool)> {
    let model = model_with_noise(cache)?;
    model.write_file(path).map_err(|e| {
        let input = !matches!(e, crate::output::OutputError::NonFinite { .. });
        (e.to_string(), input)
    })
}

/// The cached run's current model with its noise terms (as `identify` writes it).
///
/// # Errors
/// The message, and whether it is the user's input.
pub(super) fn model_with_noise(cache: &mut RunCache) -> Result<crate::model::Model, (String, bool)> {
    let identification = cache
        .identification
        .clone()
        .ok_or_else(|| ("the run is not identified yet".to_owned(), true))?;
    let mut model = identification.model.clone();
    let settings = model.settings.clone();
    crate::noise::of_model::attach_noise(&mut model, &mut cache.session, &settings)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    Ok(model)
}

/// Writes the cached run's certificate to `path` (`crate::report`).
///
/// # Errors
/// The message, and whether it is the user's input (bad settings for the run, a path that
/// cannot be written) rather than our fault.
pub(super) fn report(
    cache: &mut RunCache,
    settings: &Settings,
    path: &std::path::Path,
) -> Result<(), (String, bool)> {
    let run = cache.session.run().clone();
    let settings = settings.for_run(&run);
    let report = crate::report::run_report(&mut cache.session, &settings, None)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    let (page, _) = crate::report::render(&[report], None, &crate::report::utc_now());
    crate::report::write_page(path, &page).map_err(|e| (e.to_string(), true))
}
