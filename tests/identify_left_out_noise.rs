//! The angle noise the observer's model left out (`ident::left_out_noise`): where the gyro
//! leaves less than a thousandth of the angles' power unexplained, the model keeps the white
//! floor, and on a real stand's coloured angle noise the gains read low by up to that share
//! (the gyro's own noise may as well be what is left, so it is not corrected for): the shift is
//! in the model file and, as a uniform spread, in the deviations of the gyro and of the
//! accelerometer beside it. Long records are where
//! it tells: on 30-minute turbulent cruise runs of `--stand real` before it, the gyro's `K` read
//! 4e-4 to 8e-4 off in a fixed pattern, its normalised errors rms 1.6-2.3 (README, *Long runs*).
//! The truth is read here only.

use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::identified::identified_model;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::Model;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};

fn real_stand(
    regime: Regime,
    seed: u64,
    duration_s: f64,
    rate_hz: f64,
    blocks: &[Block],
) -> (SimulatedRun, Model) {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = duration_s;
    config.rate_hz = rate_hz;
    config.blocks = blocks.to_vec();
    config.stand = StandImperfections::real();
    let (sim, run) = sim_common::simulated_run(&config);
    let model = identified_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        &mut |_| {},
    )
    .expect("identified");
    (sim, model)
}

/// Two 30-minute turbulent cruise runs at 1 kHz on a real stand (seeds chosen before they were
/// run, 4201-4202): each block's `K` normalised errors pooled have rms within 0.7-1.4 and at most
/// 10 % beyond 2 sigma (before, the gyro's: rms 1.52, 28 % beyond 2; on such runs up to 4.3
/// sigma); the gyro's shift has a negative diagonal (its gains read low), both blocks' are under
/// a few thousandths.
#[test]
fn on_long_real_stand_runs_the_deviations_hold_the_left_out_noise() {
    let mut z: [Vec<f64>; 2] = Default::default();
    for seed in [4201, 4202] {
        let (sim, model) = real_stand(
            Regime::TurbulentCruise,
            seed,
            1800.0,
            1000.0,
            &[Block::Gyro, Block::Accel],
        );
        for (b, (name, truth)) in [
            ("gyro", &sim.sidecar.truth.gyro),
            ("accel", &sim.sidecar.truth.accel),
        ]
        .into_iter()
        .enumerate()
        {
            let truth = truth.as_ref().expect("truth").k;
            let m = &model.blocks[name];
            let shift = m.fit.k_shift_left_out_angle_noise.expect("a gyro witness");
            for i in 0..3 {
                assert!(
                    name != "gyro" || shift[i][i] < 0.0,
                    "seed {seed} {name}: {shift:?}"
                );
                for j in 0..3 {
                    assert!(shift[i][j].abs() < 3e-3, "seed {seed} {name}: {shift:?}");
                    let sd = m.fit.k_std[i][j].expect("a deviation");
                    z[b].push((m.k[i][j] - truth[i][j]) / sd);
                }
            }
        }
    }
    for (name, z) in ["gyro", "accel"].iter().zip(&z) {
        let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
        let beyond = z.iter().filter(|v| v.abs() > 2.0).count() as f64 / z.len() as f64;
        eprintln!("{name} K z: rms {rms:.2}, beyond 2 sigma {beyond:.2}: {z:.2?}");
        assert!((0.7..=1.4).contains(&rms), "{name}: {z:?}");
        assert!(beyond <= 0.1, "{name}: {z:?}");
    }
}

/// Without a gyro the model is white (nothing left out by that rule; `effect_suspected` and
/// `angle_noise_colour_unknown` speak for it): no shift.
#[test]
fn without_a_gyro_nothing_is_left_out() {
    let (_, model) = real_stand(Regime::Cruise, 7, 120.0, 500.0, &[Block::Accel]);
    assert!(model.blocks["accel"].fit.k_shift_left_out_angle_noise.is_none());
}
