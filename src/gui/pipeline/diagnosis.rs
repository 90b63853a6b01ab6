//! The missing-effect diagnosis of a loaded run on the worker. The worker keeps a run as the
//! display stages split it; the diagnosis needs the [`Run`] itself, so it is put back together
//! from those columns (one copy, for the seconds the diagnosis takes).

use super::analyse::RunCache;
use crate::block::Block;
use crate::diagnose::{DiagnoseOptions, Report, diagnose_run};
use crate::effect::Effect;
use crate::ident::settings::Settings;
use crate::run::{Run, RunSource};

fn run_of(cache: &RunCache) -> Run {
    let m = &cache.measured;
    let s = &cache.summary;
    let columns = |series: &[super::Series; 3]| series.each_ref().map(|c| c.values.clone());
    let t0 = m.angles[0].t0;
    let dt = m.angles[0].dt;
    Run {
        source: RunSource {
            path: s.path.clone(),
            file_name: s.file_name.clone(),
            sha256: s.sha256.clone(),
            size_bytes: 0,
        },
        time_s: (0..s.n_samples).map(|k| t0 + k as f64 * dt).collect(),
        sample_rate_hz: s.sample_rate_hz,
        angles: columns(&m.angles),
        gyro: m.gyro.as_ref().map(columns),
        accel: m.accel.as_ref().map(columns),
        extra: Vec::new(),
        sidecar: cache.sidecar.clone(),
        notices: s.notices.clone(),
    }
}

/// Diagnoses the cached run.
///
/// # Errors
/// The diagnosis's error, as one line.
pub(super) fn diagnose(
    cache: &RunCache,
    settings: &Settings,
    rejected: &[(Block, Effect)],
) -> Result<Report, String> {
    let options = DiagnoseOptions {
        given: None,
        rejected: rejected.to_vec(),
    };
    diagnose_run(&run_of(cache), settings, &options).map_err(|e| e.to_string())
}
