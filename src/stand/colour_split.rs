//! The witness split by gyro axis, for [`super::colour_window`].
//!
//! The witness is the gyro's body rates turned into Euler rates at the measured angles,
//! `w_i = sum_j E_ij(angles) g_j`, and each measured angle is regressed on the three `w` with a
//! transfer that is constant (or a line) across a smoothing window. A gyro's own dynamics act per
//! **body** axis, `g_j = H_j omega_j` (a mount resonance, a filter, a scale factor), and where
//! the angles move the mixing `E_ij` moves with them: the part of `H_j omega_j` that reaches
//! Euler axis `i` through a varying `E_ij` is the mode modulated by the attitude's motion, which
//! no transfer of the three `w` takes. Left in, it passed for angle noise: on a simulated approach
//! run (seed 409, 1 kHz, 300 s) a gyro mount resonance about body z (20.6 Hz, damping 0.05)
//! reaches the yaw angle through `sin(roll)`, and the model read 33 times the white floor there
//! (13.9 at 18.5 Hz, 6.2 at 23.3 Hz); the observer shrank the accelerometer's inputs by it and
//! its order-3 model with a delay of -1.43 ms was chosen (`tests/identify_gyro_mount_resonance.rs`).
//!
//! So each angle `i` may also be regressed on the parts of its witness that each body axis makes,
//! `z_ij = E_ij g_j`: a transfer per body axis is then `sum_j H_j^-1 z_ij`, right as long as the
//! attitude changes little over the mode's decay. With the three `w` kept (they take a gyro's
//! small cross-couplings as far as the mixing is steady, which a per-axis split cannot), the extra
//! regressors for axis `i` are all its nonzero `z_ij` but one (`w_i` is their sum): [`SPLIT`].
//! Each takes one constant across the window (no slope of its own). They are added only where
//! they explain significantly more than noise would ([`SPLIT_F`], an F test on top of the constant
//! or the line the window chose): elsewhere the model is what it was, and with it every rule
//! downstream measured on it. The split also weighs each body axis's share of the gyro's own
//! noise apart, so where one axis's gyro is much noisier against its motion than another's it
//! can explain more of the angles than the three `w` do: the level then holds less of the gyro's
//! noise (which the model cannot tell from the angles', [`super::colour`]), the side the error
//! should lean to.
//!
//! "Body axis" is the witness's axis: a gyro mounted turned is first taken into platform axes
//! ([`super::mount`]), so for a turn that is not a signed permutation the split is by platform
//! axis, and a mode about one of the gyro's own axes is shared between two or three of them.
//!
//! Units and contracts: those of [`super::colour_window`]; a split regressor with no power (a
//! mixing that is zero, the attitude at zero) is left out, and a singular system keeps the
//! window's own fit.

use nalgebra::{Cholesky, SMatrix};
use num_complex::Complex64;

use super::witness_delay::euler_rates_of_axes;

/// The split regressors: `(Euler axis i, body axis j)` of each `z_ij = E_ij g_j` added. With the
/// kinematics' `E` (roll from all three body rates, yaw and pitch from y and z), these and the
/// three `w` span every `z_ij`.
pub(super) const SPLIT: [(usize, usize); 4] = [(0, 1), (0, 2), (1, 2), (2, 2)];

/// The F ratio (the split's explained power per regressor over the residual's per degree of
/// freedom) above which the split regressors are kept: 12, about the 1e-4 point of `F(2, 40)`
/// (one complex regressor in a window of 26 independent bins), so that on a gyro without
/// dynamics of its own an axis's level in a window changes about once in ten thousand (3e-4 in
/// the narrowest windows with the line fitted; far less for roll's two regressors, `F(4, .)`); a
/// mode modulated by the attitude scores in the hundreds.
pub(super) const SPLIT_F: f64 = 12.0;

/// The Euler rates each [`SPLIT`] regressor is: Euler axis `i` from the body rate about axis `j`
/// alone, at the angles given, sample by sample (0 where the conversion is not finite, as for
/// the witness itself).
pub(super) fn split_euler_rates(angles: [&[f64]; 3], body: [&[f64]; 3]) -> [Vec<f64>; 4] {
    // Each body axis the split uses turned once, all three Euler axes of it.
    let of_axis = [0, 1, 2].map(|j| {
        SPLIT.iter().any(|&(_, b)| b == j).then(|| {
            let mut axes = [false; 3];
            axes[j] = true;
            euler_rates_of_axes(angles, body, axes)
        })
    });
    SPLIT.map(|(i, j)| of_axis[j].as_ref().map_or_else(Vec::new, |r| r[i].clone()))
}

/// Most regressors of one fit: the three `w`, their slopes, two split regressors.
const MOST: usize = 8;

/// A window's scaled sums as the split fit reads them: the witness's Gram blocks (`a`: `w w^H`
/// times `u^0..=2`), the angles' cross with it (`b`: `y w^H` times `u^0..=1`), and with the split
/// regressors `v` (`yv = y v^H`, `wv = w v^H` times `u^0..=1`, `vv = v v^H`).
pub(super) struct SplitSums<'a> {
    pub a: [&'a SMatrix<Complex64, 3, 3>; 3],
    pub b: [&'a SMatrix<Complex64, 3, 3>; 2],
    pub yv: &'a SMatrix<Complex64, 3, 4>,
    pub wv: [&'a SMatrix<Complex64, 3, 4>; 2],
    pub vv: &'a SMatrix<Complex64, 4, 4>,
}

/// What the witness leaves of angle `axis` with its split regressors added to the window's fit
/// (the line's slope too where `slope`), uncorrected for the regressors fitted, and the split
/// regressors used; `None` where none has power or the system is singular.
pub(super) fn split_residual(
    sums: &SplitSums<'_>,
    axis: usize,
    slope: bool,
    total: f64,
    pivot_floor: f64,
) -> Option<(f64, usize)> {
    let base = if slope { 6 } else { 3 };
    let largest_w = (0..3).map(|i| sums.a[0][(i, i)].re).fold(0.0_f64, f64::max);
    let extra: Vec<usize> = (0..SPLIT.len())
        .filter(|&k| SPLIT[k].0 == axis && sums.vv[(k, k)].re > pivot_floor * largest_w)
        .collect();
    if extra.is_empty() {
        return None;
    }
    let n = base + extra.len();
    let mut g = SMatrix::<Complex64, MOST, MOST>::zeros();
    let mut b = SMatrix::<Complex64, 1, MOST>::zeros();
    for r in 0..3 {
        b[r] = sums.b[0][(axis, r)];
        for c in 0..3 {
            g[(r, c)] = sums.a[0][(r, c)];
            if slope {
                // Both off-diagonal blocks are `sum u w w^H` (the distances are real).
                g[(r, c + 3)] = sums.a[1][(r, c)];
                g[(r + 3, c)] = sums.a[1][(r, c)];
                g[(r + 3, c + 3)] = sums.a[2][(r, c)];
            }
        }
        if slope {
            b[r + 3] = sums.b[1][(axis, r)];
        }
    }
    for (m, &k) in extra.iter().enumerate() {
        let e = base + m;
        b[e] = sums.yv[(axis, k)];
        for r in 0..3 {
            g[(r, e)] = sums.wv[0][(r, k)];
            g[(e, r)] = sums.wv[0][(r, k)].conj();
            if slope {
                g[(r + 3, e)] = sums.wv[1][(r, k)];
                g[(e, r + 3)] = sums.wv[1][(r, k)].conj();
            }
        }
        for (m2, &k2) in extra.iter().enumerate() {
            g[(e, base + m2)] = sums.vv[(k, k2)];
        }
    }
    // Unused slots: the identity at the largest power, with nothing on the right.
    let largest = (0..n).map(|i| g[(i, i)].re).fold(0.0_f64, f64::max);
    for i in n..MOST {
        g[(i, i)] = Complex64::from(largest);
    }
    let c = Cholesky::new(g)?;
    let l = c.l_dirty();
    // A Hermitian positive-definite system's pivots are real and positive.
    if !(0..n).all(|i| l[(i, i)].re > 0.0 && l[(i, i)].re.powi(2) > pivot_floor * largest) {
        return None;
    }
    let explained = (b * c.solve(&b.adjoint()))[(0, 0)].re;
    // A NaN keeps the window's own fit (as the slope's test does).
    explained
        .is_finite()
        .then(|| ((total - explained).max(0.0), extra.len()))
}

#[cfg(test)]
#[path = "colour_split_tests.rs"]
mod tests;
