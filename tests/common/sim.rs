//! Helpers shared by the tests that simulate runs: a run simulated with catalogue effects
//! hidden, written and loaded back from its CSV as a stand's run would be (the truth stays in
//! memory, in the returned `SimulatedRun`, for the test alone).

use imu_attest::run::{LoadOptions, Run, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, SimulatedRun, simulate};

/// A `duration_s` run of `regime` and `seed` with `effects` (`ID[:block][@scale]`) hidden.
///
/// # Panics
/// On an unknown effect or a failed simulation, write or load (a broken test).
#[must_use]
pub fn simulated_run_of(duration_s: f64, regime: Regime, seed: u64, effects: &[&str]) -> (SimulatedRun, Run) {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = duration_s;
    config.effects = effects.iter().map(|e| e.parse().expect("effect spec")).collect();
    simulated_run(&config)
}

/// The run `config` describes, written to a CSV and loaded back.
///
/// # Panics
/// On a failed simulation, write or load (a broken test).
#[must_use]
pub fn simulated_run(config: &SimConfig) -> (SimulatedRun, Run) {
    let sim = simulate(config).expect("simulated");
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("run.csv");
    write_run(&sim, &path).expect("written");
    let run = load(&path, &LoadOptions::default()).expect("loaded");
    (sim, run)
}
