//! `imu-attest bench`: times the identifier's stages on one run (issue 6).
//!
//! A stage is a named closure in a list ([`Stage`]); [`time_stages`] runs the list in order on one
//! [`BenchState`], which carries each stage's result to the next, and reports the wall time of
//! each (the median of its repeats). The stages are listed in [`stages::standard_stages`].
//!
//! Without a run, [`input::TempRun`] simulates one of the requested size and writes it to a
//! temporary CSV that is removed afterwards.
//!
//! # Contracts
//! - **Units**: times in s, memory in MB (10^6 bytes), rates in Hz.
//! - **NaN**: every time reported is finite and non-negative; peak memory is `None` where
//!   `/proc/self/status` cannot be read (not Linux).
//! - **Empty input**: an empty stage list gives an empty report; a stage that needs an earlier
//!   stage's result that was not computed fails with [`BenchError::Missing`].

pub mod bare;
pub mod cpu;
pub mod input;
pub mod memory;
pub mod report;
pub mod stages;

use std::time::Instant;

pub use report::{BenchReport, CommandFigure, StageTime};
pub use stages::{BenchState, standard_stages};

use crate::ident::IdentError;
use crate::output::OutputError;
use crate::run::LoadError;
use crate::sim::SimError;
use crate::spectral::SpectralError;

/// Why a benchmark could not be run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The run to simulate was refused.
    #[error("simulating the benchmark run: {0}")]
    Simulate(#[from] SimError),
    /// The temporary run could not be written.
    #[error("writing the benchmark run: {0}")]
    Write(#[from] OutputError),
    /// The run could not be loaded.
    #[error("{0}")]
    Load(#[from] LoadError),
    /// An identification stage failed.
    #[error("{0}")]
    Ident(#[from] IdentError),
    /// The missing-effect diagnosis failed.
    #[error("diagnosis: {0}")]
    Diagnose(#[from] crate::diagnose::DiagnoseError),
    /// A spectral estimate failed.
    #[error("spectra: {0}")]
    Spectral(#[from] SpectralError),
    /// A stage ran before the stage whose result it needs.
    #[error("stage '{stage}' needs the result of stage '{needs}', which has not run")]
    Missing {
        /// The stage that failed.
        stage: &'static str,
        /// The stage it needs.
        needs: &'static str,
    },
}

/// The work a stage does on the shared state.
pub type StageFn<'a> = Box<dyn FnMut(&mut BenchState) -> Result<(), BenchError> + 'a>;

/// One named, timed step of the benchmark.
pub struct Stage<'a> {
    /// Its name in the table and in the JSON `stages_s` object.
    pub name: &'static str,
    /// How many times it runs; the median time is reported (at least 1).
    pub repeats: usize,
    /// Whether it runs once more, untimed, before the timed repeats: a retune follows an
    /// identification in the app, and the session's first retune is that identification.
    pub warm_up: bool,
    /// The work.
    pub run: StageFn<'a>,
}

impl<'a> Stage<'a> {
    /// A stage run once.
    pub fn once(name: &'static str, run: impl FnMut(&mut BenchState) -> Result<(), BenchError> + 'a) -> Self {
        Self {
            name,
            repeats: 1,
            warm_up: false,
            run: Box::new(run),
        }
    }

    /// A stage run `repeats` times, reported by its median time.
    pub fn repeated(
        name: &'static str,
        repeats: usize,
        run: impl FnMut(&mut BenchState) -> Result<(), BenchError> + 'a,
    ) -> Self {
        Self {
            name,
            repeats: repeats.max(1),
            warm_up: false,
            run: Box::new(run),
        }
    }

    /// This stage, run once untimed before its timed repeats.
    #[must_use]
    pub fn after_warm_up(self) -> Self {
        Self {
            warm_up: true,
            ..self
        }
    }
}

impl std::fmt::Debug for Stage<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stage")
            .field("name", &self.name)
            .field("repeats", &self.repeats)
            .field("warm_up", &self.warm_up)
            .finish_non_exhaustive()
    }
}

/// Runs `stages` in order on `state`, calling `on_stage` with each name before it starts.
///
/// # Errors
/// The first stage's error, which stops the benchmark.
pub fn time_stages(
    state: &mut BenchState,
    stages: Vec<Stage<'_>>,
    on_stage: &mut dyn FnMut(&'static str),
) -> Result<Vec<StageTime>, BenchError> {
    let mut times = Vec::with_capacity(stages.len());
    for mut stage in stages {
        on_stage(stage.name);
        if stage.warm_up {
            (stage.run)(state)?;
        }
        let mut samples = Vec::with_capacity(stage.repeats);
        let cpu_start = cpu::process_cpu_s();
        for _ in 0..stage.repeats {
            let start = Instant::now();
            (stage.run)(state)?;
            samples.push(start.elapsed().as_secs_f64());
        }
        let cpu_seconds = cpu_start
            .zip(cpu::process_cpu_s())
            .map(|(a, b)| (b - a).max(0.0) / stage.repeats as f64);
        times.push(StageTime {
            name: stage.name,
            seconds: median(&mut samples),
            repeats: stage.repeats,
            cpu_seconds,
        });
    }
    Ok(times)
}

/// Runs [`standard_stages`] on the run at `path` with `settings`, resetting the process's peak
/// memory first (see [`memory`]), and reports the times, the run's size and the peak memory of the
/// `load` stage and of all the stages. `on_stage` is called with each stage's name and the number
/// of stages before the stage starts.
///
/// # Errors
/// The first failing stage's error.
pub fn run_bench(
    path: &std::path::Path,
    settings: crate::ident::settings::Settings,
    on_stage: &mut dyn FnMut(&'static str, usize),
) -> Result<BenchReport, BenchError> {
    let mut state = BenchState::new(path.to_owned(), settings);
    let mut stages = standard_stages();
    let count = stages.len();
    let rest = stages.split_off(1);
    let mb = |b: u64| b as f64 / 1e6;
    // Where the peak cannot be reset it includes what ran before: the report says no more.
    let _ = memory::reset_peak_rss();
    let mut times = time_stages(&mut state, stages, &mut |n| on_stage(n, count))?;
    let load_peak_rss_mb = memory::peak_rss_bytes().map(mb);
    times.extend(time_stages(&mut state, rest, &mut |n| on_stage(n, count))?);
    let (samples, rate_hz, columns) = state.run().map_or((0, 0.0, 0), |r| {
        (
            r.len(),
            r.sample_rate_hz,
            4 + 3 * r.blocks().len() + r.extra.len(),
        )
    });
    Ok(BenchReport {
        samples,
        rate_hz,
        channels: state.channels(),
        // As used on the run (the load stage fits a segment left to the program to it).
        segment_len: state.settings.welch.segment_len,
        stages: times,
        peak_rss_mb: memory::peak_rss_bytes().map(mb),
        load_peak_rss_mb,
        decoded_mb: (samples * columns * 8) as f64 / 1e6,
        commands: Vec::new(),
    })
}

/// The median of `samples` (mean of the middle two for an even count); 0 when empty.
#[must_use]
pub fn median(samples: &mut [f64]) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    samples.sort_by(f64::total_cmp);
    let mid = samples.len() / 2;
    if samples.len().is_multiple_of(2) {
        0.5 * (samples[mid - 1] + samples[mid])
    } else {
        samples[mid]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert!((median(&mut [3.0, 1.0, 2.0]) - 2.0).abs() < 1e-15);
        assert!((median(&mut [4.0, 1.0, 3.0, 2.0]) - 2.5).abs() < 1e-15);
        assert!(median(&mut []).abs() < 1e-15);
    }

    #[test]
    fn stages_run_in_order_and_missing_results_are_named() {
        let mut state = BenchState::new(
            std::path::PathBuf::from("none.csv"),
            crate::ident::settings::Settings::default(),
        );
        let mut seen = Vec::new();
        let stages = vec![Stage::repeated("count", 3, |_| Ok(()))];
        let times = time_stages(&mut state, stages, &mut |n| seen.push(n)).unwrap();
        assert_eq!(seen, vec!["count"]);
        assert_eq!(times[0].repeats, 3);
        assert!(times[0].seconds >= 0.0);
        // A warm-up runs once more, untimed: four calls, three samples, the slow first call not
        // among them.
        let mut calls = 0;
        let slow_first = Stage::repeated("warmed", 3, |_| {
            calls += 1;
            if calls == 1 {
                std::thread::sleep(std::time::Duration::from_millis(300));
            }
            Ok(())
        })
        .after_warm_up();
        let warmed = time_stages(&mut state, vec![slow_first], &mut |_| {}).unwrap();
        assert_eq!((calls, warmed[0].repeats), (4, 3));
        assert!(warmed[0].seconds < 0.15, "{}", warmed[0].seconds);
        let err = time_stages(&mut state, standard_stages().split_off(1), &mut |_| {}).unwrap_err();
        assert!(
            matches!(
                err,
                BenchError::Missing {
                    stage: "observer",
                    needs: "load"
                }
            ),
            "{err}"
        );
    }

    /// The bench's session, after every stage (warm retunes, order changes, a Welch change and
    /// the diagnosis in between), identifies the run under the original settings from scratch
    /// exactly as a fresh `identify` does: the same model file, byte for byte.
    #[test]
    fn the_bench_session_gives_identify_s_model_file() {
        use crate::ident::session::Start;
        use crate::model::Model;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/approach.csv.gz");
        let settings = crate::ident::settings::Settings::default();
        let mut state = BenchState::new(path.clone(), settings.clone());
        time_stages(&mut state, standard_stages(), &mut |_| {}).unwrap();
        let session = state.session.as_mut().unwrap();
        let run = session.run().clone();
        let after = session.identify(&settings, Start::Cold, &mut |_| {}).unwrap();
        let fresh = crate::ident::identify::identify_run(&run, &settings).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let bytes = |id: &crate::ident::identify::RunIdentification, name: &str| {
            let file = dir.path().join(name);
            let resolved = settings.for_run(&run);
            Model::from_identification(&run, &resolved, id)
                .write_file(&file)
                .unwrap();
            std::fs::read(file).unwrap()
        };
        assert!(
            bytes(&after, "bench.json") == bytes(&fresh, "identify.json"),
            "the session's cold identification differs from identify's"
        );
    }
}
