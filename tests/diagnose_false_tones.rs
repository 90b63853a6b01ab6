//! No false tones beside a real finding on a real stand. On `turbulent_cruise` seed 2 with the
//! stand's real imperfections (`--stand real`: the reference's 30 Hz band limit leaves the
//! lever-arm motion above it in the accelerometer's residual, nearly the same in every channel)
//! and one hidden accelerometer effect, the diagnosis named the effect and then a vibration tone
//! at 43-45 Hz that the run does not hold: the tone's evidence weighed the channels by the
//! inverse of their nearly collinear correlation with the wrong scales (`diagnose::tone`). The
//! truth (which effect was hidden) is known to this test only.

use crate::common::sim as sim_common;

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use sim_common::simulated_run;

#[test]
fn a_hidden_effect_on_a_real_stand_is_named_without_a_false_tone() {
    for (spec, effect) in [
        ("lever_arm_error:accel", Effect::LeverArmError),
        ("platform_resonance:accel", Effect::PlatformResonance),
    ] {
        let mut config = SimConfig::new(Regime::TurbulentCruise);
        config.seed = 2;
        config.duration_s = 120.0;
        config.rate_hz = 500.0;
        config.stand = StandImperfections::real();
        config.effects = vec![spec.parse().expect("effect spec")];
        let (_, run) = simulated_run(&config);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let names: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        assert!(names.contains(&(Block::Accel, effect)), "{spec}: {names:?}");
        assert!(
            names.iter().all(|(_, e)| *e != Effect::VibrationTone),
            "{spec}: a tone the run does not hold: {names:?}"
        );
    }
}

/// A stand's sine programme (the `simulate --sine` set of the campaigns: 2.3 Hz roll 3°, 2.36 Hz
/// yaw 2°, 7.2 Hz pitch 1°) on a cruise run: the accelerometer's residual keeps a line at 7.2 Hz
/// (a misfit of 4e-4 m/s² in an input of about 10 m/s² there), which was named a vibration tone
/// on seed 9401 (and significant but refused on four more runs). No tone is named at the inputs'
/// own lines: the search's limit lists them instead. A tone the sensor does hold, elsewhere, is
/// still named beside them.
#[test]
fn no_tone_is_named_at_a_sine_programme_s_lines_and_a_real_one_still_is() {
    for (seed, effects) in [(9401, vec![]), (9402, vec!["vibration_tone:accel"])] {
        let config = SimConfig {
            seed,
            duration_s: 120.0,
            sines: ["roll:2.3:3", "yaw:2.36:2", "pitch:7.2:1"]
                .iter()
                .map(|s| s.parse().expect("sine"))
                .collect(),
            effects: effects.iter().map(|e| e.parse().expect("effect")).collect(),
            ..SimConfig::new(Regime::Cruise)
        };
        let (_, run) = simulated_run(&config);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let tones: Vec<f64> = report
            .findings
            .iter()
            .filter(|f| f.effect == Effect::VibrationTone)
            .filter_map(|f| f.parameters["frequency_hz"].as_f64())
            .collect();
        eprintln!("seed {seed}: tones at {tones:?}");
        assert!(
            tones
                .iter()
                .all(|f| [2.3, 2.36, 7.2].iter().all(|p| (f - p).abs() > 0.5)),
            "seed {seed}: a tone at the programme's lines: {tones:?}"
        );
        if !effects.is_empty() {
            assert_eq!(tones.len(), 1, "seed {seed}: the accelerometer's tone: {tones:?}");
        }
        let limit = report.blocks["accel"].tone_limit.as_ref().expect("a tone limit");
        assert!(
            limit.input_lines_hz.iter().any(|f| (f - 7.2).abs() < 0.02),
            "seed {seed}: {:?}",
            limit.input_lines_hz
        );
        assert!(
            limit.words(Block::Accel).contains("inputs' own lines"),
            "{}",
            limit.words(Block::Accel)
        );
    }
}
