//! The worker's queue in `Manual` mode: queued diagnoses merge like identifications, and every
//! run's provisional identification is refitted (not only the last run's).

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use super::{Event, Job, JobKind, Worker, WorkerMode};
use crate::ident::settings::Settings;

fn load(worker: &mut Worker, run: u64, generation: u64) {
    worker.submit(Job {
        run,
        generation,
        kind: JobKind::Load {
            path: crate::gui::sample_run_path().expect("sample run"),
            cancel: Arc::new(AtomicBool::new(false)),
        },
    });
}

fn analyse(run: u64, generation: u64, settings: &Settings) -> Job {
    Job {
        run,
        generation,
        kind: JobKind::Analyse {
            settings: Box::new(settings.clone()),
            accepted: Vec::new(),
        },
    }
}

#[test]
fn two_queued_diagnoses_give_one_result_the_newest() {
    let mut worker = Worker::start(WorkerMode::Manual, Arc::new(|| {}));
    load(&mut worker, 1, 1);
    worker.run_queued();
    worker.events.try_iter().for_each(drop);
    for generation in [2, 3] {
        worker.submit(Job {
            run: 1,
            generation,
            kind: JobKind::Diagnose {
                settings: Box::new(Settings::default()),
                rejected: Vec::new(),
            },
        });
    }
    assert_eq!(
        worker.run_queued(),
        1,
        "the older diagnosis is dropped before it runs"
    );
    let diagnosed: Vec<u64> = worker
        .events
        .try_iter()
        .filter_map(|e| match e {
            Event::Diagnosed { generation, .. } => Some(generation),
            Event::Failed { message, .. } => panic!("{message}"),
            _ => None,
        })
        .collect();
    assert_eq!(diagnosed, vec![3]);
}

#[test]
fn a_welch_change_with_two_runs_refits_both_and_leaves_nothing_pending() {
    let mut worker = Worker::start(WorkerMode::Manual, Arc::new(|| {}));
    load(&mut worker, 1, 1);
    load(&mut worker, 2, 2);
    let first = Settings::default();
    worker.submit(analyse(1, 3, &first));
    worker.submit(analyse(2, 4, &first));
    worker.run_queued();
    worker.events.try_iter().for_each(drop);

    let rewelched = Settings {
        welch: crate::spectral::WelchSettings {
            overlap: 0.6,
            ..first.welch
        },
        ..first
    };
    worker.submit(analyse(1, 5, &rewelched));
    worker.submit(analyse(2, 6, &rewelched));
    worker.run_queued();
    let mut provisional = [0; 3];
    let mut settled = [0; 3];
    for e in worker.events.try_iter() {
        if let Event::Identified {
            run, identification, ..
        } = e
        {
            let slot = usize::try_from(run).expect("small id");
            if identification.provisional() {
                provisional[slot] += 1;
            } else {
                settled[slot] += 1;
            }
        }
    }
    assert_eq!(provisional[1..], [1, 1], "each run shows the fast result first");
    assert_eq!(settled[1..], [1, 1], "and each is refitted from scratch");
    // Nothing is left to refit: an idle worker stays idle.
    assert_eq!(worker.run_queued(), 0);
    assert_eq!(worker.events.try_iter().count(), 0);
}
