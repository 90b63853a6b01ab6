//! The stated size limits of the effects linear in the model (`diagnose::size_limit`) are what
//! the search can see. On clean simulated runs (a perfect stand and a real one) the limits of a
//! gyro `g_sensitivity`, an accelerometer `lever_arm_error` and an accelerometer
//! `scale_nonlinearity` are read from the report; then one component is put into the same run
//! outside the simulator (the test's own injection, from the simulator's true motion, delayed by
//! the block's delay as its inputs are):
//! - at 1.5 and 3 times its limit a finding is named on the block that the clean run did not
//!   have: the effect, or one that explains the same misfit with fewer parameters (an entry of
//!   `G` that reads like a channel's delay is named `axis_time_skew`, measured); or the effect
//!   is said significant but not named (a rule refused it: an accelerometer offset along x at
//!   1.5 times its limit, its evidence 78 against 81 promised, did not shrink the outputs'
//!   unweighted residual power); where it is the
//!   effect, its evidence is the one the limit promises, `s^2` times the criterion plus about one
//!   per parameter, within four of that evidence's standard deviations for `G` and the offset on
//!   the perfect stand (measured 0.95-1.26 of it, less the one per parameter), and above 0.35 of
//!   it for `k2` and on the real stand (0.66-0.69 and 0.42-0.84: the disturbance level the fit
//!   weighs by is the identification's residual, which the effect unmodelled raises by its part
//!   a per-frequency linear regression cannot take, a nonlinearity's harmonics, and on the real
//!   stand part of `G`'s low-frequency term); every evidence below four deviations above it;
//! - at half its limit the effect is not named, and its limit is stated again (within a fifth
//!   where nothing else was named).
//!
//! A limit stated too low fails the evidence's check (its upper bound, everywhere); one too high
//! fails its lower bound for `G` and the offset on the perfect stand, and the naming at 1.5
//! times. (Where the effect is named at 1.5 times its lower bound, 0.35 of the promise, is below
//! the criterion: it bites at 3 times.) `SizeLimit::any_direction` against the evidence it
//! promises in every direction is a unit test of `diagnose::size_limit`.

use crate::common::sim as sim_common;

use imu_attest::block::Block;
use imu_attest::diagnose::size_limit::SizeLimit;
use imu_attest::diagnose::{DiagnoseOptions, Report, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};
use sim_common::simulated_run;

fn diagnosed(run: &Run) -> Report {
    diagnose_run(run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed")
}

fn limit_of(report: &Report, block: Block, effect: Effect) -> Option<SizeLimit> {
    report.blocks[block.name()]
        .size_limits
        .iter()
        .find(|l| l.effect == effect)
        .cloned()
}

/// `x` at the sample times less `delay` samples (linear interpolation; held at the start).
fn delayed(x: &[f64], delay: f64, n: usize) -> f64 {
    let at = (n as f64 - delay).max(0.0);
    let (k, frac) = (at.floor() as usize, at.fract());
    let next = x.get(k + 1).unwrap_or(&x[k]);
    x[k] * (1.0 - frac) + next * frac
}

/// `run` with component `k` of `effect` at size `b`, computed from the simulator's true motion
/// as the model's term is: `G[k / 3][k % 3]` times the specific force at the gyro; the
/// accelerometer's offset along axis `k` (the specific force at the declared lever arm moved by
/// `b` along it, less the force there); `k2` of output `k` times its input `f_k |f_k|`.
fn with_effect(sim: &SimulatedRun, run: &Run, effect: Effect, k: usize, b: f64) -> Run {
    let s = &sim.sidecar;
    let motion = &sim.true_motion;
    let (block, added): (Block, [Vec<f64>; 3]) = match effect {
        Effect::GSensitivity => {
            let f = &motion.specific_forces(s.gyro_lever_arm_m, s.g_mps2)[k % 3];
            let mut added = [vec![0.0; f.len()], vec![0.0; f.len()], vec![0.0; f.len()]];
            added[k / 3] = f.iter().map(|v| b * v).collect();
            (Block::Gyro, added)
        }
        Effect::LeverArmError => {
            let at = motion.specific_forces(s.accel_lever_arm_m, s.g_mps2);
            let mut moved = s.accel_lever_arm_m;
            moved[k] += b;
            let there = motion.specific_forces(moved, s.g_mps2);
            let added = [0, 1, 2].map(|i| there[i].iter().zip(&at[i]).map(|(a, c)| a - c).collect());
            (Block::Accel, added)
        }
        _ => {
            let f = &motion.specific_forces(s.accel_lever_arm_m, s.g_mps2)[k];
            let mut added = [vec![0.0; f.len()], vec![0.0; f.len()], vec![0.0; f.len()]];
            added[k] = f.iter().map(|v| b * v * v.abs()).collect();
            (Block::Accel, added)
        }
    };
    let truth = match block {
        Block::Gyro => s.truth.gyro.as_ref(),
        Block::Accel => s.truth.accel.as_ref(),
    };
    let delay = truth.expect("the block's truth").tau_s * run.sample_rate_hz;
    let mut out = run.clone();
    let outputs = match block {
        Block::Gyro => out.gyro.as_mut(),
        Block::Accel => out.accel.as_mut(),
    }
    .expect("the block's outputs");
    for (channel, add) in outputs.iter_mut().zip(&added) {
        for (n, v) in channel.iter_mut().enumerate() {
            *v += delayed(add, delay, n);
        }
    }
    out
}

/// The block's findings that are not the stand's and not among `clean`'s.
fn new_findings(report: &Report, clean: &Report, block: Block) -> Vec<(Effect, f64)> {
    report
        .findings
        .iter()
        .filter(|f| f.block == block && f.effect != Effect::ReferenceBandLimit)
        .filter(|f| {
            !clean
                .findings
                .iter()
                .any(|c| c.block == block && c.effect == f.effect)
        })
        .map(|f| (f.effect, f.delta_chi2))
        .collect()
}

#[test]
fn an_effect_above_its_stated_limit_is_named_with_the_evidence_promised() {
    let cases = [(false, Regime::Cruise, 61), (true, Regime::Approach, 62)];
    let effects = [
        (Effect::GSensitivity, Block::Gyro),
        (Effect::LeverArmError, Block::Accel),
        (Effect::ScaleNonlinearity, Block::Accel),
    ];
    for (real, regime, seed) in cases {
        let mut config = SimConfig::new(regime);
        config.seed = seed;
        config.duration_s = 120.0;
        if real {
            config.stand = StandImperfections::real();
        }
        let (sim, run) = simulated_run(&config);
        let clean = diagnosed(&run);
        for (effect, block) in effects {
            let limit = limit_of(&clean, block, effect)
                .unwrap_or_else(|| panic!("{seed}: no {effect:?} limit: {:?}", clean.findings));
            let components = limit.component.len();
            assert_eq!(components, if effect == Effect::GSensitivity { 9 } else { 3 });
            let largest = limit.component.iter().copied().fold(0.0, f64::max);
            assert!(
                limit.component.iter().all(|c| c.is_finite() && *c > 0.0) && limit.any_direction >= largest,
                "{limit:?}"
            );
            let order = |a: &usize, b: &usize| limit.component[*a].total_cmp(&limit.component[*b]);
            let best = (0..components).min_by(order).expect("components");
            let worst = (0..components).max_by(order).expect("components");
            for (k, scales) in [(best, &[1.5, 3.0][..]), (worst, &[1.5][..])] {
                let at = limit.component[k];
                for &s in scales {
                    let report = diagnosed(&with_effect(&sim, &run, effect, k, s * at));
                    let new = new_findings(&report, &clean, block);
                    let signal = s * s * limit.chi2_needed;
                    let p = components as f64;
                    let (mean, sd) = (signal + p, (2.0 * p + 4.0 * signal).sqrt());
                    eprintln!(
                        "{seed} {effect:?}[{k}] {s} x {at:.3e}: {new:?}, promised {mean:.0} +- {sd:.0}"
                    );
                    // The effect named; or, for an entry of `G` that reads like a channel's
                    // delay, a skew; or the effect said significant but not named (a rule
                    // refused it: `not_named`).
                    let stands_in = |e: Effect| {
                        e == effect || (effect == Effect::GSensitivity && e == Effect::AxisTimeSkew)
                    };
                    let refused = report.blocks[block.name()]
                        .not_named
                        .iter()
                        .any(|r| r.effect == effect);
                    assert!(
                        new.iter().any(|(e, _)| stands_in(*e)) || refused,
                        "{seed} {effect:?}[{k}] at {s}: neither named nor said; {new:?} {:#?}",
                        report.limits(block.name()),
                    );
                    if let Some(&(_, evidence)) = new.iter().find(|(e, _)| *e == effect) {
                        // Weighed against a level the effect does not raise: as promised.
                        let linear = !real && effect != Effect::ScaleNonlinearity;
                        let low = if linear { mean - 4.0 * sd } else { 0.35 * signal };
                        assert!(
                            evidence > low && evidence < mean + 4.0 * sd,
                            "{seed} {effect:?}[{k}] at {s}: evidence {evidence:.0}, promised {mean:.0} +- \
                             {sd:.0}"
                        );
                    }
                }
            }
            let at = limit.component[worst];
            let report = diagnosed(&with_effect(&sim, &run, effect, worst, 0.5 * at));
            assert!(
                !report
                    .findings
                    .iter()
                    .any(|f| f.block == block && f.effect == effect),
                "{seed} {effect:?}[{worst}] at half the limit: {:?}",
                report.findings
            );
            // Stated again, alike where the model is the clean run's (a finding it names in its
            // place, a skew beside `G[gz][fy]`, takes that part of the component's evidence).
            let again = limit_of(&report, block, effect).expect("stated again");
            if new_findings(&report, &clean, block).is_empty() {
                assert!(
                    (again.component[worst] / at - 1.0).abs() < 0.2,
                    "{again:?} against {at}"
                );
            }
        }
    }
}
