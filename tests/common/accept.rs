//! Helpers of the tests of accepted effects (`accept_effects`, `accept_judged`): a run's model
//! as identified and with effects accepted, default settings, and the normalised errors.

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::extended_model;
use imu_attest::diagnose::identified::identified_model;
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::{BlockModel, Model};
use imu_attest::sim::truth::BlockTruth;

/// The run's model with `accepted` effects, default settings.
pub fn extend(run: imu_attest::run::Run, accepted: &[(Block, Effect)]) -> Model {
    extended_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        accepted,
        &mut |_| {},
    )
    .expect("extended")
}

/// The run's model as identified, default settings (`identify` without effects).
pub fn identify(run: imu_attest::run::Run) -> Model {
    identified_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        &mut |_| {},
    )
    .expect("identified")
}

/// Normalised errors `(estimate - truth) / std` of K's nine elements and of tau.
pub fn gain_and_delay_z(m: &BlockModel, t: &BlockTruth) -> (Vec<f64>, f64) {
    let mut k = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let sd = m.fit.k_std[i][j].expect("K's deviation");
            k.push((m.k[i][j] - t.k[i][j]) / sd);
        }
    }
    (k, (m.tau_s - t.tau_s) / m.fit.tau_std_s.expect("tau's deviation"))
}

/// The root mean square of `v`.
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}
