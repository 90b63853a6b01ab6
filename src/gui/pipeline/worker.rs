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
                    Ok(diagnosis) => Event::Diagnosed {
                        run,
                        generation,
                        diagnosis: Arc::new(diagnosis),
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
#[path = "worker_tests.rs"]
mod tests;
