//! A declared `angle_noise_rad` the angles contradict: the gyro, the motion's second witness,
//! leaves less unexplained in the angles than the declared noise alone would (`stand::colour`'s
//! bound, an upper one: it holds the gyro's own noise too). Declared three times too high, both
//! blocks say so (`angle_noise_overstated`), with the bound near the true noise; as declared by
//! the simulator, or 1.5 times too high (below the bar of twice), nothing is said. Without a
//! gyro there is no bound and nothing is said. The test reads the true noise from the simulator's
//! truth, which the identifier never sees.

use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;

use crate::common::sim as sim_common;

/// Each block's bound, when it says `angle_noise_overstated`.
fn said(run: &Run) -> Vec<Option<[f64; 3]>> {
    let id = identify_run(run, &Settings::default()).expect("identified");
    id.blocks
        .iter()
        .map(|b| {
            b.warnings.iter().find_map(|w| match w {
                IdentWarning::AngleNoiseOverstated { bound_rad, .. } => Some(*bound_rad),
                _ => None,
            })
        })
        .collect()
}

#[test]
fn an_overstated_angle_noise_is_said_and_a_right_one_is_not() {
    for seed in [11, 12] {
        let (sim, run) = sim_common::simulated_run_of(120.0, Regime::Cruise, seed, &[]);
        let truth = sim.sidecar.truth.angle_white_noise_rad;
        // The simulator declares its noise with the quantisation's (`q^2 / 12`) added.
        let declared = run.sidecar.angle_noise_rad.expect("declared");
        assert!(
            (declared / truth - 1.0).abs() < 0.01,
            "{declared:e} against {truth:e}"
        );
        assert_eq!(said(&run), vec![None, None], "seed {seed}: as declared");
        for (factor, expected) in [(1.5, false), (3.0, true)] {
            let mut wrong = run.clone();
            wrong.sidecar.angle_noise_rad = Some(factor * declared);
            let found = said(&wrong);
            eprintln!("seed {seed}, x{factor}: {found:?}");
            assert_eq!(found.len(), 2);
            for bound in found {
                assert_eq!(bound.is_some(), expected, "seed {seed}, x{factor}");
                for b in bound.into_iter().flatten() {
                    assert!(b > 0.9 * truth && b < 1.3 * truth, "seed {seed}: bound {b:e}");
                }
            }
        }
        let mut accel_only = run.clone();
        accel_only.gyro = None;
        accel_only.sidecar.angle_noise_rad = Some(3.0 * declared);
        assert_eq!(said(&accel_only), vec![None], "seed {seed}: no witness, no bound");
    }
}
