//! A stand programme of strong sines (a lab's harmonic test signal) under the broadband motion:
//! the gyro's delay and the self-check are right. A bin beside a strong line holds the line's
//! power, so the `H1` estimate there is the model at the line's frequency; evaluated at the bin's
//! centre the model missed it by `2 pi (f_line - f_k) tau` in phase, many standard deviations at
//! a line (the delay 60-170 us short on 20 s runs of an independent simulator). The model is now
//! evaluated at the inputs' power centroid per bin (`spectral::centroid`): delay and K right.
//! Lines of different frequencies on different axes in one bin: each column of `H1` is compared
//! where its own input's power lies (the offset matrix, `ident::structural::align`): no
//! `poor_fit` left. Exact run: closed-form angles, the gyro's outputs the exact body rates
//! `tau` late through `K`, plus white noise; the truth is this file's.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::fmt::Write as _;

use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::rng::Rng;
use imu_attest::run::{LoadOptions, load};
use imu_attest::stand::kinematics::EulerSeries;

const RATE: f64 = 500.0;
const TAU: f64 = 0.006;
const K: [[f64; 3]; 3] = [
    [1.002, 0.001, -0.002],
    [0.0005, 0.998, 0.001],
    [0.001, -0.0015, 1.001],
];

/// Per axis: three large sines (2-4 degrees, 0.3-1.8 Hz, off the bins) and 300 small ones
/// spread over 0.1-20 Hz (the broadband part), all times the axis's `scale`.
fn programme(seed: u64, scale: [f64; 3]) -> Vec<Vec<(f64, f64, f64)>> {
    let mut rng = Rng::new(seed);
    (0..3)
        .map(|axis| {
            let mut s: Vec<(f64, f64, f64)> = (0..3)
                .map(|_| {
                    (
                        0.035 + 0.035 * rng.uniform(),
                        0.3 + 1.5 * rng.uniform(),
                        6.3 * rng.uniform(),
                    )
                })
                .collect();
            s.extend((0..300).map(|_| (1.5e-4, 0.1 + 19.9 * rng.uniform(), 6.3 * rng.uniform())));
            for c in &mut s {
                c.0 *= scale[axis];
            }
            s
        })
        .collect()
}

/// Angle (0), rate (1) or acceleration (2) of `axis` at time `t`.
fn value(sines: &[Vec<(f64, f64, f64)>], axis: usize, t: f64, derivative: usize) -> f64 {
    sines[axis]
        .iter()
        .map(|&(a, f, p)| {
            let w = 2.0 * std::f64::consts::PI * f;
            let x = w * t + p;
            [a * x.sin(), a * w * x.cos(), -a * w * w * x.sin()][derivative]
        })
        .sum()
}

/// The run's CSV text: `seconds` of the programme, gyro noise `asd` rad/s/sqrt(Hz), white angle
/// noise `angle_sd` rad.
fn run_csv(seed: u64, seconds: f64, asd: f64, scale: [f64; 3], angle_sd: f64) -> String {
    let sines = programme(seed, scale);
    let n = (seconds * RATE) as usize;
    let at = |shift: f64| {
        let series = |d: usize| -> [Vec<f64>; 3] {
            std::array::from_fn(|a| {
                (0..n)
                    .map(|i| value(&sines, a, i as f64 / RATE - shift, d))
                    .collect()
            })
        };
        EulerSeries {
            angle: series(0),
            rate: series(1),
            accel: series(2),
        }
    };
    let (measured, late) = (at(0.0), at(TAU));
    let body = late.body_rates();
    let mut rng = Rng::new(seed + 1);
    let sd = asd * (RATE / 2.0).sqrt();
    let mut csv = String::from("t,roll,yaw,pitch,gx,gy,gz\n");
    for i in 0..n {
        let w = [body[0][i], body[1][i], body[2][i]];
        let g: [f64; 3] =
            std::array::from_fn(|r| (0..3).map(|c| K[r][c] * w[c]).sum::<f64>() + sd * rng.normal());
        let a: [f64; 3] = std::array::from_fn(|axis| measured.angle[axis][i] + angle_sd * rng.normal());
        writeln!(
            csv,
            "{},{:e},{:e},{:e},{:e},{:e},{:e}",
            i as f64 / RATE,
            a[0],
            a[1],
            a[2],
            g[0],
            g[1],
            g[2]
        )
        .unwrap();
    }
    csv
}

#[test]
fn strong_sines_leave_the_delay_and_the_fit_right() {
    let dir = tempfile::tempdir().unwrap();
    for (seed, seconds) in [(3, 120.0), (4, 20.0)] {
        let path = dir.path().join(format!("sines{seed}.csv"));
        std::fs::write(&path, run_csv(seed, seconds, 5e-5, [1.0; 3], 0.0)).unwrap();
        std::fs::write(
            dir.path().join(format!("sines{seed}.json")),
            r#"{"angle_noise_rad": 1e-7}"#,
        )
        .unwrap();
        let run = load(&path, &LoadOptions::default()).unwrap();
        let id = identify_run(&run, &Settings::default()).unwrap();
        let gyro = &id.blocks[0];
        let fit = &gyro.structural;
        let ctx = format!(
            "seed {seed}, {seconds} s: tau {:.4} +- {:.4} ms, chi2/dof {:.2}",
            fit.tau_s * 1e3,
            fit.tau_std_s * 1e3,
            fit.chi2 / fit.dof as f64
        );
        assert_eq!(fit.order, 0, "{ctx}");
        assert!((fit.tau_s - TAU).abs() < 4.0 * fit.tau_std_s, "{ctx}");
        for (i, row) in K.iter().enumerate() {
            for (j, k) in row.iter().enumerate() {
                assert!(
                    (fit.k[i][j] - k).abs() < 4.0 * fit.k_std[i][j],
                    "{ctx}: K[{i}][{j}] {}",
                    fit.k[i][j]
                );
            }
        }
        // Lines of different frequencies on different axes in one bin: each column compared
        // where its own line lies (the offset matrix), the fit explains the data (chi2/dof was
        // 2.3 with one centroid per bin, said as `poor_fit` at the lines).
        eprintln!("{ctx}");
        assert!(
            !gyro
                .warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::PoorFit { .. })),
            "{ctx}: {:?}",
            gyro.warnings
        );
    }
}

/// A weak axis the data still determine is identified, not refused: yaw moved at 2 % of the other
/// axes' amplitude (4e-4 of their power, below the excitation ratio 1e-3 that refused it before;
/// an independent simulator's runs of 3.8e-4 to 9.3e-4 were refused, and identify right). Its
/// gains come with their (wider) sigmas and are right within them. Yaw and pitch held still (roll
/// alone moves), exactly or with the angle sensor's noise (1e-5 rad) moving them, is refused as
/// before. (Yaw alone held still is not: the kinematics still turn pitch's rate into the
/// body's y rate through roll, and the data determine that column.)
#[test]
fn a_weak_axis_is_identified_and_an_axis_held_still_refused() {
    use imu_attest::ident::IdentError;
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("weak", [0.15, 0.003, 0.15], 0.0),
        ("still", [1.0, 0.0, 0.0], 0.0),
        ("still_noisy", [1.0, 0.0, 0.0], 1e-5),
    ];
    for (name, scale, angle_sd) in cases {
        let path = dir.path().join(format!("{name}.csv"));
        std::fs::write(&path, run_csv(5, 120.0, 2e-6, scale, angle_sd)).unwrap();
        std::fs::write(
            dir.path().join(format!("{name}.json")),
            r#"{"angle_noise_rad": 1e-7}"#,
        )
        .unwrap();
        let run = load(&path, &LoadOptions::default()).unwrap();
        let result = identify_run(&run, &Settings::default());
        if name.starts_with("still") {
            let err = result.expect_err("refused");
            assert!(matches!(err, IdentError::NotExcited { .. }), "{err}");
            continue;
        }
        let id = result.unwrap();
        let fit = &id.blocks[0].structural;
        for (i, row) in K.iter().enumerate() {
            for (j, k) in row.iter().enumerate() {
                let z = (fit.k[i][j] - k) / fit.k_std[i][j];
                assert!(
                    z.abs() < 4.0,
                    "K[{i}][{j}] {} +- {}",
                    fit.k[i][j],
                    fit.k_std[i][j]
                );
            }
        }
        assert!(
            fit.k_std[1][1] > 3.0 * fit.k_std[0][0],
            "the weak axis's gains are the least precise"
        );
    }
}
