//! Issue 15: tones that come and go. A vibration tone switched on part-way through a run, or
//! pulsed (2 s on, 3 s off), anywhere from 8 to 45 Hz (inside the default band or above it), is
//! named on the right block with its frequency within 1 % and when it is on. Only this test
//! reads the simulated truth.

use imu_attest::diagnose::{DiagnoseOptions, Finding, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::Run;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::truth::ToneGate;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

fn gated_run(regime: Regime, seed: u64, effect: &str, frequency_hz: f64, gate: ToneGate) -> Run {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = 120.0;
    config.effects = vec![effect.parse().expect("effect")];
    config.tone.frequency_hz = Some(frequency_hz);
    config.tone.gate = gate;
    let sim = simulate(&config).expect("simulated");
    let dir = tempfile::tempdir().expect("folder");
    let path = dir.path().join("run.csv");
    write_run(&sim, &path).expect("written");
    load(&path, &LoadOptions::default()).expect("loaded")
}

fn tone_finding(run: &Run, block: &str) -> Finding {
    let report = diagnose_run(run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let found: Vec<_> = report
        .findings
        .iter()
        .map(|f| (f.name.clone(), f.criterion_gain))
        .collect();
    report
        .findings
        .into_iter()
        .find(|f| f.effect == Effect::VibrationTone && f.block.name() == block)
        .unwrap_or_else(|| panic!("no tone on the {block} block: {found:?}"))
}

fn stretches(f: &Finding) -> Vec<[f64; 2]> {
    serde_json::from_value(f.parameters["on_s"].clone()).expect("on_s")
}

fn check_frequency(f: &Finding, truth: f64) {
    let est = f.parameters["frequency_hz"].as_f64().expect("frequency");
    assert!((est - truth).abs() < 0.01 * truth, "{est} vs {truth}");
    let sd = f.parameter_std["frequency_hz"].as_f64().expect("its deviation");
    assert!(sd > 0.0 && sd < 0.01 * truth, "{sd}");
}

#[test]
fn a_pulsed_tone_is_named_with_its_frequency_and_its_pulses() {
    for (regime, seed, effect, block, f) in [
        (Regime::Cruise, 3, "vibration_tone:gyro", "gyro", 43.0),
        (
            Regime::TurbulentCruise,
            6,
            "vibration_tone:accel@4",
            "accel",
            25.0,
        ),
        (Regime::Approach, 4, "vibration_tone:accel", "accel", 8.5),
    ] {
        let gate = ToneGate::Pulsed {
            on_s: 2.0,
            off_s: 3.0,
        };
        let finding = tone_finding(&gated_run(regime, seed, effect, f, gate), block);
        check_frequency(&finding, f);
        let on = finding.parameters["on_fraction"].as_f64().expect("on_fraction");
        assert!((on - 0.4).abs() < 0.06, "{f} Hz: on {on}");
        // Each stretch starts near a multiple of 5 s (the first may be cut by the record's start).
        let s = stretches(&finding);
        assert!((20..=28).contains(&s.len()), "{f} Hz: {} stretches", s.len());
        for [a, b] in s.iter().skip(1).take(s.len() - 2) {
            let phase = a.rem_euclid(5.0).min(5.0 - a.rem_euclid(5.0));
            assert!(phase < 0.5 && (b - a - 2.0).abs() < 0.6, "{f} Hz: [{a}, {b}]");
        }
    }
}

#[test]
fn a_tone_switched_on_part_way_is_named_with_when() {
    for (regime, seed, effect, block, f, start) in [
        (Regime::Approach, 5, "vibration_tone:gyro", "gyro", 8.0, 60.0),
        (Regime::Cruise, 7, "vibration_tone:accel@4", "accel", 45.0, 30.0),
        (
            Regime::TurbulentCruise,
            8,
            "vibration_tone:gyro",
            "gyro",
            33.0,
            45.0,
        ),
    ] {
        let gate = ToneGate::From { start_s: start };
        let finding = tone_finding(&gated_run(regime, seed, effect, f, gate), block);
        check_frequency(&finding, f);
        let s = stretches(&finding);
        assert_eq!(s.len(), 1, "{f} Hz: {s:?}");
        assert!(
            (s[0][0] - start).abs() < 1.5 && (s[0][1] - 120.0).abs() < 1e-9,
            "{f} Hz: {s:?}"
        );
        let on = finding.parameters["on_fraction"].as_f64().expect("on_fraction");
        assert!((on - (120.0 - start) / 120.0).abs() < 0.02, "{f} Hz: on {on}");
    }
}
