//! The gyro's mounting, roughly, for the angle-noise witness ([`super::colour`]).
//!
//! The witness turns the gyro's outputs into Euler rates with the exact kinematics at the
//! measured angles, which takes the outputs for body rates in platform axes. A misalignment of
//! milliradians, a scale error or the gyro's dynamics are linear filters the witness's
//! per-window regression absorbs (the dynamics with the witness split by axis where the attitude
//! moves, [`super::colour_split`]). A triad mounted **turned** (90 degrees about an axis, an axis
//! reversed) is not: the conversion's angle-dependent terms then mix the wrong axes, a part of
//! the motion that no linear filter of the witness explains, which the noise model takes for
//! angle noise. The observer then shrinks every block's inputs (found by a helper's independent
//! simulator: a gyro turned 90 degrees about y put its own `K` 3.4 % off, at 16 of its
//! deviations, and the accelerometer's, exactly the identity, 3.1 % off).
//!
//! So the outputs are regressed on the body rates of the plainly differentiated angles over the
//! whole record, both averaged over blocks of 20 ms (the angle noise that differentiation raises
//! at high frequency stays out; means removed), the outputs taken whole blocks later by their
//! lag behind the rates (found first, by a measure no mounting changes: `best_lag`), with the
//! rates' own changes as three more regressors (they take up the rest of the delay). The first
//! three coefficients are a rough static gain `G`: on simulated runs its orthogonal factor is
//! within about a degree of the mounting (the gyro's slow disturbance meets the slow motion by
//! chance), which is why only a turn beyond [`TURNED`] is taken out. Its nearest orthogonal matrix
//! `Q = U V^T` (polar decomposition, from the singular value decomposition `G = U S V^T`) is the
//! mounting. Where `Q` is more than [`TURNED`] from the identity, the witness uses `Q^T y`, the
//! outputs in platform axes; otherwise the outputs as they are (every run mounted as the
//! contract says keeps its witness bit for bit).
//!
//! Units: the outputs' own (only `Q`, dimensionless, is used); rad, Hz. Fewer than eight blocks,
//! non-finite sums, a gain element with a standard error above [`MAX_GAIN_ERROR`] (a weak axis),
//! a gain with a singular value below [`MIN_CONDITION`] of its largest (a dead channel, a still
//! axis): no mounting is read, the outputs are used as they are.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::kinematics::{EulerState, body_rate};

/// `||Q - I||_F` above which the mounting is taken out: 0.17, a turn of 7 degrees (`||Q - I||_F
/// = 2 sqrt(2) sin(angle / 2)`; a reversed axis gives at least 2). Well above the rough gain's
/// own error (about a degree), and below the 10-degree turn the helper's campaign found harmless
/// uncorrected (`K` within 0.02 % and 0.05 %).
pub const TURNED: f64 = 0.17;

/// Blocks per second the record is averaged into before the regression (20 ms each).
const BLOCKS_PER_S: f64 = 50.0;

/// The largest standard error of a rough gain's element, relative to its largest singular value,
/// for which its mounting is read: 0.05, a turn of about three degrees, well inside [`TURNED`].
const MAX_GAIN_ERROR: f64 = 0.05;

/// Smallest ratio of the rough gain's singular values for which its orthogonal factor means
/// anything.
pub const MIN_CONDITION: f64 = 0.1;

/// The mounting `Q` of a gyro whose outputs are `outputs`, against the body rates of `angles`
/// (module docs), when it is turned more than [`TURNED`]; `None` otherwise.
#[must_use]
pub fn turned_mounting(
    angles: [&[f64]; 3],
    outputs: [&[f64]; 3],
    sample_rate_hz: f64,
) -> Option<Matrix3<f64>> {
    let (rates, outputs, block_rate) = block_means(angles, outputs, sample_rate_hz)?;
    let reach = (LAG_REACH_S * block_rate).round() as usize;
    let lag = best_lag(&rates, &outputs, reach)?;
    let (rates, outputs) = aligned(rates, outputs, lag);
    let n = rates[0].len();
    if n < 8 {
        return None;
    }
    // Regressors: the body rates and their rates of change, which take up the delay (`K w(t - tau)
    // = K w(t) - tau K w'(t) + ...`: with the axes' motions in quadrature, as a Dutch roll's are,
    // a fit without them turned the gain by a degree and a half). Central differences, one-sided
    // at the ends.
    let change = |x: &[f64], i: usize| {
        let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
        (x[hi] - x[lo]) * block_rate / (hi - lo) as f64
    };
    let regressors: Vec<SVector<f64, 6>> = (0..n)
        .map(|i| {
            SVector::<f64, 6>::from_fn(|c, _| {
                if c < 3 {
                    rates[c][i]
                } else {
                    change(&rates[c - 3], i)
                }
            })
        })
        .collect();
    let regressor_mean = regressors.iter().sum::<SVector<f64, 6>>() / n as f64;
    let output_mean = Vector3::from_fn(|r, _| outputs[r].iter().sum::<f64>() / n as f64);
    let (mut yw, mut ww, mut yy) = (
        SMatrix::<f64, 3, 6>::zeros(),
        SMatrix::<f64, 6, 6>::zeros(),
        Vector3::<f64>::zeros(),
    );
    for (i, regressor) in regressors.iter().enumerate() {
        let w = regressor - regressor_mean;
        let y = Vector3::from_fn(|r, _| outputs[r][i]) - output_mean;
        yw += y * w.transpose();
        ww += w * w.transpose();
        yy += y.component_mul(&y);
    }
    let ww_inverse = ww.try_inverse()?;
    let coefficients = yw * ww_inverse;
    let gain: Matrix3<f64> = coefficients.fixed_columns::<3>(0).into_owned();
    if !gain.iter().all(|v| v.is_finite()) {
        return None;
    }
    let svd = gain.svd(true, true);
    let largest = svd.singular_values.max();
    if !(largest > 0.0 && svd.singular_values.min() >= MIN_CONDITION * largest) {
        return None;
    }
    // Each row's residual variance and each gain's standard error: a direction the motion
    // barely drives (a weak axis) leaves its column to the noise, which could turn `Q` by
    // itself; such a gain is not read.
    let dof = n.checked_sub(7)?.max(1) as f64;
    for r in 0..3 {
        let explained = (coefficients.row(r) * yw.row(r).transpose())[0];
        let variance = (yy[r] - explained).max(0.0) / dof;
        for c in 0..3 {
            let error = (variance * ww_inverse[(c, c)]).sqrt();
            if error.is_nan() || error > MAX_GAIN_ERROR * largest {
                return None;
            }
        }
    }
    let q = svd.u? * svd.v_t?;
    ((q - Matrix3::identity()).norm() > TURNED).then_some(q)
}

/// How far the outputs' lag behind the angles' rates is searched, either way, s: the reach of the
/// witness's own alignment (`super::colour`).
const LAG_REACH_S: f64 = 0.5;

/// The lag, in blocks, by which the outputs follow the rates: where their cross-covariance
/// `C(l) = sum_i y(i + l) w(i)^T` (means removed, per block of overlap) has the largest sum of
/// singular values, the Procrustes fit's, which no rotation or reflection of the outputs changes,
/// so the lag is found before the mounting is. Searched over `[-reach, reach]`, within a quarter
/// of the record; `None` when the best is at the search's end (the lag may lie beyond).
///
/// Why: the rates' changes take up a delay only while it is short beside the motion's time scale.
/// A real gyro written 38.5 ms behind its motion capture (a tapped triad, the motion's power at
/// 4-13 Hz) gave a rough gain with its x axis reversed: the mounting was read as turned, the
/// witness turned into the wrong axes explained little of the angles, the rest was taken for
/// angle noise and the gyro's `K` came out 3.4 % high, said by nothing. With the lag taken out
/// first, the changes take up only its fraction of a block.
fn best_lag(rates: &[Vec<f64>; 3], outputs: &[Vec<f64>; 3], reach: usize) -> Option<isize> {
    let n = rates[0].len();
    let reach = reach.min(n / 4) as isize;
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
    let (rate_mean, output_mean) = (
        rates.each_ref().map(|c| mean(c)),
        outputs.each_ref().map(|c| mean(c)),
    );
    let score = |lag: isize| {
        let (r0, y0, m) = overlap(n, lag);
        let mut c = Matrix3::<f64>::zeros();
        for i in 0..m {
            for (row, y) in outputs.iter().enumerate() {
                let y = y[y0 + i] - output_mean[row];
                for (col, w) in rates.iter().enumerate() {
                    c[(row, col)] += y * (w[r0 + i] - rate_mean[col]);
                }
            }
        }
        c.singular_values().sum() / m.max(1) as f64
    };
    // Nearest lags first, so that a tie (a flat output scores zero everywhere) keeps the nearest.
    let mut best = (0, score(0));
    for lag in (1..=reach).flat_map(|l| [l, -l]) {
        let s = score(lag);
        if s > best.1 {
            best = (lag, s);
        }
    }
    // At the search's end the lag may lie beyond it: no mounting is read from a misaligned fit.
    (reach == 0 || best.0.abs() < reach).then_some(best.0)
}

/// Where the rates and the outputs `lag` blocks later overlap: the first rate block, the first
/// output block, and how many.
fn overlap(n: usize, lag: isize) -> (usize, usize, usize) {
    let shift = lag.unsigned_abs().min(n);
    if lag >= 0 {
        (0, shift, n - shift)
    } else {
        (shift, 0, n - shift)
    }
}

/// The rates and the outputs `lag` blocks later, cut in place to their overlap.
fn aligned(
    mut rates: [Vec<f64>; 3],
    mut outputs: [Vec<f64>; 3],
    lag: isize,
) -> ([Vec<f64>; 3], [Vec<f64>; 3]) {
    let (r0, y0, m) = overlap(rates[0].len(), lag);
    for (columns, first) in [(&mut rates, r0), (&mut outputs, y0)] {
        for c in columns.iter_mut() {
            c.drain(..first);
            c.truncate(m);
        }
    }
    (rates, outputs)
}

/// Three body-rate columns, three output columns, per block, and the blocks' rate, Hz.
type BlockMeans = ([Vec<f64>; 3], [Vec<f64>; 3], f64);

/// Block means of 20 ms ([`BLOCKS_PER_S`]), and the blocks' rate, Hz: the body rates of the angles (central
/// differences, one-sided at the ends) and the outputs, in one pass without a full-length copy
/// (a 30-minute run at 1 kHz would otherwise hold 170 MB of temporaries). `None` for fewer than
/// eight blocks or unequal lengths.
fn block_means(angles: [&[f64]; 3], outputs: [&[f64]; 3], sample_rate_hz: f64) -> Option<BlockMeans> {
    let len = angles[0].len();
    if len < 3 || angles.iter().chain(&outputs).any(|c| c.len() != len) {
        return None;
    }
    let width = ((sample_rate_hz / BLOCKS_PER_S).round() as usize).max(1);
    let n = len / width;
    if n < 8 {
        return None;
    }
    let mut rates: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut means: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
    for block in 0..n {
        let (mut rate_sum, mut output_sum) = ([0.0; 3], [0.0; 3]);
        for i in block * width..(block + 1) * width {
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(len - 1));
            let state = EulerState {
                angle: [angles[0][i], angles[1][i], angles[2][i]],
                rate: std::array::from_fn(|a| {
                    (angles[a][hi] - angles[a][lo]) * sample_rate_hz / (hi - lo) as f64
                }),
                accel: [0.0; 3],
            };
            let w = body_rate(&state);
            for a in 0..3 {
                rate_sum[a] += w[a];
                output_sum[a] += outputs[a][i];
            }
        }
        for a in 0..3 {
            rates[a].push(rate_sum[a] / width as f64);
            means[a].push(output_sum[a] / width as f64);
        }
    }
    Some((rates, means, sample_rate_hz / width as f64))
}

/// The outputs in platform axes, `Q^T y` per sample.
#[must_use]
pub fn in_platform_axes(q: &Matrix3<f64>, outputs: [&[f64]; 3]) -> [Vec<f64>; 3] {
    let n = outputs[0].len();
    let qt = q.transpose();
    let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for i in 0..n {
        for (r, column) in out.iter_mut().enumerate() {
            column[i] = (0..3).map(|c| qt[(r, c)] * outputs[c][i]).sum();
        }
    }
    out
}

#[cfg(test)]
#[path = "mount_tests.rs"]
mod tests;
