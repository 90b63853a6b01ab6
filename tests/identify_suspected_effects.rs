//! Issue 13, never silently wrong: an effect the paper's model takes into `K` and the delay
//! without a misfit (a gyro's g-sensitivity) is said on the identified model
//! (`effect_suspected`, `imu_attest::diagnose::suspect`), and only there: not on clean runs of a
//! perfect or a real-like stand, not for a gyro's lag (a rival that the test fits first), and not
//! once the effect is accepted. The truth is read by this test alone.

#[path = "common/sim.rs"]
mod sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::extended_model;
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::model::{BlockModel, Model};
use imu_attest::noise::of_model::identified_model;
use imu_attest::run::Run;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use sim_common::{simulated_run, simulated_run_of};

fn identify(run: Run) -> Model {
    identified_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        &mut |_| {},
    )
    .expect("identified")
}

/// The effects `m` is suspected of, with the delay shift each names.
fn suspected(m: &BlockModel) -> Vec<(Effect, f64)> {
    m.fit
        .warnings
        .iter()
        .filter_map(|w| match w {
            IdentWarning::EffectSuspected {
                effect,
                delay_shift_s,
                ..
            } => Some((*effect, *delay_shift_s)),
            _ => None,
        })
        .collect()
}

/// The catalogue's g-sensitivity (about 0.26 deg/s per g at most, a MEMS gyro's) took the plain
/// model's delay 5-25 us early on these runs, 2.9-13.6 of its deviations, without a word (a
/// campaign on 1 Dec). Now it is said, and the delay's shift it names moves the delay towards
/// the truth; accepted, the effect is the model's and no longer suspected.
#[test]
fn a_g_sensitive_gyro_is_said_and_the_shift_it_names_is_towards_the_truth() {
    for (regime, seed) in [
        (Regime::Approach, 31),
        (Regime::Approach, 32),
        (Regime::Cruise, 31),
    ] {
        let (sim, run) = simulated_run_of(120.0, regime, seed, &["g_sensitivity:gyro"]);
        let truth_tau = sim.sidecar.truth.gyro.as_ref().expect("gyro truth").tau_s;
        let model = identify(run.clone());
        let gyro = &model.blocks["gyro"];
        let said = suspected(gyro);
        assert_eq!(said.len(), 1, "{regime:?} {seed}: {:?}", gyro.fit.warnings);
        let (effect, shift) = said[0];
        assert_eq!(effect, Effect::GSensitivity);
        let before = (gyro.tau_s - truth_tau).abs();
        let after = (gyro.tau_s + shift - truth_tau).abs();
        assert!(
            after < before,
            "{regime:?} {seed}: delay {} (truth {truth_tau}), shift {shift}",
            gyro.tau_s
        );
        // The accelerometer beside it holds nothing of the kind.
        assert!(suspected(&model.blocks["accel"]).is_empty());

        let extended = extended_model(
            &mut Session::new(Arc::new(run)),
            &Settings::default(),
            &[(Block::Gyro, Effect::GSensitivity)],
            &mut |_| {},
        )
        .expect("extended");
        assert!(
            suspected(&extended.blocks["gyro"]).is_empty(),
            "{regime:?} {seed}: accepted, yet {:?}",
            extended.blocks["gyro"].fit.warnings
        );
    }
}

/// Clean runs, of a perfect stand and of one with a real stand's imperfections (coloured,
/// band-limited angle noise, latency), in the three regimes: nothing suspected on either block.
#[test]
fn clean_runs_suspect_nothing() {
    let runs = [
        (Regime::Cruise, 8101, false),
        (Regime::Approach, 8102, true),
        (Regime::TurbulentCruise, 8103, true),
        (Regime::TurbulentCruise, 8104, false),
    ];
    for (regime, seed, real_stand) in runs {
        let mut config = SimConfig::new(regime);
        config.seed = seed;
        config.duration_s = 120.0;
        if real_stand {
            config.stand = StandImperfections::real();
        }
        let (_, run) = simulated_run(&config);
        let model = identify(run);
        for (name, block) in &model.blocks {
            assert!(
                suspected(block).is_empty(),
                "{regime:?} {seed} {name}: {:?}",
                block.fit.warnings
            );
        }
    }
}

/// A gyro's first-order lag gains more than a g-sensitivity fitted alone would: the lag is
/// fitted first, and beside it nothing is left for a g-sensitivity (without the rivals it was
/// suspected on every one of four such runs).
#[test]
fn a_lag_is_not_suspected_as_g_sensitivity() {
    for (regime, seed) in [(Regime::Approach, 31), (Regime::Cruise, 32)] {
        let (_, run) = simulated_run_of(120.0, regime, seed, &["sensor_lag:gyro"]);
        let model = identify(run);
        let gyro = &model.blocks["gyro"];
        assert!(
            suspected(gyro).is_empty(),
            "{regime:?} {seed}: {:?}",
            gyro.fit.warnings
        );
    }
}
