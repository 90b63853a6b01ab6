//! The Validation tab's job on the worker: a model's prediction of the run's outputs
//! (`crate::model::validation`) over the settings' span, as plot-ready series.

use super::analyse::RunCache;
use super::{Series, Validated, ValidationKey};
use crate::ident::settings::Settings;
use crate::ident::signals::channel_names;
use crate::model::BlockModel;
use crate::model::validation::validate;

/// Predicts the cached run's outputs of `key.block` with `model`. `Err` with the message (and
/// whether the input is at fault) when the run has no such block, the span does not fit, or the
/// span is too short to keep anything.
pub(super) fn validated(
    cache: &mut RunCache,
    settings: &Settings,
    model: &BlockModel,
    model_file: String,
    key: ValidationKey,
) -> Result<Validated, (String, bool)> {
    let session = &mut cache.session;
    let signals = session
        .signals(key.block)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    let span = session
        .span(settings)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    let run = session.run();
    let rate = 1.0 / run.dt_s();
    let t0 = run.time_s.get(span.start).copied().unwrap_or(0.0);
    let v = validate(model, &signals, span, rate, t0).ok_or_else(|| {
        (
            format!(
                "the span is too short to compare the {} outputs with a prediction",
                key.block
            ),
            true,
        )
    })?;
    let names = channel_names(key.block).1;
    let (t0, dt) = (v.t0_s, v.dt_s);
    // The series take the prediction's columns (a 30-minute run's are 14 MB each).
    let mut columns = v.measured.into_iter().zip(v.predicted);
    let channels = names.map(|name| {
        let (measured, predicted) = columns.next().unwrap_or_default();
        let residual: Vec<f64> = measured.iter().zip(&predicted).map(|(y, p)| y - p).collect();
        [
            Series::new(format!("{name} measured"), t0, dt, measured),
            Series::new(format!("{name} predicted"), t0, dt, predicted),
            Series::new(format!("{name} residual"), t0, dt, residual),
        ]
    });
    Ok(Validated {
        key,
        model_file,
        band_hz: v.band_hz,
        fit_percent: v.fit_percent,
        channels,
    })
}
