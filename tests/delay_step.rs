//! A stream that slips (a logger losing or repeating one sample of the angles or of a block's
//! outputs) steps the delay by one sample period: the identification says the step, where it
//! lies and that it is not a clock drift, in place of the drift a line through it would read; the
//! diagnosis searches no clock drift through it and says so. Runs with the stand's real
//! imperfections, every regime, the slip hidden by `simulate --fault slip` (its time only in the
//! truth the test reads) and a real recording slipped here; clean and drifting runs have no step.

use crate::common::sim as sim_common;

use std::path::Path;

use imu_attest::block::Block;
use imu_attest::diagnose::report::Report;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::faults::Channel;
use imu_attest::ident::identify::{RunIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::run::{LoadOptions, Run, load};
use imu_attest::sim::fault::{FaultKind, FaultSpec, FaultTruth};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};

fn config(regime: Regime, seed: u64) -> SimConfig {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = 300.0;
    config.stand = StandImperfections::real();
    config
}

fn slipped(regime: Regime, seed: u64, channel: Channel) -> (SimulatedRun, Run) {
    let mut config = config(regime, seed);
    config.faults = vec![FaultSpec {
        kind: FaultKind::Slip,
        channel: Some(channel),
    }];
    sim_common::simulated_run(&config)
}

/// Each block's step warning (`[before_s, after_s, between_s..., samples]`) and whether it was
/// warned of a drift.
fn steps(id: &RunIdentification) -> Vec<(Block, Option<[f64; 5]>, bool)> {
    id.blocks
        .iter()
        .map(|b| {
            let step = b.warnings.iter().find_map(|w| match w {
                IdentWarning::DelayStep {
                    before_s,
                    after_s,
                    between_s,
                    samples,
                    ..
                } => Some([*before_s, *after_s, between_s[0], between_s[1], *samples]),
                _ => None,
            });
            let drift = b
                .warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::DelayDrift { .. }));
            (b.block, step, drift)
        })
        .collect()
}

#[test]
fn a_slipped_stream_is_a_step_of_one_sample_where_it_slipped() {
    let cases = [
        (Regime::Cruise, 11, Channel::Gx),
        (Regime::Approach, 12, Channel::Gx),
        (Regime::TurbulentCruise, 13, Channel::Gz),
        (Regime::Cruise, 14, Channel::Ax),
        (Regime::Approach, 15, Channel::Ay),
        (Regime::TurbulentCruise, 16, Channel::Roll),
        (Regime::Cruise, 17, Channel::Pitch),
    ];
    for (regime, seed, channel) in cases {
        let (sim, run) = slipped(regime, seed, channel);
        let FaultTruth::Slip { time_s, .. } = sim.sidecar.truth.faults[0] else {
            panic!("a slip was injected");
        };
        let at = time_s - run.time_s[0];
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for (block, step, drift) in steps(&id) {
            let what = format!(
                "{regime} seed {seed}, {} slipped at {at:.1} s: {block}",
                channel.name()
            );
            // The angles' slip moves both blocks' delays down; a block's own, its delay up.
            let expected = if channel.is_angle() {
                Some(-1.0)
            } else {
                let own = match channel {
                    Channel::Gx | Channel::Gy | Channel::Gz => Block::Gyro,
                    _ => Block::Accel,
                };
                (own == block).then_some(1.0)
            };
            match (expected, step) {
                (Some(samples), Some([before, after, from, to, found])) => {
                    eprintln!("{what}: {before:.6} -> {after:.6} s between {from:.1} and {to:.1} s");
                    assert!((found - samples).abs() < 0.1, "{what}: {found} samples");
                    assert!(
                        (from..=to).contains(&at),
                        "{what}: said between {from} and {to} s"
                    );
                    assert!(!drift, "{what}: a drift said too");
                }
                (None, None) => assert!(!drift, "{what}: a drift said"),
                (expected, found) => panic!("{what}: expected {expected:?}, found {found:?}"),
            }
        }
    }
}

#[test]
fn clean_and_drifting_runs_have_no_step() {
    for (k, regime) in Regime::ALL.into_iter().enumerate() {
        for seed in [21, 22] {
            let seed = seed + 10 * k as u64;
            let (_, run) = sim_common::simulated_run(&config(regime, seed));
            let id = identify_run(&run, &Settings::default()).expect("identified");
            for (block, step, drift) in steps(&id) {
                assert!(
                    step.is_none() && !drift,
                    "{regime} seed {seed} {block}: {step:?} {drift}"
                );
            }
        }
        let (_, run) = sim_common::simulated_run_of(300.0, regime, 41 + k as u64, &["clock_drift:gyro"]);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        let gyro = steps(&id)
            .into_iter()
            .find(|s| s.0 == Block::Gyro)
            .expect("a gyro");
        assert!(gyro.1.is_none() && gyro.2, "{regime}: a drift read as {gyro:?}");
    }
}

fn real(name: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    load(&path, &LoadOptions::default()).expect("the real run loads")
}

/// Writes `run`'s gyro one sample late from `share` of its length on; the slip's time, s from the
/// first sample.
fn slip_gyro(run: &mut Run, share: f64) -> f64 {
    let (n, at) = (run.len(), (run.len() as f64 * share) as usize);
    for c in run.gyro.as_mut().expect("a gyro").iter_mut() {
        c.copy_within(at - 1..n - 1, at);
    }
    run.time_s[at] - run.time_s[0]
}

/// Asserts that `run`'s gyro is identified with a step of one sample whose bracket holds `at`,
/// and no drift.
fn assert_one_sample_step(run: &Run, at: f64, what: &str) {
    let id = identify_run(run, &Settings::default()).expect("identified");
    let (_, step, drift) = steps(&id)[0];
    let [_, _, from, to, samples] = step.unwrap_or_else(|| panic!("{what}: no step"));
    assert!(
        (samples - 1.0).abs() < 0.1 && !drift,
        "{what}: {samples} samples, drift {drift}"
    );
    assert!(
        (from..=to).contains(&at),
        "{what}: {from}-{to} s, slipped at {at}"
    );
}

/// The fast real recording slipped at a quarter and at 70 % of its length (a version that
/// needed two stretches on each side missed both, and read the second as a drift).
#[test]
fn a_real_recording_slipped_off_its_middle_is_a_step_too() {
    for share in [0.25, 0.7] {
        let mut run = real("broad07_fast_rotation");
        let at = slip_gyro(&mut run, share);
        assert_one_sample_step(&run, at, &format!("slipped at {share}"));
    }
}

/// A real recording's gyro written one sample late from its middle on: identified with the
/// step (and no drift), diagnosed with no clock drift and the step in the report; the
/// recordings as they are have none.
#[test]
fn a_real_recording_slipped_by_one_sample_is_said_and_not_read_as_a_drift() {
    for name in [
        "broad07_fast_rotation",
        "broad11_slow_translation",
        "broad25_tapping",
    ] {
        let mut run = real(name);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        assert!(
            steps(&id).iter().all(|s| s.1.is_none()),
            "{name}: {:?}",
            steps(&id)
        );
        let at = slip_gyro(&mut run, 0.5);
        assert_one_sample_step(&run, at, name);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let gyro = &report.blocks["gyro"];
        let said = gyro
            .delay_step
            .unwrap_or_else(|| panic!("{name}: the report has no step"));
        assert!((said.samples - 1.0).abs() < 0.1, "{name}: {said:?}");
        assert!(
            report.findings.iter().all(|f| f.effect != Effect::ClockDrift),
            "{name}: {:?}",
            report.findings.iter().map(|f| f.effect).collect::<Vec<_>>()
        );
    }
}

/// The gyro slipped one sample late for the middle third of a 600 s run and back after it (a
/// logger losing a sample and later repeating one): the step and its return are said, each where
/// it happened, with the delay the run had before; the accelerometer is left alone. Before, the
/// model's delay came out between the two (4.89 ms for 4.3 and 6.3) and nothing was said.
#[test]
fn a_slip_that_comes_back_is_said_with_both_places() {
    for (regime, seed) in [(Regime::Cruise, 5), (Regime::TurbulentCruise, 6)] {
        let mut config = config(regime, seed);
        config.duration_s = 600.0;
        let mut sim = imu_attest::sim::simulate(&config).expect("simulated");
        let n = sim.time_s.len();
        let (out, back) = (n * 35 / 100, n * 65 / 100);
        for c in sim.gyro.as_mut().expect("a gyro").iter_mut() {
            let original = c.clone();
            c[out..back].copy_from_slice(&original[out - 1..back - 1]);
        }
        let dir = tempfile::tempdir().expect("temporary folder");
        let path = dir.path().join("run.csv");
        imu_attest::sim::write::write_run(&sim, &path).expect("written");
        let run = load(&path, &LoadOptions::default()).expect("loaded");
        let [at_out, at_back] = [out, back].map(|i| sim.time_s[i] - sim.time_s[0]);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            let step = b.warnings.iter().find_map(|w| match w {
                IdentWarning::DelayStep {
                    between_s,
                    back_between_s,
                    samples,
                    ..
                } => Some((*between_s, *back_between_s, *samples)),
                _ => None,
            });
            let what = format!("{regime} seed {seed} {}", b.block);
            if b.block == Block::Accel {
                assert!(step.is_none(), "{what}: {step:?}");
                continue;
            }
            let (between, back_between, samples) = step.unwrap_or_else(|| panic!("{what}: no step said"));
            let [from, to] = between;
            let [back_from, back_to] = back_between.unwrap_or_else(|| panic!("{what}: no return said"));
            eprintln!(
                "{what}: {samples:+.2} samples between {from:.1}-{to:.1} s and back {back_from:.1}-{back_to:.1} s"
            );
            assert!((samples - 1.0).abs() < 0.1, "{what}: {samples} samples");
            assert!(
                (from..=to).contains(&at_out),
                "{what}: out at {at_out} said {from}-{to}"
            );
            assert!(
                (back_from..=back_to).contains(&at_back),
                "{what}: back at {at_back} said {back_from}-{back_to}"
            );
            assert!(
                !b.warnings
                    .iter()
                    .any(|w| matches!(w, IdentWarning::DelayDrift { .. })),
                "{what}: a drift said"
            );
        }
    }
}

/// The diagnosis of a default-stand run of `duration_s` whose gyro stream slipped by one sample
/// (`simulate --fault slip`, the simulator's default channel), as the helper's campaign made them.
fn slipped_and_diagnosed(regime: Regime, seed: u64, duration_s: f64) -> Report {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = duration_s;
    config.faults = vec![FaultSpec {
        kind: FaultKind::Slip,
        channel: None,
    }];
    let (_, run) = sim_common::simulated_run(&config);
    diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed")
}

/// A lag the step makes (two delays averaged droop like a lag of up to half the step) is said to
/// be possibly the step's: a helper's campaign (30 Nov) had a gyro lag of 0.93-1.08 ms named on 3
/// of 3 runs of 180-300 s with one slipped sample at 500 Hz, the step found and not a word of it
/// in the lag's evidence. The campaign's cases, the gyro stream slipped. Every lag up to what the
/// step makes (1.2 times half the block's own step, the caveat's bound) must carry the words.
#[test]
fn a_lag_beside_a_step_of_the_delay_is_said_to_be_maybe_the_steps() {
    let mut said = 0;
    for (regime, seed, duration_s) in [
        (Regime::Cruise, 414, 180.0),
        (Regime::TurbulentCruise, 455, 300.0),
    ] {
        let report = slipped_and_diagnosed(regime, seed, duration_s);
        for f in &report.findings {
            let step = report.blocks[f.block.name()].delay_step.as_ref();
            eprintln!(
                "{regime} {seed}: {} {} {}; step {step:?}",
                f.block, f.effect, f.parameters
            );
            let is_lag = matches!(f.effect, Effect::SensorLag | Effect::ReferenceLag);
            let size = f.search_band.as_ref().map_or(&f.parameters, |s| &s["parameters"]);
            if is_lag && size["T_s"].as_f64().is_some_and(|t| t < 2.5e-3) {
                let Some(step) = step else {
                    panic!("{regime} {seed}: a lag without the step: {}", f.evidence)
                };
                let bound = 1.2 * (step.after_s - step.before_s).abs() / 2.0;
                if size["T_s"].as_f64().is_some_and(|t| t > bound) {
                    continue;
                }
                assert!(
                    f.evidence.contains("may be the step's"),
                    "{regime} {seed}: the lag beside a step without a word of it: {}",
                    f.evidence
                );
                said += 1;
            }
        }
    }
    // The premise: these runs' steps make a lag (should the search stop naming it, this test
    // has nothing left to check).
    assert!(said > 0, "no lag named beside the steps");
}

/// On a short record the stretches are too few to test for a step, and a slip reads as a clock
/// drift: the drift's evidence says a slip would read alike, with the stretches' delays (a
/// helper's campaign, 30 Nov: `clock_drift` on 5 of 5 runs of 60-120 s with one slipped sample,
/// nothing said). The campaign's 120 s and 60 s cases.
#[test]
fn a_drift_read_through_a_slip_on_a_short_record_says_a_slip_would_read_alike() {
    let mut drifts = 0;
    for (regime, seed, duration_s) in [(Regime::Cruise, 403, 120.0), (Regime::TurbulentCruise, 402, 60.0)] {
        let report = slipped_and_diagnosed(regime, seed, duration_s);
        for f in report.findings.iter().filter(|f| f.effect == Effect::ClockDrift) {
            eprintln!("{regime} {seed}: {} {}: {}", f.block, f.parameters, f.evidence);
            assert!(
                f.evidence.contains("too few to test for a step") && f.evidence.contains("their delays, ms"),
                "{regime} {seed}: a drift through a slip without a word of it: {}",
                f.evidence
            );
            drifts += 1;
        }
    }
    assert!(drifts > 0, "no drift named: the premise is gone");
    // A drifting clock over 300 s, enough stretches to test for a step: the drift alone.
    let (_, run) = sim_common::simulated_run_of(300.0, Regime::Cruise, 21, &["clock_drift:gyro"]);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let drift = report
        .findings
        .iter()
        .find(|f| f.effect == Effect::ClockDrift)
        .expect("the drift named");
    assert!(
        !drift.evidence.contains("too few to test"),
        "a long drifting record said untestable: {}",
        drift.evidence
    );
}
