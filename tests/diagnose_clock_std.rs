//! A clock drift's size has a standard deviation, and an honest one: `discrepancy` gave
//! `drift_ppm` with a `null` deviation (found by a test campaign, 29 Nov), so it could not be
//! judged or compared. With stretches, the deviation is the stretches' trend's times what the
//! whole record's taper loses of a drift; without (a record too short to cut), the profiled
//! cost's curvature, conservative. Only this test reads the truth.

use crate::common::sim as sim_common;

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::truth::EffectTruth;
use sim_common::simulated_run_of;

/// `(estimate - truth) / deviation` of the drift found on `block`, ppm.
fn drift_z(duration_s: f64, regime: Regime, seed: u64, block: Block) -> f64 {
    let spec = format!("clock_drift:{}", block.name());
    let (sim, run) = simulated_run_of(duration_s, regime, seed, &[spec.as_str()]);
    let truth = match block {
        Block::Gyro => sim.sidecar.truth.gyro,
        Block::Accel => sim.sidecar.truth.accel,
    }
    .expect("the block's truth");
    let drift_ppm = truth
        .effects
        .iter()
        .find_map(|e| match e {
            EffectTruth::ClockDrift { drift_ppm } => Some(*drift_ppm),
            _ => None,
        })
        .expect("a drift in the truth");
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let f = report
        .findings
        .iter()
        .find(|f| f.effect == Effect::ClockDrift && f.block == block)
        .unwrap_or_else(|| panic!("{regime:?} {seed}: no drift"));
    let est = f.parameters["drift_ppm"].as_f64().expect("drift");
    let sd = f.parameter_std["drift_ppm"]
        .as_f64()
        .expect("a deviation, not null");
    let change = f.parameter_std["delay_change_s"]
        .as_f64()
        .expect("the delay change's too");
    assert!(
        (change / sd - duration_s * 1e-6).abs() < 1e-9 * duration_s,
        "the delay change's deviation is the drift's over the record"
    );
    (est - drift_ppm) / sd
}

#[test]
fn a_drift_s_deviation_covers_its_error() {
    let mut z = Vec::new();
    for (regime, seed, block) in [
        (Regime::Cruise, 31, Block::Gyro),
        (Regime::TurbulentCruise, 32, Block::Accel),
        (Regime::Approach, 33, Block::Gyro),
        (Regime::Cruise, 34, Block::Accel),
    ] {
        z.push(drift_z(300.0, regime, seed, block));
    }
    assert!(z.iter().all(|v| v.abs() < 3.5), "{z:?}");
    // Neither many times too wide: some error reaches a fifth of its deviation.
    assert!(z.iter().any(|v| v.abs() > 0.2), "{z:?}");
}

#[test]
fn without_stretches_the_deviation_is_the_cost_s_and_covers_the_error() {
    let z = drift_z(40.0, Regime::Approach, 147, Block::Gyro);
    assert!(z.abs() < 3.0, "{z}");
}
