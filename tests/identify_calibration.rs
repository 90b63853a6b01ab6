//! Issue 13's calibration on stands that are not perfect: twelve simulated runs (seeds 1-12, the
//! three regimes cycled, 120 s at 500 Hz) with the imperfections real stands have (`--stand
//! real`: coloured angle noise below 5 Hz, 1.5 ms angle latency, a zero-phase band limit at
//! 30 Hz), identified with default settings from the written CSV. The truth is read here only:
//! the delay expected is the sensor's minus the angle latency (delays are relative to the angle
//! measurement, contract section 2).
//!
//! Asserted for both blocks, as the "Done when" states it: no order above 0 on runs
//! without sensor dynamics, and honest sigmas: the normalised errors `(K - K_true) / K_std` and
//! `(tau - tau_true) / tau_std` with rms within 0.7-1.4 and at most 10 % beyond 2 sigma; K within
//! 0.3 % (relative Frobenius) for the gyro and 0.5 % for the accelerometer (the 0.3 % is
//! met on these 120 s runs only just, 0.299 %: see the README). Measured with the `H1` estimate
//! (the default since 26 Nov; release build of the same code): gyro K error max 0.152 %, K z rms
//! 0.89, tau z rms 1.15; accelerometer K error max 0.299 %, K z rms 0.91, tau z rms 1.00 (1 of 12
//! beyond 2 sigma; through the causal Wiener estimate it was 1.21 and 2 of 12, which is why the
//! accelerometer's delay was not asserted before). The second test does the same at 1 kHz.

use imu_attest::block::Block;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

/// Normalised errors and relative K errors of one block over the campaign.
#[derive(Default)]
struct Scatter {
    k_z: Vec<f64>,
    tau_z: Vec<f64>,
    k_error: Vec<f64>,
    orders: Vec<usize>,
    chi2_per_dof: Vec<f64>,
}

impl Scatter {
    fn rms(z: &[f64]) -> f64 {
        (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt()
    }

    fn beyond_2_sigma(z: &[f64]) -> f64 {
        z.iter().filter(|v| v.abs() > 2.0).count() as f64 / z.len() as f64
    }

    fn summary(&self, block: Block) -> String {
        format!(
            "{block:?}: K error max {:.3} %, K z rms {:.2} ({:.0} % beyond 2 sigma), tau z rms {:.2} \
             ({:.0} %), orders {:?}, chi2/dof {:.2}-{:.2}",
            self.k_error.iter().copied().fold(0.0, f64::max) * 100.0,
            Self::rms(&self.k_z),
            Self::beyond_2_sigma(&self.k_z) * 100.0,
            Self::rms(&self.tau_z),
            Self::beyond_2_sigma(&self.tau_z) * 100.0,
            self.orders,
            self.chi2_per_dof.iter().copied().fold(f64::INFINITY, f64::min),
            self.chi2_per_dof.iter().copied().fold(0.0, f64::max)
        )
    }
}

/// Simulates `seeds` (regimes cycled) on a `--stand real` stand, writes and reads each run, and
/// identifies it with default settings; the truth is read here only.
fn campaign(seeds: std::ops::RangeInclusive<u64>, rate_hz: f64, duration_s: f64) -> (Scatter, Scatter) {
    let regimes = [Regime::Cruise, Regime::TurbulentCruise, Regime::Approach];
    let (mut gyro, mut accel) = (Scatter::default(), Scatter::default());
    let dir = tempfile::tempdir().expect("temp dir");
    for seed in seeds {
        let mut config = SimConfig::new(regimes[(seed % 3) as usize]);
        config.seed = seed;
        config.duration_s = duration_s;
        config.rate_hz = rate_hz;
        config.stand = StandImperfections::real();
        let sim = simulate(&config).expect("simulated");
        let path = dir.path().join(format!("run{seed}.csv"));
        write_run(&sim, &path).expect("written");
        let run = load(&path, &LoadOptions::default()).expect("loads");
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            let (truth, scatter) = match b.block {
                Block::Gyro => (sim.sidecar.truth.gyro.as_ref().expect("gyro truth"), &mut gyro),
                Block::Accel => (sim.sidecar.truth.accel.as_ref().expect("accel truth"), &mut accel),
            };
            let fit = &b.structural;
            let (mut err, mut norm) = (0.0, 0.0);
            for i in 0..3 {
                for j in 0..3 {
                    let d = fit.k[i][j] - truth.k[i][j];
                    err += d * d;
                    norm += truth.k[i][j] * truth.k[i][j];
                    scatter.k_z.push(d / fit.k_std[i][j]);
                }
            }
            scatter.k_error.push((err / norm).sqrt());
            let tau_true = truth.tau_s - config.stand.latency_s;
            scatter.tau_z.push((fit.tau_s - tau_true) / fit.tau_std_s);
            scatter.orders.push(fit.order);
            scatter.chi2_per_dof.push(fit.chi2 / fit.dof as f64);
        }
    }
    eprintln!("{}", gyro.summary(Block::Gyro));
    eprintln!("{}", accel.summary(Block::Accel));
    (gyro, accel)
}

/// The calibration bounds: rms of the normalised errors within 0.7-1.4, at most 10 %
/// beyond 2 sigma.
fn assert_honest(block: Block, s: &Scatter, z: &[f64]) {
    let rms = Scatter::rms(z);
    assert!((0.7..=1.4).contains(&rms), "{}", s.summary(block));
    assert!(Scatter::beyond_2_sigma(z) <= 0.10, "{}", s.summary(block));
}

/// The fit's weights are the estimate's covariance: a model that holds (order 0, no effect) has
/// chi2/dof near 1 on every run. Measured with `H1` 0.91-1.23 over 168 block fits of
/// `--stand real` runs (README); through the causal `W0` on these runs 0.52-0.76 (500 Hz: the
/// weights counted noise the projection had removed) and 0.57-2.46 (1 kHz).
fn assert_weights_calibrated(block: Block, s: &Scatter) {
    assert!(
        s.chi2_per_dof.iter().all(|c| (0.8..=1.4).contains(c)),
        "{}",
        s.summary(block)
    );
}

/// K and delay sigmas honest and the weights calibrated.
fn assert_calibrated(block: Block, s: &Scatter) {
    assert_honest(block, s, &s.k_z);
    assert_honest(block, s, &s.tau_z);
    assert_weights_calibrated(block, s);
}

#[test]
fn imperfect_stands_give_order_0_small_errors_and_honest_gyro_sigmas() {
    let (gyro, accel) = campaign(1..=12, 500.0, 120.0);
    for (block, s, k_limit) in [(Block::Gyro, &gyro, 0.003), (Block::Accel, &accel, 0.005)] {
        assert!(s.orders.iter().all(|&o| o == 0), "{}", s.summary(block));
        assert!(s.k_error.iter().all(|&e| e < k_limit), "{}", s.summary(block));
    }
    for (block, s) in [(Block::Gyro, &gyro), (Block::Accel, &accel)] {
        assert_calibrated(block, s);
    }
}

/// At 1 kHz the reference's 30 Hz band limit lies far inside the grid. Fitted through the causal
/// Wiener estimate (the default until 26 Nov), whose every bin depends on the spectra at every
/// frequency, the accelerometer's K deviations were optimistic on these very runs (seeds 13-24,
/// 80 s: z rms 1.50, 14 % beyond 2 sigma, K error max 0.647 %); through `H1` (the default now)
/// 0.92 and 4 %, K error max 0.312 %, delay z rms 0.91 (release build, README). Asserted: orders
/// 0, K within 0.4 % (gyro) and 0.5 % (accelerometer), and both blocks' K and delay sigmas honest.
#[test]
fn at_1_khz_a_band_limited_reference_leaves_both_blocks_sigmas_honest() {
    let (gyro, accel) = campaign(13..=24, 1000.0, 80.0);
    for (block, s, k_limit) in [(Block::Gyro, &gyro, 0.004), (Block::Accel, &accel, 0.005)] {
        assert!(s.orders.iter().all(|&o| o == 0), "{}", s.summary(block));
        assert!(s.k_error.iter().all(|&e| e < k_limit), "{}", s.summary(block));
        assert_calibrated(block, s);
    }
}
