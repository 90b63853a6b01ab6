//! A sensor's own second-order low-pass (a read-out's anti-alias filter or a configurable digital
//! low-pass; `simulate --sensor-filter-hz`, a second-order Butterworth on both blocks) is named as
//! the sensor's lag, of second order, with its corner and damping, and not as further sensor
//! effects. Before the second-order shape the diagnosis named a first-order `sensor_lag` (80 % of
//! the misfit) and then, on 12 runs of two filters, the shape's remainder as a gyro
//! `g_sensitivity` (10), `axis_time_skew` (8), `scale_nonlinearity` (9 gyro, 7 accelerometer)
//! and an accelerometer `lever_arm_error` (5) (1 Dec, thirty-fourth session). Only these tests
//! know how the runs were made.

use crate::common::sim as sim_common;

use imu_attest::block::Block;
use imu_attest::diagnose::report::{Finding, Report};
use imu_attest::diagnose::structure::LagShape;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use sim_common::simulated_run;

fn diagnosed(regime: Regime, seed: u64, filter_hz: Option<f64>, effects: &[&str]) -> Report {
    diagnosed_blocks(regime, seed, filter_hz, effects, &[Block::Gyro, Block::Accel])
}

fn diagnosed_blocks(
    regime: Regime,
    seed: u64,
    filter_hz: Option<f64>,
    effects: &[&str],
    blocks: &[Block],
) -> Report {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.blocks = blocks.to_vec();
    config.duration_s = 120.0;
    config.sensor_filter_hz = filter_hz;
    config.effects = effects.iter().map(|e| e.parse().expect("effect spec")).collect();
    let (_, run) = simulated_run(&config);
    diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed")
}

/// The block's lag: its own, or the one both blocks share (`reference_lag`: the run cannot tell
/// a filter both sensor blocks share from the stand's, and says so).
fn lag(report: &Report, block: Block) -> Option<&Finding> {
    report
        .findings
        .iter()
        .find(|f| f.block == block && matches!(f.effect, Effect::SensorLag | Effect::ReferenceLag))
}

fn value(f: &Finding, key: &str) -> (f64, f64) {
    let of = |v: &serde_json::Value| v.get(key).and_then(serde_json::Value::as_f64).unwrap_or(f64::NAN);
    (of(&f.parameters), of(&f.parameter_std))
}

#[test]
fn a_second_order_sensor_filter_is_one_second_order_lag_and_nothing_else() {
    let mut z = Vec::new();
    // Both blocks filtered (one lag, shared), then each block alone (its own `sensor_lag`).
    for (seed, regime, corner_hz, blocks) in [
        (9601, Regime::Cruise, 20.0, &[Block::Gyro, Block::Accel][..]),
        (9602, Regime::Approach, 25.0, &[Block::Gyro, Block::Accel][..]),
        (9603, Regime::TurbulentCruise, 15.0, &[Block::Gyro][..]),
        (9604, Regime::Approach, 20.0, &[Block::Accel][..]),
    ] {
        let report = diagnosed_blocks(regime, seed, Some(corner_hz), &[], blocks);
        let found: Vec<(Block, Effect)> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        eprintln!("{regime} seed {seed}, {corner_hz} Hz: {found:?}");
        for &block in blocks {
            let f = lag(&report, block).unwrap_or_else(|| panic!("{block}: {found:?}"));
            // One block's own lag; both blocks' one lag, which one run cannot tell from the
            // stand's (`reference_lag`, said so).
            let want = if blocks.len() == 1 {
                Effect::SensorLag
            } else {
                Effect::ReferenceLag
            };
            assert_eq!(f.effect, want, "{found:?}");
            assert_eq!(
                f.parameters["shape"], "second_order",
                "{block}: {:?}",
                f.parameters
            );
            let (corner, corner_sd) = value(f, "corner_hz");
            let (damping, damping_sd) = value(f, "damping");
            eprintln!(
                "  {block}: corner {corner:.3} +- {corner_sd:.3} Hz, damping {damping:.4} +- {damping_sd:.4}"
            );
            // The Butterworth's corner and damping, within a tenth and within their deviations.
            assert!((corner / corner_hz - 1.0).abs() < 0.1, "{block}: corner {corner}");
            assert!(
                (damping * 2f64.sqrt() - 1.0).abs() < 0.1,
                "{block}: damping {damping}"
            );
            z.push((corner - corner_hz) / corner_sd);
            z.push((damping - 0.5f64.sqrt()) / damping_sd);
        }
        // Nothing but the filter.
        assert!(
            report
                .findings
                .iter()
                .all(|f| matches!(f.effect, Effect::SensorLag | Effect::ReferenceLag)),
            "{found:?}"
        );
        assert_eq!(report.findings.len(), blocks.len(), "{found:?}");
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    eprintln!("corner and damping z {z:.2?}, rms {rms:.2}");
    assert!(z.iter().all(|v| v.is_finite() && v.abs() < 4.0), "{z:?}");
    assert!(rms < 2.0, "z rms {rms}");
}

#[test]
fn a_first_order_lag_stays_first_order() {
    // The catalogue's first-order lag on the gyro: the second shape's extra parameter does not pay.
    for (seed, regime) in [(9611, Regime::Approach), (9612, Regime::Cruise)] {
        let report = diagnosed(regime, seed, None, &["sensor_lag:gyro"]);
        let f = lag(&report, Block::Gyro).expect("named");
        eprintln!("{regime} seed {seed}: {:?}", f.parameters);
        assert!(f.parameters.get("shape").is_none(), "{:?}", f.parameters);
        assert!(f.parameters.get("damping").is_none(), "{:?}", f.parameters);
        // In the first round's table the first order beats the second, where the second was
        // fitted at all (a first-order lag drives its damping to the upper bound, where it is
        // set aside).
        let rows = &report.blocks["gyro"].candidates;
        let gain = |shape: LagShape| {
            rows.iter()
                .find(|c| c.effect == Effect::SensorLag && c.lag_shape == Some(shape))
                .map(|c| c.criterion_gain)
        };
        let first = gain(LagShape::FirstOrder).expect("the first order tried");
        eprintln!(
            "  first order {first:.1}, second order {:?}",
            gain(LagShape::SecondOrder)
        );
        assert!(gain(LagShape::SecondOrder).is_none_or(|second| second < first));
    }
}
