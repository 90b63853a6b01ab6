//! The worker's own tests: only the newest analysis per run survives a batch, a panicking job is
//! reported and the worker goes on, and retunes and rejections reuse the cached stages.

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
                generation,
                diagnosis,
                ..
            } => Some((generation, diagnosis)),
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
    let cold = crate::diagnose::diagnose_run(&run, &crate::ident::settings::Settings::default(), &options)
        .expect("diagnosed");
    assert_eq!(reports[1].1.report, cold);
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
