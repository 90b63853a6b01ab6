//! Issue 5's acceptance: runs simulated with one catalogue effect hidden (two or three regimes,
//! sizes from barely significant to large) are diagnosed with that effect first, on the right
//! block, its size within 25 % and the gap shrinking; clean runs give `no_missing_effect`; runs
//! with two hidden effects name both.
//!
//! Only this test reads what the simulator hid (`sim.sidecar.truth`, in memory); the workflow
//! sees the CSV and the sidecar's declared fields, as it would from a real stand.
#![expect(clippy::unwrap_used, reason = "tests")]

use crate::common::sim as sim_common;
use sim_common::simulated_run_of;

use imu_attest::diagnose::DiagnoseOptions;
use imu_attest::diagnose::{Report, Verdict, diagnose_run};
use imu_attest::ident::settings::Settings;
use imu_attest::run::Run;
use imu_attest::sim::SimulatedRun;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::truth::{BlockTruth, EffectTruth};
use serde_json::Value;

const DURATION_S: f64 = 120.0;

/// A simulated run with `effects` hidden, loaded from its CSV as a stand run would be.
fn simulated_run(regime: Regime, seed: u64, effects: &[&str]) -> (SimulatedRun, Run) {
    simulated_run_of(DURATION_S, regime, seed, effects)
}

fn diagnose(regime: Regime, seed: u64, effects: &[&str]) -> (SimulatedRun, Report) {
    diagnose_of(DURATION_S, regime, seed, effects)
}

fn diagnose_of(duration_s: f64, regime: Regime, seed: u64, effects: &[&str]) -> (SimulatedRun, Report) {
    let (sim, run) = simulated_run_of(duration_s, regime, seed, effects);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).unwrap();
    (sim, report)
}

fn block_truth<'a>(sim: &'a SimulatedRun, block: &str) -> &'a BlockTruth {
    let t = &sim.sidecar.truth;
    if block == "gyro" {
        t.gyro.as_ref()
    } else {
        t.accel.as_ref()
    }
    .unwrap()
}

fn numbers(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(numbers).collect(),
        Value::Number(n) => vec![n.as_f64().unwrap()],
        _ => Vec::new(),
    }
}

/// `|est - truth| / |truth|` over vectors.
fn relative_error(est: &[f64], truth: &[f64]) -> f64 {
    let d: f64 = est.iter().zip(truth).map(|(a, b)| (a - b).powi(2)).sum();
    let n: f64 = truth.iter().map(|b| b * b).sum();
    (d / n).sqrt()
}

/// The relative size error of a finding against the hidden effect.
fn size_error(sim: &SimulatedRun, block: &str, p: &Value) -> f64 {
    let truth = block_truth(sim, block);
    let effect = truth.effects.first().unwrap();
    match effect {
        EffectTruth::GSensitivity { g_matrix } => relative_error(
            &numbers(&p["G"]),
            &g_matrix.iter().flatten().copied().collect::<Vec<_>>(),
        ),
        EffectTruth::SensorLag { time_constant_s } => {
            (p["T_s"].as_f64().unwrap() / time_constant_s - 1.0).abs()
        }
        EffectTruth::AxisTimeSkew { channel_delay_s } => {
            // Only differences between channels are identifiable (the common delay is tau).
            let est = numbers(&p["channel_delay_s"]);
            let diffs = |d: &[f64]| [d[1] - d[0], d[2] - d[0], d[2] - d[1]];
            relative_error(&diffs(&est), &diffs(channel_delay_s))
        }
        EffectTruth::ScaleNonlinearity { k2 } => relative_error(&numbers(&p["k2"]), k2),
        EffectTruth::VibrationTone {
            frequency_hz,
            amplitude,
            ..
        } => {
            let df = (p["frequency_hz"].as_f64().unwrap() - frequency_hz).abs() / frequency_hz;
            let norm = |a: &[f64]| a.iter().map(|v| v * v).sum::<f64>().sqrt();
            let da = (norm(&numbers(&p["amplitude"])) / norm(amplitude) - 1.0).abs();
            df.max(da)
        }
        EffectTruth::LeverArmError { offset_m } => relative_error(&numbers(&p["offset_m"]), offset_m),
        EffectTruth::PlatformResonance {
            axis,
            frequency_hz,
            damping,
        } => {
            assert_eq!(
                p["axis_index"].as_u64().unwrap() as usize,
                *axis,
                "resonance on the wrong axis"
            );
            let df = (p["frequency_hz"].as_f64().unwrap() / frequency_hz - 1.0).abs();
            let dz = (p["damping"].as_f64().unwrap() / damping - 1.0).abs();
            df.max(dz)
        }
        EffectTruth::ClockDrift { drift_ppm } => (p["drift_ppm"].as_f64().unwrap() / drift_ppm - 1.0).abs(),
    }
}

/// One effect on one block in three runs: barely significant, default and large.
fn check_effect(effect: &str, block: &str, cases: [(Regime, u64, f64); 3]) {
    check_effect_of(DURATION_S, effect, block, cases, 0.25);
}

/// [`check_effect`] on runs of `duration_s`, the size within `tolerance`.
fn check_effect_of(
    duration_s: f64,
    effect: &str,
    block: &str,
    cases: [(Regime, u64, f64); 3],
    tolerance: f64,
) {
    for (regime, seed, scale) in cases {
        let spec = format!("{effect}:{block}@{scale}");
        let (sim, report) = diagnose_of(duration_s, regime, seed, &[&spec]);
        let summary: Vec<String> = report
            .findings
            .iter()
            .map(|f| {
                format!(
                    "{} {} (gain {:.0}) {}",
                    f.block, f.effect, f.criterion_gain, f.parameters
                )
            })
            .collect();
        eprintln!("{regime} seed {seed} {spec}: {summary:?}");
        assert_eq!(
            report.verdict,
            Verdict::EffectFound,
            "{spec} on {regime}: nothing found"
        );
        let first = &report.findings[0];
        assert_eq!(
            (first.effect.id(), first.block.name()),
            (effect, block),
            "{spec} on {regime}: ranked first {summary:?}"
        );
        let err = size_error(&sim, block, &first.parameters);
        eprintln!(
            "  size error {:.1} %, criterion gain {:.0}, gap {:.2} -> {:.2} dB",
            err * 100.0,
            first.criterion_gain,
            first.gap_before_db,
            first.gap_after_db
        );
        assert!(
            err < tolerance,
            "{spec} on {regime}: size error {:.1} % ({})",
            err * 100.0,
            first.parameters
        );
        // The fit weights bins by the expected disturbance, the gap does not: for a barely
        // significant effect the unweighted gap may move by a few thousandths of a dB either way.
        let slack = if scale < 1.0 { 0.01 } else { 0.0 };
        assert!(
            first.gap_after_db < first.gap_before_db + slack,
            "{spec} on {regime}: gap {} -> {} dB",
            first.gap_before_db,
            first.gap_after_db
        );
    }
}

#[test]
fn g_sensitivity_is_named_and_sized() {
    check_effect(
        "g_sensitivity",
        "gyro",
        [
            (Regime::Approach, 31, 1.5),
            (Regime::TurbulentCruise, 32, 3.0),
            (Regime::Cruise, 33, 8.0),
        ],
    );
}

#[test]
fn sensor_lag_is_named_and_sized() {
    check_effect(
        "sensor_lag",
        "gyro",
        [
            (Regime::Approach, 41, 0.3),
            (Regime::Cruise, 42, 1.0),
            (Regime::TurbulentCruise, 43, 3.0),
        ],
    );
    check_effect(
        "sensor_lag",
        "accel",
        [
            (Regime::Cruise, 44, 0.3),
            (Regime::Approach, 45, 1.0),
            (Regime::Cruise, 46, 3.0),
        ],
    );
}

#[test]
fn axis_time_skew_is_named_and_sized() {
    check_effect(
        "axis_time_skew",
        "gyro",
        [
            (Regime::Cruise, 51, 0.1),
            (Regime::Approach, 52, 1.0),
            (Regime::TurbulentCruise, 53, 3.0),
        ],
    );
    check_effect(
        "axis_time_skew",
        "accel",
        [
            (Regime::Approach, 54, 0.2),
            (Regime::Cruise, 55, 1.0),
            (Regime::Approach, 56, 3.0),
        ],
    );
}

#[test]
fn scale_nonlinearity_is_named_and_sized() {
    check_effect(
        "scale_nonlinearity",
        "gyro",
        [
            (Regime::Approach, 61, 0.3),
            (Regime::Cruise, 62, 1.0),
            (Regime::TurbulentCruise, 63, 4.0),
        ],
    );
    check_effect(
        "scale_nonlinearity",
        "accel",
        [
            (Regime::Cruise, 64, 0.5),
            (Regime::Approach, 65, 1.0),
            (Regime::Cruise, 66, 4.0),
        ],
    );
}

#[test]
fn vibration_tone_is_named_and_sized() {
    check_effect(
        "vibration_tone",
        "gyro",
        [
            (Regime::Cruise, 71, 0.5),
            (Regime::Approach, 72, 1.0),
            (Regime::TurbulentCruise, 73, 5.0),
        ],
    );
    check_effect(
        "vibration_tone",
        "accel",
        [
            (Regime::Approach, 74, 2.0),
            (Regime::Cruise, 75, 3.0),
            (Regime::Approach, 76, 8.0),
        ],
    );
}

#[test]
fn lever_arm_error_is_named_and_sized() {
    check_effect(
        "lever_arm_error",
        "accel",
        [
            (Regime::Cruise, 81, 0.15),
            (Regime::Approach, 82, 1.0),
            (Regime::TurbulentCruise, 83, 3.0),
        ],
    );
}

#[test]
fn platform_resonance_is_named_and_sized() {
    check_effect(
        "platform_resonance",
        "gyro",
        [
            (Regime::Cruise, 91, 0.1),
            (Regime::Approach, 92, 1.0),
            (Regime::TurbulentCruise, 93, 2.0),
        ],
    );
    check_effect(
        "platform_resonance",
        "accel",
        [
            (Regime::Approach, 94, 0.1),
            (Regime::Cruise, 95, 1.0),
            (Regime::Approach, 96, 2.0),
        ],
    );
}

/// Issue 14: 20 to 200 ppm in 300 s runs (delay changes of 6 to 60 ms), either block, named
/// first and sized within 20 %.
#[test]
fn clock_drift_is_named_and_sized() {
    let duration_s = 300.0;
    check_effect_of(
        duration_s,
        "clock_drift",
        "gyro",
        [
            (Regime::Cruise, 141, 0.4),
            (Regime::Approach, 142, 1.0),
            (Regime::TurbulentCruise, 143, 4.0),
        ],
        0.2,
    );
    check_effect_of(
        duration_s,
        "clock_drift",
        "accel",
        [
            (Regime::Approach, 144, 0.4),
            (Regime::TurbulentCruise, 145, 1.0),
            (Regime::Cruise, 146, 4.0),
        ],
        0.2,
    );
}

/// A record too short to cut into stretches at the settings' segment has no drift hint (its
/// stationarity, if any, is from a few stretches of a shorter segment, too weak a test of the
/// drift): the search starts from zero drift and still finds it.
#[test]
fn clock_drift_is_found_without_stretches() {
    let (sim, run) = simulated_run_of(40.0, Regime::Approach, 147, &["clock_drift:gyro@3"]);
    let id = imu_attest::ident::identify::identify_run(&run, &Settings::default()).unwrap();
    assert!(
        id.blocks
            .iter()
            .all(|b| b.stationarity.as_ref().is_none_or(|st| st.segment_len.is_some())),
        "40 s was expected to be too short to cut at the settings' segment"
    );
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).unwrap();
    let first = report.findings.first().expect("a finding");
    assert_eq!((first.block.name(), first.effect.id()), ("gyro", "clock_drift"));
    let err = size_error(&sim, "gyro", &first.parameters);
    assert!(err < 0.2, "size error {err} ({})", first.parameters);
}

fn check_clean(runs: &[(Regime, u64)]) {
    for &(regime, seed) in runs {
        let (_, report) = diagnose(regime, seed, &[]);
        let gains: Vec<String> = report
            .blocks
            .iter()
            .map(|(b, r)| {
                let gain = r.candidates.first().map_or(0.0, |c| c.criterion_gain);
                format!("{b}: gain {gain:.1}, chi2/dof {:.3}", r.chi2_per_dof[0])
            })
            .collect();
        eprintln!("clean {regime} seed {seed}: best gains {gains:?}");
        assert_eq!(
            report.verdict,
            Verdict::NoMissingEffect,
            "clean {regime} seed {seed}: cried wolf: {:?}",
            report
                .findings
                .iter()
                .map(|f| (&f.block, &f.effect, f.criterion_gain))
                .collect::<Vec<_>>()
        );
        assert!(report.findings.is_empty());
        for (b, r) in &report.blocks {
            // The model explains the data: chi2 per degree of freedom near 1.
            assert!(
                (0.8..1.25).contains(&r.chi2_per_dof[0]),
                "{b}: chi2/dof {}",
                r.chi2_per_dof[0]
            );
        }
    }
}

#[test]
fn clean_runs_give_no_missing_effect_part_1() {
    check_clean(&[
        (Regime::Cruise, 101),
        (Regime::Approach, 102),
        (Regime::TurbulentCruise, 103),
        (Regime::Cruise, 104),
        (Regime::Approach, 105),
    ]);
}

#[test]
fn clean_runs_give_no_missing_effect_part_2() {
    check_clean(&[
        (Regime::TurbulentCruise, 106),
        (Regime::Cruise, 107),
        (Regime::Approach, 108),
        (Regime::TurbulentCruise, 109),
        (Regime::Cruise, 110),
    ]);
}

/// Regime, seed, the two `--effect` specs, the `(block, effect)` pairs to be named.
type TwoEffects = (Regime, u64, [&'static str; 2], [(&'static str, &'static str); 2]);

#[test]
fn two_hidden_effects_are_both_named() {
    let cases: [TwoEffects; 3] = [
        (
            Regime::Approach,
            121,
            ["sensor_lag:gyro", "platform_resonance:accel"],
            [("gyro", "sensor_lag"), ("accel", "platform_resonance")],
        ),
        (
            Regime::Cruise,
            122,
            ["g_sensitivity@4", "vibration_tone:gyro"],
            [("gyro", "g_sensitivity"), ("gyro", "vibration_tone")],
        ),
        (
            Regime::TurbulentCruise,
            123,
            ["lever_arm_error", "axis_time_skew:accel"],
            [("accel", "lever_arm_error"), ("accel", "axis_time_skew")],
        ),
    ];
    for (regime, seed, specs, expected) in cases {
        let (_, report) = diagnose(regime, seed, &specs);
        let found: Vec<(&str, &str)> = report
            .findings
            .iter()
            .map(|f| (f.block.name(), f.effect.id()))
            .collect();
        eprintln!("{regime} seed {seed} {specs:?}: {found:?}");
        for e in expected {
            assert!(
                found.contains(&e),
                "{specs:?} on {regime}: {e:?} not named in {found:?}"
            );
        }
        for f in &report.findings {
            assert!(f.gap_after_db <= f.gap_before_db, "{}: gap grew", f.effect);
        }
    }
}

#[test]
fn a_rejected_effect_is_not_named_again() {
    let (_, run) = simulated_run(Regime::Approach, 131, &["sensor_lag:gyro"]);
    let options = DiagnoseOptions {
        given: None,
        rejected: vec![(
            imu_attest::block::Block::Gyro,
            imu_attest::effect::Effect::SensorLag,
        )],
    };
    let report = diagnose_run(&run, &Settings::default(), &options).unwrap();
    let named: Vec<(&str, &str)> = report
        .findings
        .iter()
        .map(|f| (f.block.name(), f.effect.id()))
        .collect();
    assert!(!named.contains(&("gyro", "sensor_lag")), "{named:?}");
    // The lag is still there: something else must stand in for it, so the gyro is not clean.
    assert!(named.iter().any(|(b, _)| *b == "gyro"), "{named:?}");
}
