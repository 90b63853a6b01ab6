//! The benchmark's input when no run is given: a simulated run of the requested size written to a
//! temporary CSV (with its sidecar), both removed when the [`TempRun`] is dropped.

use std::path::{Path, PathBuf};

use super::BenchError;
use crate::sim::regime::Regime;
use crate::sim::write::write_run_with_progress;
use crate::sim::{SimConfig, simulate};

/// Regime of the simulated benchmark run.
pub const BENCH_REGIME: Regime = Regime::Cruise;

/// A simulated run in the temporary folder, deleted on drop.
#[derive(Debug)]
pub struct TempRun {
    csv: PathBuf,
}

impl TempRun {
    /// Simulates `minutes` of [`BENCH_REGIME`] at `rate_hz` (both blocks, seed 1) and writes it to
    /// a uniquely named CSV in [`std::env::temp_dir`]; `progress(rows_written, rows_total)` is
    /// called as the rows are written.
    ///
    /// # Errors
    /// [`BenchError::Simulate`] for a size the simulator refuses, [`BenchError::Write`] when the
    /// temporary folder cannot be written.
    pub fn simulate(
        minutes: f64,
        rate_hz: f64,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Self, BenchError> {
        let mut config = SimConfig::new(BENCH_REGIME);
        config.duration_s = minutes * 60.0;
        config.rate_hz = rate_hz;
        let run = simulate(&config)?;
        let temp = Self::unwritten();
        write_run_with_progress(&run, &temp.csv, progress)?;
        Ok(temp)
    }

    /// A unique CSV path in [`std::env::temp_dir`] with nothing written there yet, for a run
    /// written by another process (`imu-attest bench` simulates in a child process, so that the
    /// simulation's memory does not count in the benchmark's peak). Whatever is written there and
    /// to its sidecar is removed on drop.
    #[must_use]
    pub fn unwritten() -> Self {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let csv = std::env::temp_dir().join(format!("imu-attest-bench-{}-{nanos}.csv", std::process::id()));
        Self { csv }
    }

    /// The CSV's path.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.csv
    }
}

impl Drop for TempRun {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.csv);
        let _ = std::fs::remove_file(crate::run::sidecar_path(&self.csv));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_run_is_written_and_removed() {
        let mut calls = 0;
        let temp = TempRun::simulate(0.05, 200.0, &mut |_, _| calls += 1).unwrap();
        let (csv, json) = (temp.path().to_owned(), crate::run::sidecar_path(temp.path()));
        assert!(csv.is_file() && json.is_file());
        assert!(calls > 0);
        let run = crate::run::load(&csv, &crate::run::LoadOptions::default()).unwrap();
        assert_eq!(run.len(), 600);
        drop(temp);
        assert!(!csv.exists() && !json.exists());
    }
}
