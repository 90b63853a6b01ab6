//! The gyro's mounting, roughly, for the angle-noise witness ([`super::colour`]).
//!
//! The witness turns the gyro's outputs into Euler rates with the exact kinematics at the
//! measured angles, which takes the outputs for body rates in platform axes. A misalignment of
//! milliradians, a scale error or the gyro's dynamics are linear filters the witness's
//! per-window regression absorbs. A triad mounted **turned** (90 degrees about an axis, an axis
//! reversed) is not: the conversion's angle-dependent terms then mix the wrong axes, a part of
//! the motion that no linear filter of the witness explains, which the noise model takes for
//! angle noise. The observer then shrinks every block's inputs (found by a helper's independent
//! simulator: a gyro turned 90 degrees about y put its own `K` 3.4 % off, at 16 of its
//! deviations, and the accelerometer's, exactly the identity, 3.1 % off).
//!
//! So the outputs are regressed on the body rates of the plainly differentiated angles over the
//! whole record, both averaged over blocks of 20 ms (the angle noise that differentiation raises
//! at high frequency stays out; means removed), with the rates' own changes as three more
//! regressors (they take up the delay). The first three coefficients are a rough static gain
//! `G`: on simulated runs its orthogonal factor is within about a degree of the mounting (the
//! gyro's slow disturbance meets the slow motion by chance), which is why only a turn beyond
//! [`TURNED`] is taken out. Its nearest orthogonal matrix
//! `Q = U V^T` (polar decomposition, from the singular value decomposition `G = U S V^T`) is the
//! mounting. Where `Q` is more than [`TURNED`] from the identity, the witness uses `Q^T y`, the
//! outputs in platform axes; otherwise the outputs as they are (every run mounted as the
//! contract says keeps its witness bit for bit).
//!
//! Units: the outputs' own (only `Q`, dimensionless, is used); rad, Hz. Empty or non-finite
//! input, a gain with a singular value below [`MIN_CONDITION`] of its largest (a dead channel,
//! a still axis): no mounting is read, the outputs are used as they are.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::inputs::differentiate;

/// `||Q - I||_F` above which the mounting is taken out: 0.17, a turn of 7 degrees (`||Q - I||_F
/// = 2 sqrt(2) sin(angle / 2)`; a reversed axis gives at least 2). Well above the rough gain's
/// own error (about a degree), and below the 10-degree turn the helper's campaign found harmless
/// uncorrected (`K` within 0.02 % and 0.05 %).
pub const TURNED: f64 = 0.17;

/// Blocks per second the record is averaged into before the regression (20 ms each).
const BLOCKS_PER_S: f64 = 50.0;

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
    let n = angles[0].len();
    if n < 3 || outputs.iter().any(|c| c.len() != n) {
        return None;
    }
    // Means over blocks of 20 ms: the motion's strong low-frequency part, not the angle noise
    // that differentiation raises at high frequency (errors in variables turned the gain).
    let width = ((sample_rate_hz / BLOCKS_PER_S).round() as usize).max(1);
    let n = n / width;
    if n < 3 {
        return None;
    }
    let block_means = |x: &[f64]| -> Vec<f64> {
        x.chunks_exact(width)
            .map(|c| c.iter().sum::<f64>() / width as f64)
            .collect()
    };
    let rates = differentiate(angles, sample_rate_hz)
        .body_rates()
        .map(|c| block_means(&c));
    let outputs = outputs.map(block_means);
    let outputs = outputs.each_ref().map(Vec::as_slice);
    let block_rate = sample_rate_hz / width as f64;
    // Regressors: the body rates and their rates of change, which take up the delay (`K w(t - tau)
    // = K w(t) - tau K w'(t) + ...`: with the axes' motions in quadrature, as a Dutch roll's are,
    // a fit without them turned the gain by a degree and a half).
    let step = |x: &[f64], i: usize| 0.5 * (x[(i + 1).min(n - 1)] - x[i.saturating_sub(1)]) * block_rate;
    let regressors = |i: usize| -> [f64; 6] {
        std::array::from_fn(|c| {
            if c < 3 {
                rates[c][i]
            } else {
                step(&rates[c - 3], i)
            }
        })
    };
    let mean = |x: &[f64]| x.iter().sum::<f64>() / n as f64;
    let output_mean = outputs.map(mean);
    let mut regressor_mean = [0.0; 6];
    for i in 0..n {
        regressor_mean
            .iter_mut()
            .zip(regressors(i))
            .for_each(|(m, v)| *m += v / n as f64);
    }
    let (mut yw, mut ww) = (SMatrix::<f64, 3, 6>::zeros(), SMatrix::<f64, 6, 6>::zeros());
    for i in 0..n {
        let w = SVector::<f64, 6>::from_fn(|c, _| regressors(i)[c] - regressor_mean[c]);
        let y = Vector3::from_fn(|r, _| outputs[r][i] - output_mean[r]);
        yw += y * w.transpose();
        ww += w * w.transpose();
    }
    let coefficients = yw * ww.try_inverse()?;
    let gain: Matrix3<f64> = coefficients.fixed_columns::<3>(0).into_owned();
    if !gain.iter().all(|v| v.is_finite()) {
        return None;
    }
    let svd = gain.svd(true, true);
    let largest = svd.singular_values.max();
    if !(largest > 0.0 && svd.singular_values.min() >= MIN_CONDITION * largest) {
        return None;
    }
    let q = svd.u? * svd.v_t?;
    ((q - Matrix3::identity()).norm() > TURNED).then_some(q)
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
