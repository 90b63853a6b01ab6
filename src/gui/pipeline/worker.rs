//! The worker: a named thread (or, for tests, the caller's thread) that owns the stage caches.

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::time::Duration;

use super::analyse::{Analysis, RunCache};
use super::stages;
use super::{Event, FailureKind, Job, JobKind, RunId, Stage};
use crate::ident::session::Session;
use crate::ident::settings::Settings;
use crate::run::{LoadError, LoadOptions, load_with_progress};

/// Called after every event so the UI wakes up (egui's `request_repaint`).
pub type Waker = Arc<dyn Fn() + Send + Sync>;

/// How jobs run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkerMode {
    /// On the `imu-attest-worker` thread (the app).
    Thread,
    /// Inside [`Worker::submit`], before it returns (tests: deterministic, no repaint loop).
    Synchronous,
    /// Queued until [`Worker::run_queued`] (tests that act while a job is pending, e.g. cancel
    /// a load from the UI).
    Manual,
}

/// Sends jobs and receives events.
pub struct Worker {
    jobs: Option<Sender<Job>>,
    inline: Option<Box<Pipeline>>,
    queued: Option<Vec<Job>>,
    /// Events from the worker, drained by the app's `logic`.
    pub events: Receiver<Event>,
}

impl Worker {
    /// Starts the worker with the default load options.
    #[must_use]
    pub fn start(mode: WorkerMode, waker: Waker) -> Self {
        Self::start_with(mode, waker, LoadOptions::default())
    }

    /// Starts the worker; runs load with `load` (memory limit, chunk size). If the thread cannot
    /// be spawned, falls back to synchronous mode.
    #[must_use]
    pub fn start_with(mode: WorkerMode, waker: Waker, load: LoadOptions) -> Self {
        let (event_tx, events) = channel();
        let inline = |events, pipeline, queued| Self {
            jobs: None,
            inline: Some(Box::new(pipeline)),
            queued,
            events,
        };
        match mode {
            WorkerMode::Thread => {
                let (job_tx, job_rx) = channel::<Job>();
                let spare = event_tx.clone();
                let pipeline = Pipeline::new(event_tx, waker, load.clone());
                let spawned = std::thread::Builder::new()
                    .name("imu-attest-worker".into())
                    .spawn(move || pipeline.serve(&job_rx));
                if spawned.is_ok() {
                    return Self {
                        jobs: Some(job_tx),
                        inline: None,
                        queued: None,
                        events,
                    };
                }
                // Spawning failed: the closure (and the pipeline) is gone; run inline instead.
                inline(events, Pipeline::new(spare, Arc::new(|| {}), load), None)
            }
            WorkerMode::Synchronous => inline(events, Pipeline::new(event_tx, waker, load), None),
            WorkerMode::Manual => inline(events, Pipeline::new(event_tx, waker, load), Some(Vec::new())),
        }
    }

    /// Queues a job (or runs it now in synchronous mode).
    pub fn submit(&mut self, job: Job) {
        if let Some(queued) = self.queued.as_mut() {
            queued.push(job);
        } else if let Some(pipeline) = self.inline.as_mut() {
            pipeline.run_caught(job);
            pipeline.polish_caught();
        } else if let Some(jobs) = &self.jobs {
            // A send fails only if the worker thread is gone; its panic was already reported.
            let _ = jobs.send(job);
        }
    }

    /// Runs the jobs queued in [`WorkerMode::Manual`], merged as the worker thread merges them
    /// (only the newest analysis and diagnosis per run), then refits what is provisional; returns
    /// how many jobs ran.
    pub fn run_queued(&mut self) -> usize {
        let jobs = newest_only(self.queued.as_mut().map(std::mem::take).unwrap_or_default());
        let n = jobs.len();
        if let Some(pipeline) = self.inline.as_mut() {
            for job in jobs {
                pipeline.run_caught(job);
            }
            pipeline.polish_caught();
        }
        n
    }
}

/// Every loaded run's session and display snapshots.
struct Pipeline {
    runs: HashMap<RunId, RunCache>,
    events: Sender<Event>,
    waker: Waker,
    load: LoadOptions,
    /// Per run, the generation of its latest analysis whose identification is provisional: each
    /// is refitted from scratch when the worker is idle.
    unpolished: HashMap<RunId, u64>,
}

/// How long the worker waits without a job before it refits a provisional identification from
/// scratch: a pause in a slider drag shorter than this does not start the slower refit.
const POLISH_AFTER: Duration = Duration::from_millis(150);

impl Pipeline {
    fn new(events: Sender<Event>, waker: Waker, load: LoadOptions) -> Self {
        Self {
            runs: HashMap::new(),
            events,
            waker,
            load,
            unpolished: HashMap::new(),
        }
    }
}

impl Pipeline {
    fn serve(mut self, jobs: &Receiver<Job>) {
        loop {
            let first = if self.unpolished.is_empty() {
                match jobs.recv() {
                    Ok(job) => job,
                    Err(_) => return,
                }
            } else {
                match jobs.recv_timeout(POLISH_AFTER) {
                    Ok(job) => job,
                    Err(RecvTimeoutError::Timeout) => {
                        self.polish_caught();
                        continue;
                    }
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            };
            let mut batch = vec![first];
            batch.extend(jobs.try_iter());
            for job in newest_only(batch) {
                self.run_caught(job);
            }
        }
    }

    /// Refits every provisional identification from scratch (a panic is reported like a job's).
    fn polish_caught(&mut self) {
        let mut pending: Vec<(RunId, u64)> = self.unpolished.drain().collect();
        pending.sort_by_key(|&(_, g)| g);
        for (run, generation) in pending {
            self.polish_one(run, generation);
        }
    }

    /// Refits one run's provisional identification from scratch.
    fn polish_one(&mut self, run: RunId, generation: u64) {
        let Pipeline {
            runs, events, waker, ..
        } = self;
        let send = |event: Event| {
            // The app is gone when this fails; nothing left to tell.
            let _ = events.send(event);
            waker();
        };
        let Some(cache) = runs.get_mut(&run) else { return };
        let analysis = Analysis {
            run,
            generation,
            send: &send,
        };
        if catch_unwind(AssertUnwindSafe(|| analysis.polish(cache))).is_err() {
            send(Event::Failed {
                run,
                generation,
                stage: Stage::Identify,
                message: "internal error (panic) while refitting the structural model".into(),
                kind: FailureKind::Internal,
            });
        }
    }

    fn send(&self, event: Event) {
        // The app is gone when this fails; nothing left to tell.
        let _ = self.events.send(event);
        (self.waker)();
    }

    fn run_caught(&mut self, job: Job) {
        let (run, generation) = (job.run, job.generation);
        let mut stage = Stage::Load;
        let outcome = catch_unwind(AssertUnwindSafe(|| self.run(job, &mut stage)));
        if let Err(payload) = outcome {
            let what = payload
                .downcast_ref::<&str>()
                .map(ToString::to_string)
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            self.send(Event::Failed {
                run,
                generation,
                stage,
                message: format!("internal error (panic) in the {} stage: {what}", stage.name()),
                kind: FailureKind::Internal,
            });
        }
    }

    fn run(&mut self, job: Job, stage: &mut Stage) {
        let (run, generation) = (job.run, job.generation);
        match job.kind {
            JobKind::Load { path, cancel } => self.load(run, generation, &path, &cancel),
            JobKind::Analyse { settings, accepted } => {
                if let Some(cache) = self.runs.get_mut(&run) {
                    cache.accepted = accepted;
                }
                self.analyse(run, generation, &settings, stage);
                // The identification of these settings (as used on the run: blocks and segment
                // resolved), if the job ended with one.
                let current = self.runs.get(&run).and_then(|c| {
                    let used = settings.for_run(c.session.run());
                    c.identification.as_ref().filter(|i| i.settings == used)
                });
                if current.is_some_and(|i| i.provisional()) {
                    self.unpolished.insert(run, generation);
                } else {
                    self.unpolished.remove(&run);
                }
            }
            JobKind::Diagnose { settings, rejected } => {
                *stage = Stage::Diagnose;
                let Some(cache) = self.runs.get_mut(&run) else {
                    return;
                };
                let event = match super::diagnosis::diagnose(cache, &settings, &rejected) {
                    Ok(report) => Event::Diagnosed {
                        run,
                        generation,
                        report: Arc::new(report),
                    },
                    Err(e) => Event::Failed {
                        run,
                        generation,
                        stage: Stage::Diagnose,
                        message: e.to_string(),
                        kind: FailureKind::of(e.is_input_error()),
                    },
                };
                self.send(event);
            }
            JobKind::Validate { settings, model, key } => {
                *stage = Stage::Validate;
                let model_file = self
                    .runs
                    .get(&key.model_run)
                    .map(|c| c.summary.file_name.clone())
                    .unwrap_or_default();
                let Some(cache) = self.runs.get_mut(&run) else {
                    return;
                };
                let event = match super::validation::validated(cache, &settings, &model, model_file, key) {
                    Ok(v) => Event::Validated {
                        run,
                        generation,
                        validation: Arc::new(v),
                    },
                    Err((message, input)) => Event::Failed {
                        run,
                        generation,
                        stage: Stage::Validate,
                        message,
                        kind: FailureKind::of(input),
                    },
                };
                self.send(event);
            }
            JobKind::ExportResults { runs, path } => {
                *stage = Stage::Export;
                let mut rows = Vec::new();
                for id in &runs {
                    let Some(cache) = self.runs.get_mut(id) else {
                        continue;
                    };
                    match super::diagnosis::model_with_noise(cache) {
                        Ok(model) => rows.extend(crate::batch::table::rows_of(&model, None)),
                        Err((message, _)) => {
                            let name = cache.session.run().source.file_name.clone();
                            rows.push(crate::batch::BatchRow::failed(&name, &message));
                        }
                    }
                }
                let event = match crate::batch::write_table(&path, &rows) {
                    Ok(()) => Event::Written {
                        run,
                        what: "results table",
                        path,
                    },
                    Err(e) => Event::Failed {
                        run,
                        generation,
                        stage: Stage::Export,
                        message: e.to_string(),
                        kind: FailureKind::Input,
                    },
                };
                self.send(event);
            }
            JobKind::Report { .. } | JobKind::ExportModel { .. } => {
                *stage = Stage::Export;
                let Some(cache) = self.runs.get_mut(&run) else {
                    return;
                };
                let (what, path, outcome) = match job.kind {
                    JobKind::Report { settings, path } => {
                        let outcome = super::diagnosis::report(cache, &settings, &path);
                        ("report", path, outcome)
                    }
                    JobKind::ExportModel { path } => {
                        let outcome = super::diagnosis::export_model(cache, &path);
                        ("model", path, outcome)
                    }
                    _ => return,
                };
                let event = match outcome {
                    Ok(()) => Event::Written { run, what, path },
                    Err((message, input)) => Event::Failed {
                        run,
                        generation,
                        stage: Stage::Export,
                        message,
                        kind: FailureKind::of(input),
                    },
                };
                self.send(event);
            }
            JobKind::Forget => {
                self.runs.remove(&run);
                self.unpolished.remove(&run);
            }
            JobKind::InjectPanic { stage: at } => {
                *stage = at;
                panic!("deliberate fault injected in the {} stage", at.name());
            }
        }
    }

    fn load(&mut self, run: RunId, generation: u64, path: &Path, cancel: &AtomicBool) {
        let mut progress = |p: crate::run::LoadProgress| {
            if cancel.load(Ordering::Relaxed) {
                return ControlFlow::Break(());
            }
            let fraction = p.bytes_done as f32 / p.bytes_total.max(1) as f32;
            self.send(Event::Progress {
                run,
                fraction: fraction.clamp(0.0, 1.0),
            });
            ControlFlow::Continue(())
        };
        match load_with_progress(path, &self.load.clone(), &mut progress) {
            Ok(loaded) => {
                let loaded = Arc::new(loaded);
                let (summary, measured) = stages::split_run(&loaded);
                let (summary, measured) = (Arc::new(summary), Arc::new(measured));
                self.runs.insert(
                    run,
                    RunCache::new(summary.clone(), measured.clone(), Session::new(loaded)),
                );
                self.send(Event::Loaded {
                    run,
                    generation,
                    summary,
                    measured,
                });
            }
            Err(e) => self.send(Event::Failed {
                run,
                generation,
                stage: Stage::Load,
                kind: if matches!(e, LoadError::Cancelled) {
                    FailureKind::Cancelled
                } else {
                    FailureKind::Input
                },
                message: e.to_string(),
            }),
        }
    }

    fn analyse(&mut self, run: RunId, generation: u64, settings: &Settings, stage: &mut Stage) {
        let Pipeline {
            runs, events, waker, ..
        } = self;
        let send = |event: Event| {
            // The app is gone when this fails; nothing left to tell.
            let _ = events.send(event);
            waker();
        };
        let Some(cache) = runs.get_mut(&run) else { return };
        Analysis {
            run,
            generation,
            send: &send,
        }
        .analyse(cache, settings, stage);
    }
}

/// Keeps every load, report and forget job in order, and of the analysis jobs and of the diagnosis jobs
/// only the newest of each kind per run (a diagnosis takes seconds: one queued behind another is
/// stale before it starts).
fn newest_only(batch: Vec<Job>) -> Vec<Job> {
    let merged = |job: &Job| match job.kind {
        JobKind::Analyse { .. } => Some(0_u8),
        JobKind::Diagnose { .. } => Some(1),
        JobKind::Validate { .. } => Some(2),
        _ => None,
    };
    let mut newest: HashMap<(RunId, u8), u64> = HashMap::new();
    for job in &batch {
        if let Some(kind) = merged(job) {
            let g = newest.entry((job.run, kind)).or_insert(job.generation);
            *g = (*g).max(job.generation);
        }
    }
    batch
        .into_iter()
        .filter(|job| merged(job).is_none_or(|kind| newest.get(&(job.run, kind)) == Some(&job.generation)))
        .collect()
}

#[cfg(test)]
#[path = "worker_queue_tests.rs"]
mod queue_tests;

#[cfg(test)]
mod tests {
    use super::{Event, Job, JobKind, Stage, Worker, WorkerMode, newest_only};
    use std::sync::Arc;

    #[test]
    fn only_the_newest_analysis_per_run_survives() {
        let analyse = |run, generation| Job {
            run,
            generation,
            kind: JobKind::Analyse {
                settings: Box::default(),
                accepted: Vec::new(),
            },
        };
        let batch = vec![
            analyse(1, 1),
            Job {
                run: 2,
                generation: 2,
                kind: JobKind::Forget,
            },
            analyse(1, 3),
            analyse(3, 4),
        ];
        let kept: Vec<u64> = newest_only(batch).iter().map(|j| j.generation).collect();
        assert_eq!(kept, vec![2, 3, 4]);
    }

    #[test]
    fn a_panicking_job_is_reported_and_the_worker_goes_on() {
        let mut worker = Worker::start(WorkerMode::Synchronous, Arc::new(|| {}));
        worker.submit(Job {
            run: 1,
            generation: 1,
            kind: JobKind::InjectPanic { stage: Stage::Load },
        });
        let events: Vec<Event> = worker.events.try_iter().collect();
        let [
            Event::Failed {
                run: 1,
                generation: 1,
                stage: Stage::Load,
                message,
                kind: super::FailureKind::Internal,
            },
        ] = &events[..]
        else {
            panic!("{events:?}");
        };
        assert!(
            message.contains("panic") && message.contains("deliberate fault injected"),
            "{message}"
        );
        // Still serving: a job after the panic runs.
        worker.submit(Job {
            run: 2,
            generation: 2,
            kind: JobKind::Forget,
        });
        worker.submit(Job {
            run: 1,
            generation: 3,
            kind: JobKind::InjectPanic { stage: Stage::Load },
        });
        assert_eq!(worker.events.try_iter().count(), 1);
    }

    /// Job `kind` of run 1.
    fn job(generation: u64, kind: JobKind) -> Job {
        Job {
            run: 1,
            generation,
            kind,
        }
    }

    /// A synchronous worker with the sample run loaded as run 1 (generation 1), and its path.
    fn sample_loaded() -> (Worker, std::path::PathBuf) {
        let path = crate::gui::sample_run_path().expect("sample run");
        let mut worker = Worker::start(WorkerMode::Synchronous, Arc::new(|| {}));
        let cancel = Arc::new(std::sync::atomic::AtomicBool::new(false));
        worker.submit(job(
            1,
            JobKind::Load {
                path: path.clone(),
                cancel,
            },
        ));
        (worker, path)
    }

    #[test]
    fn a_rejection_rediagnoses_from_the_cached_fits() {
        use crate::block::Block;
        use crate::effect::Effect;

        let (mut worker, _) = sample_loaded();
        let diagnose = |rejected| JobKind::Diagnose {
            settings: Box::default(),
            rejected,
        };
        worker.submit(job(2, diagnose(Vec::new())));
        let prepared = |worker: &Worker| {
            let cache = &worker.inline.as_ref().expect("inline").runs[&1];
            cache.prepared.as_ref().expect("prepared").1.clone()
        };
        let first = prepared(&worker);
        worker.submit(job(3, diagnose(vec![(Block::Gyro, Effect::SensorLag)])));
        assert!(
            Arc::ptr_eq(&first, &prepared(&worker)),
            "the same identification and fits"
        );
        let reports: Vec<_> = worker
            .events
            .try_iter()
            .filter_map(|e| match e {
                Event::Diagnosed {
                    generation, report, ..
                } => Some((generation, report)),
                _ => None,
            })
            .collect();
        assert_eq!(reports.iter().map(|r| r.0).collect::<Vec<_>>(), vec![2, 3]);
        // And it is the diagnosis the core makes from scratch.
        let path = crate::gui::sample_run_path().expect("sample run");
        let run = crate::run::load(&path, &crate::run::LoadOptions::default()).expect("sample run");
        let options = crate::diagnose::DiagnoseOptions {
            given: None,
            rejected: vec![(Block::Gyro, Effect::SensorLag)],
        };
        let cold =
            crate::diagnose::diagnose_run(&run, &crate::ident::settings::Settings::default(), &options)
                .expect("diagnosed");
        assert_eq!(*reports[1].1, cold);
    }

    #[test]
    fn accepted_effects_stay_in_the_model_through_a_retune_and_its_refit() {
        use crate::block::Block;
        use crate::effect::Effect;
        use crate::ident::settings::{LambdaSetting, Settings};

        let (mut worker, _) = sample_loaded();
        let accepted = vec![(Block::Gyro, Effect::SensorLag)];
        let analyse = |settings: &Settings| JobKind::Analyse {
            settings: Box::new(settings.clone()),
            accepted: accepted.clone(),
        };
        let first = Settings::default();
        worker.submit(job(2, analyse(&first)));
        let start = |worker: &Worker| {
            let cache = &worker.inline.as_ref().expect("inline").runs[&1];
            cache.effect_prepared.as_ref().expect("prepared").2.clone()
        };
        let before = start(&worker);
        let retuned = Settings {
            lambda: LambdaSetting::Values([0.05, 0.03, 0.02]),
            ..first
        };
        worker.submit(job(3, analyse(&retuned)));
        let shown: Vec<_> = worker
            .events
            .try_iter()
            .filter_map(|e| match e {
                Event::Identified { identification, .. } => Some(identification),
                _ => None,
            })
            .collect();
        assert!(shown.len() >= 2);
        for i in &shown {
            let gyro = i.block_model(Block::Gyro).expect("gyro");
            assert_eq!(
                gyro.effects.as_ref().expect("the lag stays").accepted[0].effect,
                Effect::SensorLag
            );
            assert!(i.block_model(Block::Accel).expect("accel").effects.is_none());
        }
        // The retune's settings differ: the effects' start is made again for them.
        assert!(!Arc::ptr_eq(&before, &start(&worker)));
    }

    #[test]
    fn a_retune_is_sent_at_once_then_refitted_from_scratch() {
        use crate::ident::identify::identify_run;
        use crate::ident::settings::{LambdaSetting, Settings};

        let (mut worker, path) = sample_loaded();
        let analyse = |settings: &Settings| JobKind::Analyse {
            settings: Box::new(settings.clone()),
            accepted: Vec::new(),
        };
        let identified = |worker: &Worker| -> Vec<(u64, Arc<super::super::Identification>)> {
            worker
                .events
                .try_iter()
                .filter_map(|e| match e {
                    Event::Identified {
                        generation,
                        identification,
                        ..
                    } => Some((generation, identification)),
                    _ => None,
                })
                .collect()
        };
        let first = Settings::default();
        worker.submit(job(2, analyse(&first)));
        let sent = identified(&worker);
        assert_eq!(sent.len(), 1, "a first fit is from scratch, sent once");
        assert!(!sent[0].1.provisional());

        let retuned = Settings {
            lambda: LambdaSetting::Values([0.05, 0.03, 0.02]),
            ..first
        };
        worker.submit(job(3, analyse(&retuned)));
        let sent = identified(&worker);
        assert_eq!(sent.len(), 2, "the refined fit, then the refit");
        assert!(sent.iter().all(|(g, _)| *g == 3));
        assert!(sent[0].1.provisional(), "refined from the previous fit");
        let polished = &sent[1].1;
        assert!(!polished.provisional());
        // The refit is what `identify` gives for these settings.
        let run = crate::run::load(&path, &crate::run::LoadOptions::default()).expect("sample run");
        let reference = identify_run(&run, &retuned).expect("identify");
        for (shown, cold) in polished.blocks().iter().zip(&reference.blocks) {
            assert_eq!(shown.block, cold.block);
            assert_eq!(*shown.structural, *cold.structural, "{:?}", shown.block);
        }

        // A Welch change: the factors start from the previous ones, then are redone from scratch.
        let rewelched = Settings {
            welch: crate::spectral::WelchSettings {
                overlap: 0.6,
                ..retuned.welch
            },
            ..retuned
        };
        worker.submit(job(4, analyse(&rewelched)));
        let sent = identified(&worker);
        assert_eq!(sent.len(), 2, "the provisional result, then the one from scratch");
        assert!(
            sent[0]
                .1
                .blocks()
                .iter()
                .all(|b| !b.factorisation.from_scratch_for(b.wiener.estimate))
        );
        assert!(sent[0].1.provisional());
        let polished = &sent[1].1;
        assert!(!polished.provisional());
        let reference = identify_run(&run, &rewelched).expect("identify");
        for (shown, cold) in polished.blocks().iter().zip(&reference.blocks) {
            assert_eq!(*shown.structural, *cold.structural, "{:?}", shown.block);
            assert_eq!(shown.factorisation.noise_factor, cold.factorisation.noise_factor);
        }
    }
}
