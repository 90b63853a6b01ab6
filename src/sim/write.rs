//! Writing a simulated run as a contract run: `RUN.csv` (or `RUN.csv.gz`, gzipped when the name
//! ends in `.gz`) plus the sidecar `RUN.json`, both atomically.
//!
//! Numbers are written with 7 significant digits (`%.6e`), far below every noise level of the
//! simulation; times with microsecond resolution.

use std::io::{self, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::SimulatedRun;
use crate::output::{OutputError, write_atomic};
use crate::run::sidecar_path;

/// Writes the CSV (gzipped if `path` ends in `.gz`) and its sidecar.
///
/// # Errors
/// [`OutputError`] when either file cannot be written; neither is then left half-written.
pub fn write_run(run: &SimulatedRun, path: &Path) -> Result<(), OutputError> {
    write_run_with_progress(run, path, &mut |_, _| {})
}

/// Rows written between two calls of [`write_run_with_progress`]'s `progress`.
pub const PROGRESS_ROWS: usize = 1 << 16;

/// [`write_run`], calling `progress(rows_written, rows_total)` every [`PROGRESS_ROWS`] rows and
/// once at the end.
///
/// # Errors
/// As [`write_run`].
pub fn write_run_with_progress(
    run: &SimulatedRun,
    path: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(), OutputError> {
    let gz = path.extension().is_some_and(|e| e == "gz");
    write_atomic(path, |w| {
        if gz {
            let mut enc = GzEncoder::new(w, Compression::best());
            write_csv(run, &mut enc, progress)?;
            enc.finish()?.flush()
        } else {
            write_csv(run, w, progress)
        }
    })?;
    let sidecar = sidecar_path(path);
    write_atomic(&sidecar, |w| {
        serde_json::to_writer_pretty(&mut *w, &run.sidecar).map_err(io::Error::other)?;
        w.write_all(b"\n")
    })
}

fn write_csv(
    run: &SimulatedRun,
    w: &mut impl Write,
    progress: &mut dyn FnMut(usize, usize),
) -> io::Result<()> {
    let mut header = vec!["t", "roll", "yaw", "pitch"];
    let mut cols: Vec<&[f64]> = run.angles.iter().map(Vec::as_slice).collect();
    if let Some(g) = &run.gyro {
        header.extend(["gx", "gy", "gz"]);
        cols.extend(g.iter().map(Vec::as_slice));
    }
    if let Some(a) = &run.accel {
        header.extend(["ax", "ay", "az"]);
        cols.extend(a.iter().map(Vec::as_slice));
    }
    writeln!(w, "{}", header.join(","))?;
    let mut line = String::with_capacity(16 * header.len());
    // No NaN or infinity ever reaches a run file: the write fails and nothing is left.
    if let Some((name, n)) = std::iter::once(("t", run.time_s.as_slice()))
        .chain(header[1..].iter().copied().zip(cols.iter().copied()))
        .find_map(|(name, c)| c.iter().position(|v| !v.is_finite()).map(|n| (name, n)))
    {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("column '{name}' row {n} is not a finite number"),
        ));
    }
    for (n, t) in run.time_s.iter().enumerate() {
        use std::fmt::Write as _;
        line.clear();
        let _ = write!(line, "{t:.6}");
        for c in &cols {
            let _ = write!(line, ",{:.6e}", c[n]);
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
        if (n + 1) % PROGRESS_ROWS == 0 {
            progress(n + 1, run.time_s.len());
        }
    }
    progress(run.time_s.len(), run.time_s.len());
    Ok(())
}
