//! `gain_depends_on_amplitude`: a block whose outputs hold `k2 u |u|` (the catalogue's
//! `scale_nonlinearity`) had its `K` moved by 1.6 % by `identify` alone, said by nothing but a
//! band trimmed at its top. Now the self-check sizes `k2` per output and the gain it adds to `K`,
//! and says it; the same runs without the effect, with the stand's real imperfections, say
//! nothing; once the effect is accepted (`identify --effects`) the model no longer says it. The
//! truth (`k2`, `K`) is read by the test only.

use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::extended_model;
use imu_attest::effect::Effect;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::odd_gain::OddOutput;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::truth::EffectTruth;
use sim_common::{simulated_run, simulated_run_of};

fn said(warnings: &[IdentWarning]) -> Option<&Vec<OddOutput>> {
    warnings.iter().find_map(|w| match w {
        IdentWarning::GainDependsOnAmplitude { outputs, .. } => Some(outputs),
        _ => None,
    })
}

#[test]
fn a_nonlinear_scale_factor_is_said_with_its_size_and_the_gain_it_adds() {
    let cases = [
        (Regime::Cruise, 1, Block::Gyro),
        (Regime::Approach, 2, Block::Accel),
        (Regime::TurbulentCruise, 3, Block::Gyro),
    ];
    for (regime, seed, block) in cases {
        let spec = format!("scale_nonlinearity:{}", block.name());
        let (sim, run) = simulated_run_of(120.0, regime, seed, &[spec.as_str()]);
        let truth = match block {
            Block::Gyro => sim.sidecar.truth.gyro,
            Block::Accel => sim.sidecar.truth.accel,
        }
        .expect("the block's truth");
        let k2 = truth
            .effects
            .iter()
            .find_map(|e| match e {
                EffectTruth::ScaleNonlinearity { k2 } => Some(*k2),
                _ => None,
            })
            .expect("k2 in the truth");
        let id = identify_run(&run, &Settings::default()).expect("identified");
        let b = id.blocks.iter().find(|b| b.block == block).expect("the block");
        let outputs =
            said(&b.warnings).unwrap_or_else(|| panic!("{regime:?} {seed}: not said: {:?}", b.warnings));
        assert!(!outputs.is_empty());
        for o in outputs {
            let i = ["x", "y", "z"]
                .iter()
                .position(|a| o.output.ends_with(a))
                .expect("an output name");
            let z = (o.k2 - k2[i]) / o.k2_std;
            assert!(
                z.abs() < 4.0,
                "{regime:?} {seed} {}: k2 {} +- {}, truth {}",
                o.output,
                o.k2,
                o.k2_std,
                k2[i]
            );
            // The gain it adds is what K reads beyond the truth's scale factor.
            let k_error = b.structural.k[i][i] - truth.k[i][i];
            assert!(
                (o.gain_shift * b.structural.k[i][i] - k_error).abs()
                    < 0.15 * k_error.abs() + 3.0 * b.structural.k_std[i][i],
                "{regime:?} {seed} {}: gain added {} against K's error {k_error}",
                o.output,
                o.gain_shift
            );
        }
        // The other block, linear, says nothing of it.
        for other in id.blocks.iter().filter(|o| o.block != block) {
            assert!(
                said(&other.warnings).is_none(),
                "{:?}: {:?}",
                other.block,
                other.warnings
            );
        }
    }
}

#[test]
fn linear_blocks_on_a_real_stand_say_nothing() {
    for (regime, seed) in [
        (Regime::Cruise, 21),
        (Regime::TurbulentCruise, 22),
        (Regime::Approach, 23),
    ] {
        let mut config = SimConfig::new(regime);
        config.seed = seed;
        config.duration_s = 120.0;
        config.stand = StandImperfections::real();
        let (_, run) = simulated_run(&config);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            assert!(
                said(&b.warnings).is_none(),
                "{regime:?} {seed} {:?}: {:?}",
                b.block,
                b.warnings
            );
        }
    }
}

#[test]
fn accepted_it_is_no_longer_said() {
    let (_, run) = simulated_run_of(120.0, Regime::Cruise, 4, &["scale_nonlinearity:gyro"]);
    let run = Arc::new(run);
    let bare = extended_model(
        &mut Session::new(run.clone()),
        &Settings::default(),
        &[],
        &mut |_| {},
    )
    .expect("identified");
    assert!(said(&bare.blocks["gyro"].fit.warnings).is_some());
    let accepted = [(Block::Gyro, Effect::ScaleNonlinearity)];
    let extended = extended_model(
        &mut Session::new(run),
        &Settings::default(),
        &accepted,
        &mut |_| {},
    )
    .expect("extended");
    assert!(
        said(&extended.blocks["gyro"].fit.warnings).is_none(),
        "{:?}",
        extended.blocks["gyro"].fit.warnings
    );
}
