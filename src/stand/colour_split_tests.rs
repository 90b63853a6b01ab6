use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x4, Matrix4, Vector3, Vector4};

use super::*;
use crate::rng::Rng;
use crate::stand::kinematics::euler_rate;

/// Random bins: the angles `y`, the witness `w`, the split regressors `v`, and distances `u`.
struct Bins {
    y: Vec<Vector3<Complex64>>,
    w: Vec<Vector3<Complex64>>,
    v: Vec<Vector4<Complex64>>,
    u: Vec<f64>,
}

fn random_bins(seed: u64, n: usize) -> Bins {
    let mut rng = Rng::new(seed);
    let mut c = || Complex64::new(rng.normal(), rng.normal());
    let w: Vec<Vector3<Complex64>> = (0..n).map(|_| Vector3::new(c(), c(), c())).collect();
    let v: Vec<Vector4<Complex64>> = (0..n).map(|_| Vector4::new(c(), c(), c(), c())).collect();
    // The angles: a line in frequency of the witness, a part of each split regressor, noise.
    let u: Vec<f64> = (0..n)
        .map(|k| (k as f64 - 0.5 * n as f64) / (0.5 * n as f64))
        .collect();
    let y = (0..n)
        .map(|k| {
            let line = Complex64::new(1.0, 0.3 * u[k]);
            Vector3::new(
                w[k][0] * line + v[k][0] * 0.4 - v[k][1] * 0.2 + c() * 0.1,
                w[k][1] * line + w[k][0] * 0.05 + v[k][2] * 0.3 + c() * 0.1,
                w[k][2] * line + v[k][3] * 0.5 + c() * 0.1,
            )
        })
        .collect();
    Bins { y, w, v, u }
}

/// The sums `unexplained` scales, from the bins.
struct Accumulated {
    a: [Matrix3<Complex64>; 3],
    b: [Matrix3<Complex64>; 2],
    yv: Matrix3x4<Complex64>,
    wv: [Matrix3x4<Complex64>; 2],
    vv: Matrix4<Complex64>,
}

fn accumulate(bins: &Bins) -> Accumulated {
    let mut s = Accumulated {
        a: [Matrix3::zeros(); 3],
        b: [Matrix3::zeros(); 2],
        yv: Matrix3x4::zeros(),
        wv: [Matrix3x4::zeros(); 2],
        vv: Matrix4::zeros(),
    };
    for k in 0..bins.u.len() {
        let (y, w, v, u) = (&bins.y[k], &bins.w[k], &bins.v[k], Complex64::from(bins.u[k]));
        s.a[0] += w * w.adjoint();
        s.a[1] += w * w.adjoint() * u;
        s.a[2] += w * w.adjoint() * u * u;
        s.b[0] += y * w.adjoint();
        s.b[1] += y * w.adjoint() * u;
        s.yv += y * v.adjoint();
        s.wv[0] += w * v.adjoint();
        s.wv[1] += w * v.adjoint() * u;
        s.vv += v * v.adjoint();
    }
    s
}

fn split_sums(s: &Accumulated) -> SplitSums<'_> {
    SplitSums {
        a: [&s.a[0], &s.a[1], &s.a[2]],
        b: [&s.b[0], &s.b[1]],
        yv: &s.yv,
        wv: [&s.wv[0], &s.wv[1]],
        vv: &s.vv,
    }
}

/// The naive reference: the regressors as columns, least squares by the SVD, the residual's
/// power.
fn least_squares_residual(bins: &Bins, axis: usize, slope: bool) -> f64 {
    let n = bins.u.len();
    let extra: Vec<usize> = (0..SPLIT.len()).filter(|&k| SPLIT[k].0 == axis).collect();
    let columns = if slope { 6 } else { 3 } + extra.len();
    let x = DMatrix::from_fn(n, columns, |k, c| match c {
        0..3 => bins.w[k][c],
        3..6 if slope => bins.w[k][c - 3] * bins.u[k],
        _ => bins.v[k][extra[c - if slope { 6 } else { 3 }]],
    });
    let y = DVector::from_fn(n, |k, _| bins.y[k][axis]);
    let beta = x.clone().svd(true, true).solve(&y, 1e-12).expect("solves");
    (y - x * beta).norm_squared()
}

/// Each axis's residual with its split regressors equals the least-squares fit's over the same
/// regressors (by the SVD of the columns: a brute-force reference), with the constant and with the line.
#[test]
fn the_split_fit_is_the_least_squares_fit() {
    let bins = random_bins(21, 60);
    let sums = accumulate(&bins);
    for slope in [false, true] {
        for axis in 0..3 {
            let total: f64 = bins.y.iter().map(|y| y[axis].norm_sqr()).sum();
            let (left, used) = split_residual(&split_sums(&sums), axis, slope, total, 1e-12).expect("fits");
            let want = least_squares_residual(&bins, axis, slope);
            let expected_used = SPLIT.iter().filter(|(i, _)| *i == axis).count();
            assert_eq!(used, expected_used);
            assert!(
                (left / want - 1.0).abs() < 1e-8,
                "axis {axis}, slope {slope}: {left} vs {want}"
            );
            // The noise is 0.02 per bin: with the line, what is left is about it, not the split's
            // parts.
            if slope {
                assert!(left / 60.0 < 0.03, "axis {axis}: {}", left / 60.0);
            }
        }
    }
}

/// A split regressor without power (a mixing that is zero: the attitude at zero) is left out;
/// an axis with none has no split fit.
#[test]
fn a_split_regressor_without_power_is_left_out() {
    let mut bins = random_bins(22, 60);
    for v in &mut bins.v {
        v[0] = Complex64::default();
        v[2] = Complex64::default();
    }
    let sums = accumulate(&bins);
    let total: f64 = bins.y.iter().map(|y| y[0].norm_sqr()).sum();
    let (_, used) = split_residual(&split_sums(&sums), 0, false, total, 1e-12).expect("fits");
    assert_eq!(used, 1, "roll keeps its second split regressor only");
    assert!(split_residual(&split_sums(&sums), 1, false, 1.0, 1e-12).is_none());
}

/// The split regressors are Euler rates of one body axis each: at a roll of 0.3 rad and a pitch
/// of 0.2 rad they sum with the rest to the whole conversion (`euler_rate`), and yaw and pitch
/// get nothing from the body's x axis.
#[test]
fn the_split_rates_add_up_to_the_witness() {
    let angles = [[0.3], [0.7], [0.2]];
    let body = [[0.5], [-1.1], [0.8]];
    let split = split_euler_rates(angles.each_ref().map(|a| &a[..]), body.each_ref().map(|b| &b[..]));
    let whole = euler_rate([0.3, 0.7, 0.2], [0.5, -1.1, 0.8]);
    let only_x = euler_rate([0.3, 0.7, 0.2], [0.5, 0.0, 0.0]);
    let only_y = euler_rate([0.3, 0.7, 0.2], [0.0, -1.1, 0.0]);
    assert!(only_x[1].abs() < 1e-300);
    assert!(only_x[2].abs() < 1e-300);
    // Roll: x's part plus the two split parts.
    assert!((only_x[0] + split[0][0] + split[1][0] - whole[0]).abs() < 1e-12);
    // Yaw and pitch: y's part plus z's split part.
    assert!((only_y[1] + split[2][0] - whole[1]).abs() < 1e-12);
    assert!((only_y[2] + split[3][0] - whole[2]).abs() < 1e-12);
}
