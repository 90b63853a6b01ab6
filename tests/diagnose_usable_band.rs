//! Findings sized where the inputs are the motion (`diagnose::usable_band`). The search covers
//! 0.1-40 Hz; above the usable band the inputs from the angles are not all the motion, and a
//! size fitted there leans on that. A hidden sensor lag (cruise, 120 s) beside 0.1 mrad coloured
//! angle noise read 2.0-5.3 of its standard deviations long over the band searched (measured on
//! 29 Nov, seeds 21-24); over the usable band it is within its deviations. With the reference's
//! zero-phase band limit (`--stand real`) the band searched's size reads short and the evidence
//! says the size depends on the band above; on a perfect stand the usable band is the band
//! searched and nothing changes. The diagnosis sees the loaded run only; the hidden lag's time
//! constant is read by the test from the simulator's truth.

use imu_attest::diagnose::{DiagnoseOptions, Finding, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::truth::EffectTruth;
use imu_attest::sim::{SimConfig, SimulatedRun};

use crate::common::sim as sim_common;

/// The lag finding on `block` of a cruise run with `stand` and a hidden lag there, and the
/// lag's true time constant.
fn lag_finding(seed: u64, duration_s: f64, stand: StandImperfections, block: &str) -> (Finding, f64) {
    let mut config = SimConfig::new(Regime::Cruise);
    (config.seed, config.duration_s, config.rate_hz) = (seed, duration_s, 500.0);
    config.stand = stand;
    config.effects = vec![format!("sensor_lag:{block}").parse().expect("effect spec")];
    let (sim, run): (SimulatedRun, _) = sim_common::simulated_run(&config);
    let truth = sim.sidecar.truth;
    let effects = if block == "gyro" { truth.gyro } else { truth.accel };
    let t_true = effects
        .and_then(|b| {
            b.effects.iter().find_map(|e| match e {
                EffectTruth::SensorLag { time_constant_s } => Some(*time_constant_s),
                _ => None,
            })
        })
        .expect("the hidden lag");
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let finding = report
        .findings
        .into_iter()
        .find(|f| f.effect == Effect::SensorLag && f.block.name() == block)
        .unwrap_or_else(|| panic!("seed {seed}: the {block} lag not named"));
    (finding, t_true)
}

fn figure(v: &serde_json::Value, key: &str) -> f64 {
    v.get(key).and_then(serde_json::Value::as_f64).expect("a figure")
}

/// `(T - truth) / sd` of the finding's size, and of the band searched's.
fn z_scores(f: &Finding, t_true: f64) -> (f64, Option<f64>) {
    let z = (figure(&f.parameters, "T_s") - t_true) / figure(&f.parameter_std, "T_s");
    let searched = f
        .search_band
        .as_ref()
        .map(|s| (figure(&s["parameters"], "T_s") - t_true) / figure(&s["parameter_std"], "T_s"));
    (z, searched)
}

#[test]
fn a_lag_beside_coloured_angle_noise_is_sized_over_the_usable_band() {
    let stand = StandImperfections {
        coloured_noise_rad: 1e-4,
        coloured_corner_hz: StandImperfections::real().coloured_corner_hz,
        ..StandImperfections::default()
    };
    let mut worst_searched: f64 = 0.0;
    for seed in [21_u64, 23] {
        let (f, t_true) = lag_finding(seed, 120.0, stand, "accel");
        let (z, searched) = z_scores(&f, t_true);
        let searched = searched.unwrap_or_else(|| panic!("seed {seed}: not sized over the usable band"));
        eprintln!(
            "seed {seed}: z {z:.2} (the band searched's {searched:.2}); {}",
            f.evidence
        );
        assert!(z.abs() < 2.5, "seed {seed}: z {z}");
        assert!(
            f.evidence.contains("fitted over the usable band"),
            "{}",
            f.evidence
        );
        worst_searched = worst_searched.max(searched.abs());
    }
    // The band searched's sizes were off by more (the reason for the change).
    assert!(worst_searched > 3.0, "{worst_searched}");
}

#[test]
fn the_reference_s_band_limit_is_said_and_a_perfect_stand_changes_nothing() {
    let (f, t_true) = lag_finding(1, 300.0, StandImperfections::real(), "gyro");
    let (z, searched) = z_scores(&f, t_true);
    let searched = searched.expect("sized over the usable band");
    eprintln!("real stand: z {z:.2} (the band searched's {searched:.2})");
    // Since 30 Nov the stand's 30 Hz band limit is named beside the lag (`reference_band_limit`),
    // and the band searched's size is no longer pulled by it (z -1.51, was below -3).
    assert!(z.abs() < 2.5 && searched.abs() < 2.5, "{z} {searched}");
    // With the band limit in the model the two sizes agree, and the lag is not said to depend on
    // the band above (it was, until the band limit was a candidate).
    assert!(
        f.evidence.contains("fitted over the usable band")
            && !f.evidence.contains("the size depends on the band above"),
        "{}",
        f.evidence
    );
    // A band the user gives is the band the sizes are fitted over.
    let given = Settings {
        band_hz: imu_attest::ident::band::BandSetting::Fixed([0.1, 40.0]),
        ..Settings::default()
    };
    let mut config = SimConfig::new(Regime::Cruise);
    (config.seed, config.duration_s, config.rate_hz) = (1, 300.0, 500.0);
    config.stand = StandImperfections::real();
    config.effects = vec!["sensor_lag:gyro".parse().expect("effect spec")];
    let (_, run) = sim_common::simulated_run(&config);
    let report = diagnose_run(&run, &given, &DiagnoseOptions::default()).expect("diagnosed");
    assert!(
        report.findings.iter().all(|f| f.search_band.is_none()),
        "resized over a given band"
    );
    let (f, t_true) = lag_finding(1, 120.0, StandImperfections::default(), "gyro");
    let (z, searched) = z_scores(&f, t_true);
    assert!(searched.is_none(), "{:?}", f.search_band);
    assert!(
        z.abs() < 2.5 && !f.evidence.contains("usable band"),
        "z {z}: {}",
        f.evidence
    );
}

/// A false lag on both blocks beside 0.1 mrad coloured angle noise (cruise, 300 s, seed 21, a
/// true gyro resonance): over the accelerometer's usable band its time constant fell to its
/// bound (measured: 0.0005 ms), the finding rested on the band above and was named so, as a
/// `reference_lag` of both blocks. The band below, where a smooth finding must be confirmed,
/// now ends where the accelerometer's outputs stop being coherent with its inputs (below the
/// angles' noisy range from 19.6 Hz): the accelerometer's lag is set aside there, and said.
/// (What a finding the usable band does not determine says is tested in `usable_band`'s own
/// tests.)
#[test]
fn a_false_lag_the_usable_band_does_not_determine_is_set_aside() {
    let mut config = SimConfig::new(Regime::Cruise);
    (config.seed, config.duration_s, config.rate_hz) = (21, 300.0, 500.0);
    config.stand = StandImperfections {
        coloured_noise_rad: 1e-4,
        coloured_corner_hz: StandImperfections::real().coloured_corner_hz,
        ..StandImperfections::default()
    };
    config.effects = vec!["platform_resonance:gyro".parse().expect("effect spec")];
    let (_, run) = sim_common::simulated_run(&config);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
    assert!(
        !report
            .findings
            .iter()
            .any(|f| f.block == imu_attest::block::Block::Accel
                && matches!(f.effect, Effect::ReferenceLag | Effect::SensorLag)),
        "{named:?}"
    );
    assert!(
        named.contains(&(imu_attest::block::Block::Gyro, Effect::PlatformResonance)),
        "{named:?}"
    );
    let noisy = report.blocks["accel"]
        .noisy_angles
        .as_ref()
        .expect("the noisy range");
    assert!(
        noisy
            .usable_top_hz
            .is_some_and(|f| noisy.angles.is_some_and(|a| f < a.from_hz))
            && noisy.set_aside.contains(&Effect::SensorLag),
        "{noisy:?}"
    );
}
