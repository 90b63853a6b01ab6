//! Campaigns (`imu-attest batch`): many runs identified (and optionally diagnosed) in parallel
//! with at most [`MAX_DECODED`] runs decoded at once, one table row per run and block. A run that
//! cannot be loaded or identified gets its own row with the reason; the others go on.
//!
//! The numbers are those of `identify`'s model file for the same run and settings (the same
//! session, model and noise terms), rounded nowhere: the CSV writes shortest round-trip decimals.

pub mod table;

pub use table::{BatchRow, write_table};

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::diagnose::identified::identified_model;
use crate::diagnose::{DiagnoseOptions, diagnose_session};
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::run::{LoadOptions, load};

/// Runs decoded at once: each holds its columns, the observer's estimate and the spectra.
pub const MAX_DECODED: usize = 2;

/// Whether `path` is named like a run (`.csv`, `.csv.gz`, any case).
#[must_use]
pub fn is_run_file(path: &Path) -> bool {
    let ext = |p: &Path, e: &str| p.extension().is_some_and(|x| x.eq_ignore_ascii_case(e));
    ext(path, "csv") || (ext(path, "gz") && path.file_stem().is_some_and(|s| ext(Path::new(s), "csv")))
}

/// The run files of `dir` (`*.csv`, `*.csv.gz`), sorted by name.
///
/// # Errors
/// The directory cannot be read.
pub fn runs_in(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.is_file() && is_run_file(p))
        .collect();
    out.sort();
    Ok(out)
}

/// The rows of one run: identified under `settings` (its blocks resolved for the run), noise
/// attached, and diagnosed when `diagnose` is set. A failure is one row saying why.
#[must_use]
pub fn run_rows(path: &Path, settings: &Settings, diagnose: bool) -> Vec<BatchRow> {
    let file = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let run = match load(path, &LoadOptions::default()) {
        Ok(run) => Arc::new(run),
        Err(e) => return vec![BatchRow::failed(&file, &e.to_string())],
    };
    let settings = settings.for_run(&run);
    let mut session = Session::new(run);
    let model = match identified_model(&mut session, &settings, &mut |_| {}) {
        Ok(model) => model,
        Err(e) => return vec![BatchRow::failed(&file, &e.to_string())],
    };
    let verdict =
        diagnose.then(
            || match diagnose_session(&mut session, &settings, &DiagnoseOptions::default()) {
                Ok(report) => {
                    let names: Vec<&str> = report.findings.iter().map(|f| f.name.as_str()).collect();
                    if names.is_empty() {
                        "no_missing_effect".to_owned()
                    } else {
                        format!("effect_found: {}", names.join("; "))
                    }
                }
                Err(e) => format!("diagnosis failed: {e}"),
            },
        );
    table::rows_of(&model, verdict.as_deref())
}

/// Every run's rows, in the order of `paths`, computed by [`MAX_DECODED`] threads taking the
/// next run as they finish; `done(finished, total)` is called after each run.
#[must_use]
pub fn batch(
    paths: &[PathBuf],
    settings: &Settings,
    diagnose: bool,
    done: &(dyn Fn(usize, usize) + Sync),
) -> Vec<BatchRow> {
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Vec<BatchRow>>>> = Mutex::new(vec![None; paths.len()]);
    std::thread::scope(|scope| {
        for k in 0..MAX_DECODED.min(paths.len()) {
            let (next, finished, results) = (&next, &finished, &results);
            let _ = std::thread::Builder::new()
                .name(format!("imu-attest-batch-{k}"))
                .spawn_scoped(scope, move || {
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(path) = paths.get(i) else { break };
                        // A bug in one run's processing is that run's row, not the campaign's end.
                        let rows = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            run_rows(path, settings, diagnose)
                        }))
                        .unwrap_or_else(|_| {
                            vec![BatchRow::failed(
                                &path.display().to_string(),
                                "internal error (please report it): the processing panicked",
                            )]
                        });
                        if let Ok(mut r) = results.lock() {
                            r[i] = Some(rows);
                        }
                        done(finished.fetch_add(1, Ordering::Relaxed) + 1, paths.len());
                    }
                });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .zip(paths)
        .flat_map(|(rows, path)| {
            rows.unwrap_or_else(|| {
                vec![BatchRow::failed(
                    &path.display().to_string(),
                    "internal error: the run was not processed",
                )]
            })
        })
        .collect()
}
