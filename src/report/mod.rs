//! The certificate: one self-contained HTML report of one or several runs of a unit
//! (`imu-attest report`, File > Export report in the app).
//!
//! Per run: the run and its sha256, regime and unit; the settings; per block the model (scale
//! factor errors in ppm and misalignments in mrad with their standard deviations, the delay,
//! poles where the order has them, why each order was kept or rejected), the Bode grid with the
//! band, the noise terms with the Allan plot and the channels' noise correlation, the
//! self-check warnings; the diagnosis's findings; the specification's verdicts. Several runs add
//! a comparison table. Built from the same model as `identify` writes (noise attached), so the
//! report and the model file never disagree.

pub mod html;
mod html_diagnosis;
pub mod spec;
pub mod svg;

use std::io::Write as _;
use std::path::Path;

use crate::diagnose::identified::identified_model;
use crate::diagnose::{DiagnoseError, DiagnoseOptions, Report as Diagnosis, diagnose_session};
use crate::ident::IdentError;
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::model::Model;
use crate::noise::of_model::attach_noise;
use crate::output::{OutputError, write_atomic};

/// What the report shows of one run.
#[derive(Clone, Debug)]
pub struct RunReport {
    /// The model (noise attached).
    pub model: Model,
    /// The unit under test, from the sidecar's notes if any.
    pub unit: Option<String>,
    /// Samples analysed.
    pub samples: usize,
    /// Their duration, s.
    pub duration_s: f64,
    /// The diagnosis, or why it could not be made.
    pub diagnosis: Result<Diagnosis, String>,
}

/// Identifies (or takes `given`, identified before from this run), attaches the noise figures
/// and diagnoses `session`'s run under `settings`.
///
/// # Errors
/// The identification's errors (the diagnosis's own are kept in the report).
pub fn run_report(
    session: &mut Session,
    settings: &Settings,
    given: Option<Model>,
) -> Result<RunReport, IdentError> {
    let run = session.run().clone();
    let model = if let Some(mut m) = given {
        let model_settings = m.settings.clone();
        attach_noise(&mut m, session, &model_settings)?;
        m
    } else {
        identified_model(session, settings, &mut |_| {})?
    };
    let model_settings = model.settings.clone();
    let span = session.span(&model_settings)?;
    let diagnosis = diagnose_session(session, &model_settings, &DiagnoseOptions::default())
        .map_err(|e: DiagnoseError| e.to_string());
    let duration_s = match (
        run.time_s.get(span.start),
        span.end.checked_sub(1).and_then(|i| run.time_s.get(i)),
    ) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    Ok(RunReport {
        model,
        unit: run.sidecar.notes.clone().filter(|n| !n.trim().is_empty()),
        samples: span.len(),
        duration_s,
        diagnosis,
    })
}

/// The page of `runs` with the checks of `spec` (if given), made at `generated_utc`.
#[must_use]
pub fn render(
    runs: &[RunReport],
    spec: Option<&spec::Spec>,
    generated_utc: &str,
) -> (String, Vec<spec::Check>) {
    let checks: Vec<spec::Check> = spec
        .map(|s| runs.iter().flat_map(|r| spec::check(s, &r.model)).collect())
        .unwrap_or_default();
    (html::page(runs, &checks, spec.is_some(), generated_utc), checks)
}

/// Writes the page atomically.
///
/// # Errors
/// [`write_atomic`]'s.
pub fn write_page(path: &Path, page: &str) -> Result<(), OutputError> {
    write_atomic(path, |w| w.write_all(page.as_bytes()))
}

/// The current time, `YYYY-MM-DD HH:MM UTC`.
#[must_use]
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_of(secs)
}

/// `YYYY-MM-DD HH:MM UTC` of a Unix time (Howard Hinnant's civil-from-days).
#[must_use]
pub fn utc_of(unix_s: u64) -> String {
    let days = i64::try_from(unix_s / 86_400).unwrap_or(0);
    let rem = unix_s % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn civil_dates_are_right() {
        assert_eq!(super::utc_of(0), "1970-01-01 00:00 UTC");
        // 2026-11-24 00:48 UTC.
        assert_eq!(super::utc_of(1_795_481_280), "2026-11-24 00:48 UTC");
        assert_eq!(super::utc_of(951_782_400), "2000-02-29 00:00 UTC");
    }
}
