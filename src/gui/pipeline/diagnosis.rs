//! The missing-effect diagnosis of a loaded run on the worker: the core's diagnosis on the run's
//! session, so the observer, spectra and factorisations the app already holds are used as they
//! are (only the order-0 fit over the diagnosis's band is new).

use super::analyse::RunCache;
use crate::block::Block;
use crate::diagnose::{DiagnoseError, DiagnoseOptions, Report, diagnose_session};
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
    diagnose_session(&mut cache.session, settings, &options)
}
