//! Issue 15: the stand side is blamed for what is the stand's. On runs simulated with a real
//! stand's angle measurement (`--stand real`: coloured noise, a 30 Hz band limit, 1.5 ms of
//! latency) and no sensor effect, the lag both blocks show is named the angle measurement's
//! (`reference_lag`), never a sensor's first-order lag. Only this test knows how the runs were
//! made; the diagnosis sees the CSV and the sidecar's declared fields.

use imu_attest::block::Block;
use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

#[test]
fn a_lag_of_the_angle_measurement_is_the_stands_on_both_blocks() {
    let mut config = SimConfig::new(Regime::Cruise);
    config.seed = 3;
    config.duration_s = 120.0;
    config.stand = StandImperfections::real();
    let dir = tempfile::tempdir().expect("folder");
    let path = dir.path().join("run.csv");
    write_run(&simulate(&config).expect("simulated"), &path).expect("written");
    let run = load(&path, &LoadOptions::default()).expect("loaded");
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let names: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
    assert!(
        report.findings.iter().all(|f| f.effect != Effect::SensorLag),
        "no sensor lag: {names:?}"
    );
    for block in Block::BOTH {
        let f = report
            .findings
            .iter()
            .find(|f| f.block == block && f.effect == Effect::ReferenceLag)
            .unwrap_or_else(|| panic!("the stand's lag on the {block:?} block: {names:?}"));
        let t = f.parameters["T_s"].as_f64().expect("T");
        // The stand's 1.5 ms latency and 30 Hz band limit look like a lag of a few ms.
        assert!((1e-3..4e-3).contains(&t), "{t}");
    }
}
