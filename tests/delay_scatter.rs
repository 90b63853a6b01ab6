//! A logger slip on a short run: 120 s at 500 Hz with the stand's real imperfections leave four
//! stretches, too few to place a step (`delay_step` needs sides of its own), and the delay's
//! deviation was the stretches' spread, seventy times the fit's (0.007 to 0.47 ms), said by
//! nothing. Now each slipped block is said to move (`delay_scatter`, or the step or drift where
//! they are found), and the same runs without the slip say none of it. The slip's time and
//! channels are read from the simulator's truth, by the test only.

use crate::common::sim as sim_common;

use imu_attest::block::Block;
use imu_attest::faults::Channel;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::sim::fault::{FaultKind, FaultSpec, FaultTruth};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};

fn config(regime: Regime, seed: u64, slip: Option<Channel>) -> SimConfig {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = 120.0;
    config.rate_hz = 500.0;
    config.stand = StandImperfections::real();
    config.faults = slip
        .map(|channel| FaultSpec {
            kind: FaultKind::Slip,
            channel: Some(channel),
        })
        .into_iter()
        .collect();
    config
}

/// The blocks whose outputs or inputs the slip moved: both for the angles, else the one.
fn slipped_blocks(sim: &SimulatedRun) -> Vec<Block> {
    let [FaultTruth::Slip { channels, .. }] = sim.sidecar.truth.faults.as_slice() else {
        panic!("one slip: {:?}", sim.sidecar.truth.faults)
    };
    if channels[0].is_angle() {
        vec![Block::Gyro, Block::Accel]
    } else if channels[0].name().starts_with('g') {
        vec![Block::Gyro]
    } else {
        vec![Block::Accel]
    }
}

fn moves(w: &IdentWarning) -> bool {
    matches!(
        w,
        IdentWarning::DelayScatter { .. } | IdentWarning::DelayStep { .. } | IdentWarning::DelayDrift { .. }
    )
}

#[test]
fn a_slip_on_a_short_run_is_said_and_the_same_run_without_it_says_nothing() {
    let cases = [
        (Regime::TurbulentCruise, 4, Channel::Gx),
        (Regime::TurbulentCruise, 4, Channel::Roll),
        (Regime::Approach, 5, Channel::Roll),
        (Regime::Cruise, 6, Channel::Gx),
    ];
    let mut scatter_said = 0;
    for (regime, seed, channel) in cases {
        let (sim, run) = sim_common::simulated_run(&config(regime, seed, Some(channel)));
        let slipped = slipped_blocks(&sim);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            let said: Vec<&IdentWarning> = b.warnings.iter().filter(|w| moves(w)).collect();
            eprintln!("{regime:?} {seed} {channel:?} {}: {:?}", b.block, said);
            if slipped.contains(&b.block) {
                assert!(
                    !said.is_empty(),
                    "{regime:?} {seed} {}: the slip said by nothing",
                    b.block
                );
                scatter_said += usize::from(
                    said.iter()
                        .any(|w| matches!(w, IdentWarning::DelayScatter { .. })),
                );
                if let Some(IdentWarning::DelayScatter {
                    spread_std_s,
                    own_std_s,
                    ..
                }) = said.first()
                {
                    assert!(
                        (*spread_std_s - b.structural.tau_std_s).abs() < 1e-12,
                        "the deviation quoted is the model's"
                    );
                    assert!(
                        *spread_std_s > 10.0 * own_std_s / 2.0,
                        "{spread_std_s} {own_std_s}"
                    );
                }
            }
        }
        let (_, clean) = sim_common::simulated_run(&config(regime, seed, None));
        let id = identify_run(&clean, &Settings::default()).expect("identified");
        for b in &id.blocks {
            assert!(
                !b.warnings
                    .iter()
                    .any(|w| matches!(w, IdentWarning::DelayScatter { .. })),
                "{regime:?} {seed} {} without a slip: {:?}",
                b.block,
                b.warnings
            );
        }
    }
    assert!(scatter_said >= 3, "the case this test stands for: {scatter_said}");
}
