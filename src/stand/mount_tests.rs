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
