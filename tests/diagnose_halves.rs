//! Issue 15: is a finding one property of the block over the run? Each finding's sizes are
//! fitted again on each half of the record (`diagnose::halves`). A steady simulated quadratic
//! scale factor is named with its halves agreeing (no caveat); the same unit whose effect stops
//! half-way (the second half's gyro outputs those of the same seed without it: same motion,
//! same angles) is still named, and its evidence says the size is not one fixed property of the
//! block over this run. The diagnosis sees the loaded run only.

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, Finding, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;

use crate::common::sim as sim_common;

/// Said when the halves disagree with each other or with the whole record.
const CAVEAT: &str = "not one fixed property of the block over this run";

fn k2_finding(run: &Run) -> Finding {
    let report = diagnose_run(run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    report
        .findings
        .into_iter()
        .find(|f| f.block == Block::Gyro && f.effect == Effect::ScaleNonlinearity)
        .expect("the quadratic scale factor named")
}

#[test]
fn a_steady_effect_agrees_between_halves_and_one_that_stops_does_not() {
    for seed in [11_u64, 12] {
        let regime = if seed == 11 {
            Regime::Approach
        } else {
            Regime::TurbulentCruise
        };
        let (_, steady) = sim_common::simulated_run_of(120.0, regime, seed, &["scale_nonlinearity:gyro@3"]);
        let f = k2_finding(&steady);
        let halves = f.halves.as_ref().expect("the halves compared");
        assert_eq!(halves.as_array().map(Vec::len), Some(2), "{halves}");
        assert!(
            !f.evidence.contains(CAVEAT),
            "seed {seed}, steady: {}",
            f.evidence
        );

        let (_, clean) = sim_common::simulated_run_of(120.0, regime, seed, &[]);
        assert_eq!(steady.angles, clean.angles, "same seed, same motion");
        let mut stopping = steady.clone();
        let half = stopping.len() / 2;
        let (gyro, clean_gyro) = (
            stopping.gyro.as_mut().expect("gyro"),
            clean.gyro.as_ref().expect("gyro"),
        );
        for (channel, clean_channel) in gyro.iter_mut().zip(clean_gyro) {
            channel[half..].copy_from_slice(&clean_channel[half..]);
        }
        let f = k2_finding(&stopping);
        assert!(
            f.evidence.contains(CAVEAT),
            "seed {seed}, stopping half-way: {}",
            f.evidence
        );
    }
}
