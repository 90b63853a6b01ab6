use nalgebra::{Matrix3, Rotation3, Vector3};

use super::*;
use crate::sim::regime::Regime;
use crate::sim::{SimConfig, SimulatedRun, simulate};

const RATE: f64 = 500.0;

fn sim(seed: u64) -> SimulatedRun {
    let mut c = SimConfig::new(Regime::Approach);
    c.seed = seed;
    c.duration_s = 60.0;
    c.rate_hz = RATE;
    simulate(&c).unwrap()
}

/// `m y` per sample.
fn turned(m: &Matrix3<f64>, y: &[Vec<f64>; 3]) -> [Vec<f64>; 3] {
    std::array::from_fn(|r| {
        (0..y[0].len())
            .map(|i| (0..3).map(|c| m[(r, c)] * y[c][i]).sum())
            .collect()
    })
}

fn views(x: &[Vec<f64>; 3]) -> [&[f64]; 3] {
    x.each_ref().map(Vec::as_slice)
}

/// The simulated gyro's outputs (its own scale errors, misalignments of a few mrad, delay, noise)
/// turned by a rotation or a reflection give that mounting within a degree or two (`||Q - P||`
/// below 0.04); as they are, or turned by three degrees, no mounting is read.
#[test]
fn a_turned_gyro_s_mounting_is_read_and_a_mounting_as_the_contract_says_is_left() {
    for seed in [1, 2] {
        let r = sim(seed);
        let angles = views(&r.angles);
        let gyro = r.gyro.as_ref().unwrap();
        let half_pi = std::f64::consts::FRAC_PI_2;
        let mountings = [
            *Rotation3::from_axis_angle(&Vector3::y_axis(), half_pi).matrix(),
            *Rotation3::from_axis_angle(&Vector3::z_axis(), -half_pi).matrix(),
            Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)),
            Matrix3::new(0.0, -1.0, 0.0, 0.0, 0.0, 1.0, -1.0, 0.0, 0.0),
            *Rotation3::from_axis_angle(&Vector3::x_axis(), 10f64.to_radians()).matrix(),
        ];
        for p in mountings {
            let q = turned_mounting(angles, views(&turned(&p, gyro)), RATE).expect("read");
            assert!((q - p).norm() < 0.04, "seed {seed}: {q} for {p}");
        }
        assert!(turned_mounting(angles, views(gyro), RATE).is_none());
        let three_degrees = *Rotation3::from_axis_angle(&Vector3::y_axis(), 3f64.to_radians()).matrix();
        assert!(turned_mounting(angles, views(&turned(&three_degrees, gyro)), RATE).is_none());
        // The outputs back in platform axes are the outputs as recorded, to rounding.
        let p = mountings[0];
        let back = in_platform_axes(&p, views(&turned(&p, gyro)));
        for (b, g) in back.iter().zip(gyro) {
            assert!(b.iter().zip(g).all(|(x, y)| (x - y).abs() < 1e-12));
        }
    }
}

/// Exact body rates of `angles` (central differences) plus white noise of `noise` rad/s.
fn noisy_rates(angles: &[Vec<f64>; 3], noise: f64, seed: u64) -> [Vec<f64>; 3] {
    let mut rng = crate::rng::Rng::new(seed);
    let rates = crate::stand::inputs::differentiate(views(angles), RATE).body_rates();
    rates.map(|c| c.iter().map(|v| v + noise * rng.normal()).collect())
}

/// A yaw a thousand times weaker than the other axes (its rates below the gyro's noise) leaves
/// the rough gain's yaw column to the noise: no mounting is read, turned or not, where the same
/// motion with yaw as strong as the others reads the turn.
#[test]
fn a_weak_axis_reads_no_mounting() {
    let r = sim(4);
    let turn = Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0);
    let mut weak = r.angles.clone();
    let mean = weak[1].iter().sum::<f64>() / weak[1].len() as f64;
    weak[1].iter_mut().for_each(|v| *v = mean + 1e-3 * (*v - mean));
    for (angles, readable) in [(&r.angles, true), (&weak, false)] {
        let outputs = noisy_rates(angles, 0.02, 9);
        let q = turned_mounting(views(angles), views(&turned(&turn, &outputs)), RATE);
        assert_eq!(q.is_some(), readable, "{q:?}");
        assert!(turned_mounting(views(angles), views(&outputs), RATE).is_none());
    }
}

/// A dead channel, a still record, empty or unequal columns: no mounting, no panic.
#[test]
fn degenerate_outputs_read_no_mounting() {
    let r = sim(3);
    let angles = views(&r.angles);
    let mut gyro = r.gyro.clone().unwrap();
    gyro[1].iter_mut().for_each(|v| *v = 0.0);
    assert!(turned_mounting(angles, views(&gyro), RATE).is_none());
    let still = [vec![0.1; 100], vec![0.2; 100], vec![0.3; 100]];
    assert!(turned_mounting(views(&still), views(&still), RATE).is_none());
    let empty: [&[f64]; 3] = [&[], &[], &[]];
    assert!(turned_mounting(empty, empty, RATE).is_none());
    assert!(turned_mounting(angles, views(&still), RATE).is_none());
}

/// Angles that move mostly at 4-12 Hz (a tapped or vibrated triad), 60 s at [`RATE`], with a slow
/// swing beside: two sines per axis, about 0.2 rad/s each.
fn quick_motion() -> [Vec<f64>; 3] {
    let tones = [
        [(5.3, 0.006), (9.1, 0.003)],
        [(6.7, 0.005), (11.2, 0.003)],
        [(4.4, 0.007), (8.3, 0.004)],
    ];
    std::array::from_fn(|axis| {
        (0..(60.0 * RATE) as usize)
            .map(|i| {
                let t = i as f64 / RATE;
                let slow = 0.05 * (2.0 * std::f64::consts::PI * 0.3 * t + axis as f64).sin();
                slow + tones[axis]
                    .iter()
                    .map(|(f, a)| a * (2.0 * std::f64::consts::PI * f * t + 0.7 * axis as f64).sin())
                    .sum::<f64>()
            })
            .collect()
    })
}

/// A gyro tens of milliseconds late behind a quick motion: its delay turns the fast motion's phase
/// by radians, which the rates' changes cannot take up (at 40 ms the 9-11 Hz motion comes back
/// with its sign reversed). Without the lag found first a gyro mounted as the contract says was
/// read as turned (a real tapped triad 38.5 ms late: its x axis read reversed); with it, no
/// mounting is read, and a turned one is read as it is, at every delay.
#[test]
fn a_late_gyro_behind_a_quick_motion_is_not_read_as_turned() {
    let angles = quick_motion();
    let rates = noisy_rates(&angles, 0.002, 5);
    let turn = *Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2).matrix();
    for late in [0_usize, 20, 45] {
        let gyro = rates.clone().map(|mut c| {
            c.rotate_right(late);
            c
        });
        let q = turned_mounting(views(&angles), views(&gyro), RATE);
        assert!(q.is_none(), "{late} samples late: read as turned {q:?}");
        let q = turned_mounting(views(&angles), views(&turned(&turn, &gyro)), RATE).expect("read");
        assert!((q - turn).norm() < 0.05, "{late} samples late: {q} for {turn}");
        // The lag in blocks of 20 ms, to a block.
        let (block_rates, outputs, block_rate) =
            block_means(views(&angles), views(&gyro), RATE).expect("blocks");
        let lag = best_lag(&block_rates, &outputs, 25).expect("inside the search");
        let due = late as f64 / RATE * block_rate;
        assert!(
            (lag as f64 - due).abs() <= 1.0,
            "{late} samples late: lag {lag} blocks, {due} due"
        );
    }
}
