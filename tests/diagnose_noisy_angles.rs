//! Findings set aside where the angles are mostly their noise (`diagnose::noisy_angles`). Clean
//! 300 s runs with strong coloured angle noise (`simulate --coloured-angle-noise`, 5 Hz corner):
//! over 0.1-40 Hz the search named lags, reference lags and lever-arm errors the runs do not have
//! (measured 29 Nov before the check: approach seed 1 at 0.2 mrad a gyro `sensor_lag` and both
//! blocks' reference lags; cruise seed 5 at 0.1 mrad the accelerometer a lag of criterion gain
//! 176 and a lever-arm error). Each is now refitted on the band below the angles' noisy range and
//! not confirmed there: nothing is named, the report says what was set aside and from where the
//! angles are noise. True smooth effects beside the same noise are confirmed below and named.
//! Where the angles are clean but a block's coherence ends below the band's top, the same is
//! asked below that end (a false accelerometer lag set aside, a true lever arm named). The
//! diagnosis sees the loaded run only.

use imu_attest::block::Block;
use imu_attest::diagnose::noisy_angles::MIN_ANGLE_SNR;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;

use crate::common::sim as sim_common;

fn run_of(
    regime: Regime,
    seed: u64,
    duration_s: f64,
    stand: StandImperfections,
    effects: &[&str],
) -> imu_attest::run::Run {
    let mut config = SimConfig::new(regime);
    (config.seed, config.duration_s, config.rate_hz) = (seed, duration_s, 500.0);
    config.stand = stand;
    config.effects = effects.iter().map(|e| e.parse().expect("effect spec")).collect();
    sim_common::simulated_run(&config).1
}

fn coloured(rms: f64) -> StandImperfections {
    StandImperfections {
        coloured_noise_rad: rms,
        coloured_corner_hz: StandImperfections::real().coloured_corner_hz,
        ..StandImperfections::default()
    }
}

#[test]
fn smooth_misfits_of_the_angle_noise_model_are_set_aside_and_said() {
    for (regime, seed, rms) in [(Regime::Approach, 1_u64, 2e-4), (Regime::Cruise, 5, 1e-4)] {
        let run = run_of(regime, seed, 300.0, coloured(rms), &[]);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let case = format!("{regime:?} seed {seed} at {rms} rad");
        let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        assert!(named.is_empty(), "{case}: {named:?}");
        let mut set_aside = 0;
        for (name, b) in &report.blocks {
            let Some(noisy) = &b.noisy_angles else { continue };
            let angles = noisy.angles.expect("the angles' noisy range");
            // Where: the angles' SNR falls below pi for good at 17-20 Hz on these runs
            // (measured); one read too low would start the range inside the motion's band.
            assert!(
                noisy.unconfirmed.is_empty()
                    && (8.0..35.0).contains(&angles.from_hz)
                    && angles.snr < MIN_ANGLE_SNR,
                "{case}: {name}: {noisy:?}"
            );
            set_aside += noisy.set_aside.len();
            if !noisy.set_aside.is_empty() {
                let words = noisy.words(name).expect("words for what was set aside");
                assert!(
                    words.contains("mostly their noise") && words.contains(noisy.set_aside[0].id()),
                    "{words}"
                );
            }
        }
        assert!(
            set_aside > 0,
            "{case}: nothing set aside: the check did nothing here"
        );
    }
}

/// True smooth effects beside 0.1 mrad of coloured angle noise (cruise, 120 s): a gyro lag and an
/// accelerometer lever-arm error are confirmed on the band below the noisy range, named, and
/// neither set aside nor said unconfirmed (a helper's campaign, 29 Nov: 4 of 4 seeds each).
#[test]
fn true_smooth_effects_are_confirmed_below_and_named() {
    for (seed, effect, block, hidden) in [
        (21_u64, Effect::SensorLag, "gyro", "sensor_lag:gyro"),
        (22, Effect::LeverArmError, "accel", "lever_arm_error:accel"),
    ] {
        let run = run_of(Regime::Cruise, seed, 120.0, coloured(1e-4), &[hidden]);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let b = &report.blocks[block];
        let noisy = b.noisy_angles.as_ref().expect("the angles' noisy range");
        assert!(
            !noisy.set_aside.contains(&effect) && !noisy.unconfirmed.contains(&effect),
            "seed {seed}: {noisy:?}"
        );
        assert!(
            report
                .findings
                .iter()
                .any(|f| f.block.name() == block && f.effect == effect),
            "seed {seed}: {hidden} not named: {:?}",
            report
                .findings
                .iter()
                .map(|f| (f.block, f.effect))
                .collect::<Vec<_>>()
        );
    }
}

/// Where the angles have no noisy range but a block's outputs stop being coherent with its
/// inputs below the band's top, a smooth finding is confirmed below that end too. A clean
/// turbulent cruise run (120 s, 0.05 mrad of coloured noise, seed 14): the angles' SNR stays
/// above pi up to 40 Hz, the accelerometer's coherence ends near 36 Hz, and the search found a
/// lag over the band that rested on the last few hertz (measured 30 Nov: named before, on one of
/// the 209 campaign runs). It is set aside, in words that do not call the angles noise. (Since
/// 30 Nov the stand's band limit adds five candidates (six since its interpolated shape) and their look-elsewhere cost, and the lag
/// falls 0.6 short of the criterion: the band limit is rejected here, as an engineer may, to keep
/// the search's candidates those this case was measured with.) A true
/// lever-arm error on the default stand (cruise seed 21), where the accelerometer's coherence
/// ends near 39 Hz, is confirmed below and named.
#[test]
fn the_blocks_own_coherence_asks_confirmation_without_a_noisy_range() {
    let run = run_of(Regime::TurbulentCruise, 14, 120.0, coloured(5e-5), &[]);
    let without_band_limit = DiagnoseOptions {
        rejected: vec![
            (Block::Gyro, Effect::ReferenceBandLimit),
            (Block::Accel, Effect::ReferenceBandLimit),
        ],
        ..DiagnoseOptions::default()
    };
    let report = diagnose_run(&run, &Settings::default(), &without_band_limit).expect("diagnosed");
    let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
    assert!(named.is_empty(), "{named:?}");
    let noisy = report.blocks["accel"].noisy_angles.as_ref().expect("the range");
    assert!(
        noisy.angles.is_none()
            && noisy.usable_top_hz.is_some_and(|f| (20.0..40.0).contains(&f))
            && noisy.set_aside.contains(&Effect::SensorLag),
        "{noisy:?}"
    );
    let words = noisy.words("accel").expect("said");
    assert!(
        words.contains("coherent with its inputs only up to")
            && words.contains("signal-to-noise ratio stays above")
            && words.contains("sensor_lag"),
        "{words}"
    );

    let run = run_of(
        Regime::Cruise,
        21,
        120.0,
        StandImperfections::default(),
        &["lever_arm_error:accel"],
    );
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let noisy = report.blocks["accel"].noisy_angles.as_ref().expect("the range");
    assert!(
        noisy.angles.is_none()
            && noisy.usable_top_hz.is_some()
            && noisy.set_aside.is_empty()
            && noisy.unconfirmed.is_empty()
            && noisy.words("accel").is_none(),
        "{noisy:?}"
    );
    assert!(
        report
            .findings
            .iter()
            .any(|f| f.block.name() == "accel" && f.effect == Effect::LeverArmError),
        "{:?}",
        report
            .findings
            .iter()
            .map(|f| (f.block, f.effect))
            .collect::<Vec<_>>()
    );
}
