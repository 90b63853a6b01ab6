//! The reference's share of a block's disturbance (`noise::share`, the dashed line and the
//! explanation under the app's disturbance PSD), on both blocks, against pairs of runs that
//! differ only in the stand's angle noise: a simulated run, and the same run with white noise
//! added to its angles (and declared in its sidecar, as a stand's data sheet would). What the
//! extra angle noise adds to the measured disturbance PSD is what the share says it adds, and
//! where the share calls the disturbance the reference's, the run without the extra noise has a
//! disturbance several times smaller there. The identifier and the share never see the
//! simulator's truth; the test compares two measured disturbances.

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::identified::bare_model;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::BlockModel;
use imu_attest::noise::reference::AccelGeometry;
use imu_attest::noise::share::{ReferenceShare, reference_share};
use imu_attest::rng::Rng;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;

use crate::common::sim;

/// White noise added to the angles, rad (a few times the simulator's 1e-5 rad).
const EXTRA_RAD: f64 = 5e-5;

/// `run` identified with the default settings: each block's model and the reference's share.
fn blocks_of(run: Run) -> Vec<(Block, BlockModel, ReferenceShare)> {
    let run = Arc::new(run);
    let settings = Settings {
        blocks: Settings::default().blocks_for(&run.blocks()),
        ..Settings::default()
    };
    let mut session = Session::new(run.clone());
    let mut model = bare_model(&mut session, &settings, &mut |_| {}).expect("identified");
    let motion = session.motion().expect("observer");
    Block::BOTH
        .iter()
        .map(|&b| {
            let m = model.blocks.remove(b.name()).expect("block identified");
            let share = reference_share(b, &m, &motion, AccelGeometry::of(&run));
            (b, m, share)
        })
        .collect()
}

/// `run` with white noise of `EXTRA_RAD` added to its angles and declared in its sidecar.
fn noisier(mut run: Run, seed: u64) -> Run {
    let mut rng = Rng::new(seed);
    for axis in &mut run.angles {
        for v in axis.iter_mut() {
            *v += EXTRA_RAD * rng.normal();
        }
    }
    run.sidecar.angle_noise_rad =
        Some((run.sidecar.angle_noise_rad.unwrap_or(0.0).powi(2) + EXTRA_RAD * EXTRA_RAD).sqrt());
    run
}

/// Bin of `m` at `f_hz`.
fn bin(m: &BlockModel, f_hz: f64) -> Option<usize> {
    m.frequency_hz.iter().position(|&f| (f - f_hz).abs() < 1e-9)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn the_angle_noise_added_to_a_run_shows_in_its_disturbance_as_the_share_says() {
    for (regime, seed) in [(Regime::Cruise, 3), (Regime::Approach, 4)] {
        let (_, run) = sim::simulated_run_of(120.0, regime, seed, &[]);
        let quiet_blocks = blocks_of(run.clone());
        let noisy_blocks = blocks_of(noisier(run, seed + 100));
        for ((block, quiet, quiet_share), (_, noisy, share)) in quiet_blocks.iter().zip(&noisy_blocks) {
            for i in 0..3 {
                // Where the added part dominates, what was added is what the share adds.
                let ratios: Vec<f64> = noisy
                    .frequency_hz
                    .iter()
                    .enumerate()
                    .filter_map(|(k, &f)| {
                        let q = bin(quiet, f)?;
                        let before = quiet.noise_psd.re[q][i][i];
                        let added = share.psd[i][k] - quiet_share.psd[i][q];
                        (added > 4.0 * before).then(|| (noisy.noise_psd.re[k][i][i] - before) / added)
                    })
                    .collect();
                assert!(
                    ratios.len() >= 20,
                    "{regime:?} seed {seed} {block:?} channel {i}: {} bins where the added noise dominates",
                    ratios.len()
                );
                let m = median(ratios);
                assert!(
                    (0.7..1.4).contains(&m),
                    "{regime:?} seed {seed} {block:?} channel {i}: measured / predicted addition {m}"
                );
                // ... and the frequencies named the reference's are where the disturbance grew.
                assert!(
                    !share.dominated_hz[i].is_empty(),
                    "{regime:?} seed {seed} {block:?} channel {i}: no range named"
                );
                let grown: Vec<f64> = share.dominated_hz[i]
                    .iter()
                    .flat_map(|&[a, b]| {
                        noisy
                            .frequency_hz
                            .iter()
                            .enumerate()
                            .filter(move |(_, f)| **f >= a && **f <= b)
                    })
                    .filter_map(|(k, &f)| {
                        Some(noisy.noise_psd.re[k][i][i] / quiet.noise_psd.re[bin(quiet, f)?][i][i])
                    })
                    .collect();
                assert!(
                    !grown.is_empty(),
                    "{regime:?} seed {seed} {block:?} channel {i}: ranges without bins"
                );
                assert!(
                    median(grown.clone()) > 2.0,
                    "{regime:?} seed {seed} {block:?} channel {i}: named the reference's where it did not grow"
                );
            }
        }
    }
}
