//! A block the run cannot identify does not take the others with it: a simulated run whose
//! sidecar's accelerometer lever arm is lost (zero, as when the sidecar is missing) leaves that
//! block's vertical input flat. The gyro is identified as it would be alone; the accelerometer
//! is refused beside it, in every output that reports blocks (model, diagnosis, batch row,
//! certificate). A still stand axis, which takes every block's inputs with it, refuses the run.

use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::batch::table::{Cell, rows_of};
use imu_attest::block::Block;
use imu_attest::compare::compare;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_session};
use imu_attest::ident::IdentError;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::Model;
use imu_attest::model::refused::RefusalKind;
use imu_attest::report::spec::{self, Spec, Verdict};
use imu_attest::report::{render, run_report};
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;

/// A 60 s cruise run of `seed` with its accelerometer's lever arm lost.
fn without_lever_arm(seed: u64) -> Run {
    let (_, mut run) = sim_common::simulated_run_of(60.0, Regime::Cruise, seed, &[]);
    assert!(run.sidecar.accel_lever_arm_m.iter().any(|x| *x != 0.0));
    run.sidecar.accel_lever_arm_m = [0.0; 3];
    run
}

/// Asserts that the diagnosis of `run` diagnoses the gyro alone and names the accelerometer
/// refused for `kind`.
fn assert_diagnosed_beside(run: &Arc<Run>, settings: &Settings, kind: RefusalKind) {
    let report = diagnose_session(
        &mut Session::new(run.clone()),
        settings,
        &DiagnoseOptions::default(),
    )
    .expect("diagnosed");
    assert_eq!(report.blocks.keys().collect::<Vec<_>>(), ["gyro"]);
    assert_eq!(report.refused_blocks["accel"].kind, kind);
}

#[test]
fn the_gyro_is_identified_beside_a_refused_accelerometer() {
    for seed in [3, 4] {
        let run = without_lever_arm(seed);
        let id = identify_run(&run, &Settings::default()).unwrap();
        let blocks: Vec<Block> = id.blocks.iter().map(|b| b.block).collect();
        assert_eq!(blocks, [Block::Gyro], "seed {seed}");
        let [refusal] = id.refused.as_slice() else {
            panic!("seed {seed}: {:?}", id.refused)
        };
        assert_eq!(refusal.block, Block::Accel);
        let IdentError::NotExcited { axis, .. } = &refusal.error else {
            panic!("seed {seed}: {}", refusal.error)
        };
        assert_eq!(*axis, "fy", "the vertical input is the flat one");

        // Exactly the gyro's identification on its own.
        let alone = identify_run(
            &run,
            &Settings {
                blocks: vec![Block::Gyro],
                ..Settings::default()
            },
        )
        .unwrap();
        assert!(alone.refused.is_empty());
        let (a, b) = (&alone.blocks[0].structural, &id.blocks[0].structural);
        assert_eq!((a.k, a.tau_s, a.order), (b.k, b.tau_s, b.order), "seed {seed}");

        let model = Model::from_identification(&run, &Settings::default().for_run(&run), &id);
        assert_eq!(model.blocks.keys().collect::<Vec<_>>(), ["gyro"]);
        let entry = &model.refused_blocks["accel"];
        assert_eq!(entry.kind, RefusalKind::NotExcited);
        assert_eq!(entry.axis.as_deref(), Some("fy"));
        assert_eq!(entry.reason, refusal.error.to_string());
        // The file round-trips with the refusal.
        let back: Model = serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();
        assert_eq!(back.refused_blocks, model.refused_blocks);
    }
}

#[test]
fn the_diagnosis_batch_and_certificate_say_the_block_was_refused() {
    let run = Arc::new(without_lever_arm(3));
    let settings = Settings::default().for_run(&run);
    assert_diagnosed_beside(&run, &settings, RefusalKind::NotExcited);

    let page_of = |run: &Arc<Run>| {
        let r = run_report(&mut Session::new(run.clone()), &settings, None).unwrap();
        let rows = rows_of(&r.model, None);
        (render(&[r], None, "2026-11-27 00:00 UTC").0, rows)
    };
    let (page, rows) = page_of(&run);
    let status = |row: &imu_attest::batch::table::BatchRow, column: &str| match row.get(column) {
        Some(Cell::Text(t)) => t.clone(),
        other => panic!("{column}: {other:?}"),
    };
    let statuses: Vec<(String, String)> = rows
        .iter()
        .map(|r| (status(r, "block"), status(r, "status")))
        .collect();
    assert_eq!(
        statuses,
        [
            ("gyro".to_owned(), "ok".to_owned()),
            ("accel".to_owned(), "refused".to_owned())
        ]
    );
    assert!(status(&rows[1], "error").contains("axis fy not excited"));
    assert!(
        page.contains(
            "accel block not identified, the result holds the gyro block only: axis fy not excited"
        ),
        "the certificate says it"
    );
    // A specification's limits on the refused block are undecided, not skipped.
    let spec = Spec::parse(br#"{"gyro": {"tau_s": 0.1}, "accel": {"tau_s": 0.1}}"#, "s.json").unwrap();
    let r = run_report(&mut Session::new(run.clone()), &settings, None).unwrap();
    let checks = spec::check(&spec, &r.model);
    let accel: Vec<_> = checks.iter().filter(|c| c.block == Block::Accel).collect();
    assert_eq!(accel.len(), 1, "{checks:?}");
    assert_eq!(accel[0].verdict, Verdict::Undecided);
    assert_eq!(accel[0].element, "block not identified");

    // The same run with its lever arm: nothing refused anywhere.
    let (_, whole) = sim_common::simulated_run_of(60.0, Regime::Cruise, 3, &[]);
    let whole = Arc::new(whole);
    let (page, rows) = page_of(&whole);
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| status(r, "status") == "ok"));
    assert!(!page.contains("not identified"));

    // The two compared: the gyro in a pair, the accelerometer in none, and both say why.
    let w = run_report(&mut Session::new(whole), &settings, None).unwrap();
    let c = compare(&[w.model.clone(), r.model.clone()]).unwrap();
    assert!(!c.differences.is_empty() && c.differences.iter().all(|d| d.block == "gyro"));
    assert!(c.runs[1].refused_blocks.contains_key("accel") && c.runs[0].refused_blocks.is_empty());
    let page = render(&[w, r], None, "2026-11-27 00:00 UTC").0;
    assert!(page.contains(": the accel block was not identified (its run's section says why)."));
}

/// A specification's limits on a block the run does not hold are undecided, said as such: a
/// gyro-only run against a two-block specification printed "nothing checked" for the
/// accelerometer's limits.
#[test]
fn a_specification_s_block_the_run_lacks_is_undecided() {
    let mut config = imu_attest::sim::SimConfig::new(Regime::Cruise);
    config.seed = 9;
    config.duration_s = 60.0;
    config.blocks = vec![Block::Gyro];
    let (_, run) = sim_common::simulated_run(&config);
    let run = Arc::new(run);
    let settings = Settings::default().for_run(&run);
    let spec = Spec::parse(
        br#"{"accel": {"tau_s": 0.1, "scale_factor_error_ppm": 500}}"#,
        "s.json",
    )
    .unwrap();
    let r = run_report(&mut Session::new(run), &settings, None).unwrap();
    let checks = spec::check(&spec, &r.model);
    assert_eq!(checks.len(), 2, "{checks:?}");
    assert!(
        checks
            .iter()
            .all(|c| c.verdict == Verdict::Undecided && c.element == "block not in the model"),
        "{checks:?}"
    );
    assert_eq!(spec::summary(&checks), "2 undecided");
}

/// A stand axis held still is not one block's fault: the gyro's inputs are the stand's angular
/// motion, and the accelerometer fitted beside it had gains 50 % off. The run is refused.
#[test]
fn a_still_stand_axis_refuses_the_run() {
    let (_, mut run) = sim_common::simulated_run_of(60.0, Regime::Cruise, 21, &[]);
    let first = run.angles[0][0];
    run.angles[0].iter_mut().for_each(|a| *a = first);
    for blocks in [vec![Block::Gyro, Block::Accel], vec![Block::Gyro]] {
        let settings = Settings {
            blocks: blocks.clone(),
            ..Settings::default()
        };
        let err = identify_run(&run, &settings).unwrap_err();
        assert!(
            matches!(err, IdentError::NotExcited { block: "gyro", .. }),
            "{err}"
        );
        assert!(!err.is_refusal(), "a run-level refusal: {err}");
        // Leaving the gyro out would leave nothing right (or nothing at all).
        assert!(
            !err.to_string().contains("leave this block out"),
            "{blocks:?}: {err}"
        );
    }
}

/// A dead accelerometer (outputs noise alone) has no usable band: the diagnosis sets it aside as
/// the identification does, though it searches a fixed band, and diagnoses the gyro.
#[test]
fn the_diagnosis_refuses_the_block_the_model_refuses() {
    let (_, mut run) = sim_common::simulated_run_of(60.0, Regime::Cruise, 5, &[]);
    let mut rng = imu_attest::rng::Rng::new(9);
    for channel in run.accel.as_mut().unwrap() {
        for v in channel.iter_mut() {
            *v = 1e-3 * rng.normal();
        }
    }
    let run = Arc::new(run);
    let settings = Settings::default().for_run(&run);
    let id = identify_run(&run, &settings).unwrap();
    assert!(matches!(
        id.refused[0].error,
        IdentError::NoUsableBand { block: "accel", .. }
    ));
    assert_diagnosed_beside(&run, &settings, RefusalKind::NoUsableBand);
    // The dead accelerometer alone: nothing left to diagnose, refused as `identify` refuses it.
    let alone = Settings {
        blocks: vec![Block::Accel],
        ..settings
    };
    let err = diagnose_session(
        &mut Session::new(run.clone()),
        &alone,
        &DiagnoseOptions::default(),
    )
    .expect_err("nothing to diagnose");
    assert!(err.to_string().contains("accel block: no usable band"), "{err}");
    assert!(!err.to_string().contains("leave this block out"), "{err}");
}

/// Compared with its diagnoses, a run whose accelerometer was refused does not make the other
/// run's accelerometer findings "named on one run only": that block was not diagnosed there.
#[test]
fn a_refused_block_s_findings_are_not_compared() {
    let (_, whole) = sim_common::simulated_run_of(120.0, Regime::Cruise, 46, &["sensor_lag:accel@3"]);
    let mut lost = whole.clone();
    lost.sidecar.accel_lever_arm_m = [0.0; 3];
    let settings = Settings::default().for_run(&whole);
    let reports: Vec<_> = [whole, lost]
        .into_iter()
        .map(|run| run_report(&mut Session::new(Arc::new(run)), &settings, None).unwrap())
        .collect();
    let diagnosis = |i: usize| reports[i].diagnosis.as_ref().unwrap();
    assert!(
        diagnosis(0).findings.iter().any(|f| f.block == Block::Accel),
        "the lag is found where the accelerometer is identified"
    );
    assert!(diagnosis(1).refused_blocks.contains_key("accel"));
    let mut c = compare(&[reports[0].model.clone(), reports[1].model.clone()]).unwrap();
    c.add_findings(&[diagnosis(0), diagnosis(1)], &["a".to_owned(), "b".to_owned()]);
    let compared = c.findings.unwrap();
    assert!(compared.iter().all(|d| d.block == Block::Gyro), "{compared:?}");
}
