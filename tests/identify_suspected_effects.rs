//! Issue 13, never silently wrong: an effect the paper's model takes into `K` and the delay
//! without a misfit (a gyro's g-sensitivity, an accelerometer's lever-arm error) is said on the
//! identified model (`effect_suspected`, `imu_attest::diagnose::suspect`), and only there: not on
//! clean runs of a perfect or a real-like stand (large sine programmes among them), not for a
//! gyro's lag (a rival that the test fits first), not on a model that already says it misfits,
//! and not once the effect is accepted. The truth is read by this test alone.

use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::extended_model;
use imu_attest::diagnose::identified::identified_model;
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::suspicion::Suspicion;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::model::{BlockModel, Model};
use imu_attest::run::Run;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::sines::ProgramSine;
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

/// The effects `m` is suspected of.
fn suspected(m: &BlockModel) -> Vec<&Suspicion> {
    m.fit
        .warnings
        .iter()
        .filter_map(|w| match w {
            IdentWarning::EffectSuspected(s) => Some(s),
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
        assert_eq!(said[0].effect, Effect::GSensitivity);
        // The shift is of the whole-record refit of the paper's model, which stays within a
        // deviation of the identified delay it is added to here.
        let shift = said[0].delay_shift_s;
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

/// Simulates `config`, identifies it and asserts that no block is suspected of anything.
fn assert_nothing_suspected(config: &SimConfig, what: &str) {
    let (_, run) = simulated_run(config);
    let model = identify(run);
    for (name, block) in &model.blocks {
        assert!(
            suspected(block).is_empty(),
            "{what} {name}: {:?}",
            block.fit.warnings
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
        assert_nothing_suspected(&config, &format!("{regime:?} {seed}"));
    }
}

/// A perfect stand's programme with large sines (20 degrees of roll at 0.8 Hz, 10 of pitch at
/// 0.5 Hz): the model is right (delays within 1.1 deviations of the truth), but at the sines' lines
/// a g-sensitivity removed chi2 140-551 while the residual's power grew, and was said with the
/// delay "4.8-6.9 us earlier", 13-18 of its deviations (1 Dec, before the diagnosis's rule that
/// an effect must close the gap applied here too; this seed at 120 s: chi2 551, 94 needed).
#[test]
fn large_sines_on_a_clean_run_suspect_nothing() {
    for (seed, duration_s) in [(63, 120.0), (63, 240.0)] {
        let mut config = SimConfig::new(Regime::TurbulentCruise);
        config.seed = seed;
        config.duration_s = duration_s;
        config.sines = vec![
            ProgramSine {
                axis: 0,
                frequency_hz: 0.8,
                amplitude_rad: 20f64.to_radians(),
            },
            ProgramSine {
                axis: 2,
                frequency_hz: 0.5,
                amplitude_rad: 10f64.to_radians(),
            },
        ];
        assert_nothing_suspected(&config, &format!("{seed} {duration_s} s"));
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

/// A g-sensitivity beside a gyro lag that gains more: the lag is fitted first, the
/// g-sensitivity beside it still gains and is said with the lag named, and the shift it names
/// moves the order-1 model's delay towards the truth (+23 us off before, 1.2-2.5 of its
/// deviations on four such runs; within 1.2 after).
#[test]
fn a_g_sensitivity_beside_a_lag_is_said_with_the_lag_fitted_first() {
    let (sim, run) = simulated_run_of(
        120.0,
        Regime::Approach,
        52,
        &["g_sensitivity:gyro", "sensor_lag:gyro"],
    );
    let truth_tau = sim.sidecar.truth.gyro.as_ref().expect("gyro truth").tau_s;
    let model = identify(run);
    let gyro = &model.blocks["gyro"];
    let said = suspected(gyro);
    assert_eq!(said.len(), 1, "{:?}", gyro.fit.warnings);
    assert_eq!(
        (said[0].effect, said[0].beside),
        (Effect::GSensitivity, Some(Effect::SensorLag))
    );
    let shift = said[0].delay_shift_s;
    assert!(
        (gyro.tau_s + shift - truth_tau).abs() < (gyro.tau_s - truth_tau).abs(),
        "delay {} (truth {truth_tau}), shift {shift}",
        gyro.tau_s
    );
}

/// An accelerometer's lever arm a little off the sidecar's (a tenth of the catalogue's error):
/// the plain model's `K[ax][fz]` was 21-28 of its deviations off on four runs with no other
/// warning; now the lever-arm error is said, naming that element. At four tenths the model says
/// it does not explain the data, and is not tested (that warning already sends the reader to the
/// diagnosis).
#[test]
fn a_lever_arm_error_is_said_and_a_model_that_misfits_is_not_tested() {
    let (sim, run) = simulated_run_of(120.0, Regime::Cruise, 71, &["lever_arm_error:accel@0.1"]);
    let truth = sim.sidecar.truth.accel.as_ref().expect("accel truth");
    let model = identify(run);
    let accel = &model.blocks["accel"];
    let said = suspected(accel);
    assert_eq!(said.len(), 1, "{:?}", accel.fit.warnings);
    assert_eq!(said[0].effect, Effect::LeverArmError);
    // The gyro beside it witnessed the angle noise: no other reading to offer.
    assert!(!said[0].angle_noise_taken_white);
    let element = said[0].k_shift.as_ref().expect("K's deviations");
    let z = (accel.k[0][2] - truth.k[0][2]) / accel.fit.k_std[0][2].expect("deviation");
    assert!(z.abs() > 10.0, "K[ax][fz] {z} deviations off");
    assert_eq!((element.output.as_str(), element.input.as_str()), ("ax", "fz"));
    assert!(element.sigmas > 10.0, "{}", element.sigmas);

    let (_, run) = simulated_run_of(120.0, Regime::Approach, 71, &["lever_arm_error:accel@0.4"]);
    let accel = &identify(run).blocks["accel"];
    assert!(
        accel
            .fit
            .warnings
            .iter()
            .any(|w| matches!(w, IdentWarning::PoorFit { .. })),
        "{:?}",
        accel.fit.warnings
    );
    assert!(suspected(accel).is_empty());
}

/// Channel delays a little apart (0.3 of the catalogue's: 0.36 and 0.24 ms on two
/// accelerometer channels): the plain model's `K[ax][fz]` was 7.3 of its deviations off without
/// a word; now the channel delays are said, naming an element moved beyond 3 deviations.
#[test]
fn channel_delays_apart_are_said() {
    let (sim, run) = simulated_run_of(120.0, Regime::Cruise, 91, &["axis_time_skew:accel@0.3"]);
    let truth = sim.sidecar.truth.accel.as_ref().expect("accel truth");
    let model = identify(run);
    let accel = &model.blocks["accel"];
    let said = suspected(accel);
    assert_eq!(said.len(), 1, "{:?}", accel.fit.warnings);
    assert_eq!(said[0].effect, Effect::AxisTimeSkew);
    let element = said[0].k_shift.as_ref().expect("K's deviations");
    assert!(element.sigmas > 3.0, "{element:?}");
    let z = (accel.k[0][2] - truth.k[0][2]) / accel.fit.k_std[0][2].expect("deviation");
    assert!(z.abs() > 3.0, "K[ax][fz] {z} deviations off");
    assert!(suspected(&model.blocks["gyro"]).is_empty());
}

/// The three real recordings (a gyro triad against optical motion capture): nothing suspected
/// (their gyro's g-sensitivity removes chi2 11-24 in the diagnosis, far below the criterion).
#[test]
fn the_real_recordings_suspect_nothing() {
    for name in [
        "broad07_fast_rotation",
        "broad11_slow_translation",
        "broad25_tapping",
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/real")
            .join(format!("{name}.csv.gz"));
        let run = imu_attest::run::load(&path, &imu_attest::run::LoadOptions::default()).expect("loads");
        let gyro = &identify(run).blocks["gyro"];
        assert!(suspected(gyro).is_empty(), "{name}: {:?}", gyro.fit.warnings);
    }
}

/// An accelerometer alone on a real-like stand (coloured angle noise, no gyro to witness it):
/// the angle noise is taken white, the coloured part enters the inputs as motion where the motion
/// is weak and lowers the gain there, and the test of effects read that as a lever-arm error moving `K` by about 5 % (a campaign
/// on 1 Dec, the same seed with a gyro beside it said nothing). The suspicion now says that
/// reading too; the lever arm is the sidecar's (the run has no effect), so what the words offer
/// in its place is the cause.
#[test]
fn a_suspicion_under_a_white_angle_noise_says_the_coloured_noise_reads_so_too() {
    let mut config = SimConfig::new(Regime::Cruise);
    config.seed = 11;
    config.duration_s = 120.0;
    config.blocks = vec![Block::Accel];
    config.stand = StandImperfections::real();
    let (sim, run) = simulated_run(&config);
    assert!(
        sim.sidecar
            .truth
            .accel
            .as_ref()
            .expect("accel truth")
            .effects
            .is_empty()
    );
    let model = identify(run);
    let accel = &model.blocks["accel"];
    assert!(
        accel
            .fit
            .warnings
            .iter()
            .any(|w| matches!(w, IdentWarning::AngleNoiseColourUnknown { .. })),
        "{:?}",
        accel.fit.warnings
    );
    let said = suspected(accel);
    assert!(!said.is_empty(), "{:?}", accel.fit.warnings);
    for s in said {
        assert!(s.angle_noise_taken_white, "{s:?}");
        assert!(
            s.to_string()
                .contains("a coloured one enters the inputs as motion"),
            "{s}"
        );
    }
}
