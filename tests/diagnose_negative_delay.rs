//! A reference whose angles lag the sensors' outputs (50 ms of angle latency: the measured delay
//! about -47 ms). The search's lag and resonance candidates started their delay at 0 (a sensor's
//! own delay is not negative), 47 ms off: their fits failed (chi2 "gains" of -3e7 in the
//! report's candidates), and a true gyro lag was named only in a later round, after a false
//! `g_sensitivity` (measured 30 Nov with the binary before, cruise 120 s, seeds 31 and 32; a
//! helper's campaign found the failed fits at 250 Hz). Now a negative delay starts unclamped:
//! the lag is the first finding and the only one, sized within its deviations, and no lag
//! candidate fits worse than the model it extends; a mount resonance, named on one seed of three
//! before, is named alone on all three. The diagnosis sees the loaded run only; the
//! test reads the hidden lag from the simulator's truth.

use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::SimConfig;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::truth::EffectTruth;

use crate::common::sim as sim_common;

#[test]
fn a_lag_behind_a_late_reference_is_found_first_and_alone() {
    for seed in [31_u64, 32] {
        let mut config = SimConfig::new(Regime::Cruise);
        (config.seed, config.duration_s, config.rate_hz) = (seed, 120.0, 500.0);
        config.stand = StandImperfections {
            latency_s: 0.05,
            ..StandImperfections::default()
        };
        config.effects = vec!["sensor_lag:gyro".parse().expect("effect spec")];
        let (sim, run) = sim_common::simulated_run(&config);
        let t_true = sim
            .sidecar
            .truth
            .gyro
            .and_then(|g| {
                g.effects.iter().find_map(|e| match e {
                    EffectTruth::SensorLag { time_constant_s } => Some(*time_constant_s),
                    _ => None,
                })
            })
            .expect("the hidden lag");
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        assert_eq!(
            named,
            vec![(imu_attest::block::Block::Gyro, Effect::SensorLag)],
            "seed {seed}"
        );
        let f = &report.findings[0];
        let t = f.parameters["T_s"].as_f64().expect("T_s");
        let sd = f.parameter_std["T_s"].as_f64().expect("its deviation");
        assert!(
            (t - t_true).abs() < 3.0 * sd,
            "seed {seed}: T {t} +- {sd}, truth {t_true}"
        );
        for (name, b) in &report.blocks {
            // A lag nests the model it extends (T -> 0): fitted from a sound start it can only
            // lower chi2 (a little noise in the optimiser's stop aside). (A resonance does not
            // nest it: unity at DC and a peak inside the band, it may fit worse.)
            for c in b.candidates.iter().filter(|c| c.effect == Effect::SensorLag) {
                assert!(c.delta_chi2 > -1.0, "seed {seed}: {name}: {c:?}");
            }
        }
    }
}

/// The same late reference beside a gyro mount resonance (30.6-30.7 Hz, damping 0.05; cruise
/// 120 s, seeds 31-33): the resonance's grid start took the delay to 0 too, and with the binary
/// before it was named on one seed of three (beside a false `g_sensitivity`); on the other two
/// a false `g_sensitivity`, skew, lag or nonlinearity took its place. Now it is named alone on
/// all three, its frequency and damping within their deviations.
#[test]
fn a_resonance_behind_a_late_reference_is_named_alone() {
    for seed in [31_u64, 32, 33] {
        let mut config = SimConfig::new(Regime::Cruise);
        (config.seed, config.duration_s, config.rate_hz) = (seed, 120.0, 500.0);
        config.stand = StandImperfections {
            latency_s: 0.05,
            ..StandImperfections::default()
        };
        config.effects = vec!["platform_resonance:gyro".parse().expect("effect spec")];
        let (sim, run) = sim_common::simulated_run(&config);
        let (f_true, zeta_true) = sim
            .sidecar
            .truth
            .gyro
            .and_then(|g| {
                g.effects.iter().find_map(|e| match e {
                    EffectTruth::PlatformResonance {
                        frequency_hz,
                        damping,
                        ..
                    } => Some((*frequency_hz, *damping)),
                    _ => None,
                })
            })
            .expect("the hidden resonance");
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        assert_eq!(
            named,
            vec![(imu_attest::block::Block::Gyro, Effect::PlatformResonance)],
            "seed {seed}"
        );
        let f = &report.findings[0];
        for (key, truth) in [("frequency_hz", f_true), ("damping", zeta_true)] {
            let v = f.parameters[key].as_f64().expect("a size");
            let sd = f.parameter_std[key].as_f64().expect("its deviation");
            assert!(
                (v - truth).abs() < 3.5 * sd,
                "seed {seed}: {key} {v} +- {sd}, truth {truth}"
            );
        }
    }
}
