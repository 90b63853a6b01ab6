//! Exact kinematics of the gimbaled platform.
//!
//! Body angular rate from Euler rates (yaw -> pitch -> roll sequence, READING.md):
//! `wx = roll' + yaw' sin(pitch)`,
//! `wy = yaw' cos(pitch) cos(roll) + pitch' sin(roll)`,
//! `wz = pitch' cos(roll) - yaw' cos(pitch) sin(roll)`.
//!
//! A point at lever arm `r` (platform axes, from the centre of rotation, which does not move)
//! accelerates by `a = w' x r + w x (w x r)`. Specific force is `f = a - g_body` with
//! `g_body = C^T (0, -g, 0)`, i.e. `f = a + g (sin(pitch), cos(pitch) cos(roll), -cos(pitch) sin(roll))`,
//! and the vertical channel is g-compensated by subtracting `g` from `f_y`.
//!
//! Sign convention (checked by tests): at rest with pitch +0.1 rad the block reads
//! `f = (+0.979, -0.049, 0)` m/s^2; with roll +0.1 rad, `f = (0, -0.049, -0.979)`. The paper's
//! printed `-g*theta` in the x row has the opposite sign; ours follows from the rotation matrices.
//!
//! The Earth's rotation (7.3e-5 rad/s, constant in a laboratory) is not modelled: it is a bias,
//! and biases are removed before spectra.
//!
//! NaN contract: these are pointwise formulas; NaN in gives NaN out. Callers validate first.

use nalgebra::{Matrix3, Vector3};

/// Euler angles and their first two time derivatives at one instant, axis order
/// `[roll, yaw, pitch]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EulerState {
    /// `[roll, yaw, pitch]`, rad.
    pub angle: [f64; 3],
    /// Their time derivatives, rad/s.
    pub rate: [f64; 3],
    /// Their second time derivatives, rad/s^2.
    pub accel: [f64; 3],
}

/// Rotation about x by `a` (right-handed).
#[must_use]
pub fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Rotation about y by `a` (right-handed).
#[must_use]
pub fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Rotation about z by `a` (right-handed).
#[must_use]
pub fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Platform-to-level rotation `C = R_y(yaw) R_z(pitch) R_x(roll)` for angles `[roll, yaw, pitch]`.
#[must_use]
pub fn platform_to_level(angle: [f64; 3]) -> Matrix3<f64> {
    rot_y(angle[1]) * rot_z(angle[2]) * rot_x(angle[0])
}

/// Body angular rate (platform axes), rad/s.
#[must_use]
pub fn body_rate(e: &EulerState) -> Vector3<f64> {
    let [roll, _, pitch] = e.angle;
    let [droll, dyaw, dpitch] = e.rate;
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    Vector3::new(
        droll + dyaw * sp,
        dyaw * cp * cr + dpitch * sr,
        dpitch * cr - dyaw * cp * sr,
    )
}

/// Euler rates `[roll', yaw', pitch']` from a body rate `w` at the Euler `angle`: the inverse of
/// [`body_rate`] (`yaw' = (cos(roll) wy - sin(roll) wz) / cos(pitch)`,
/// `pitch' = sin(roll) wy + cos(roll) wz`, `roll' = wx - yaw' sin(pitch)`). Singular at
/// `pitch = +-pi/2` (gimbal lock), where it returns non-finite values.
#[must_use]
pub fn euler_rate(angle: [f64; 3], w: [f64; 3]) -> [f64; 3] {
    let [roll, _, pitch] = angle;
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let dyaw = (cr * w[1] - sr * w[2]) / cp;
    let dpitch = sr * w[1] + cr * w[2];
    [w[0] - dyaw * sp, dyaw, dpitch]
}

/// Body angular acceleration (platform axes), rad/s^2: the time derivative of [`body_rate`].
#[must_use]
pub fn body_angular_accel(e: &EulerState) -> Vector3<f64> {
    let [roll, _, pitch] = e.angle;
    let [dr, dy, dp] = e.rate;
    let [ddr, ddy, ddp] = e.accel;
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    Vector3::new(
        ddr + ddy * sp + dy * dp * cp,
        ddy * cp * cr - dy * dp * sp * cr - dy * dr * cp * sr + ddp * sr + dp * dr * cr,
        ddp * cr - dp * dr * sr - ddy * cp * sr + dy * dp * sp * sr - dy * dr * cp * cr,
    )
}

/// Gravity-projection part of the specific force, `-g_body = g C^T e_y`, platform axes, before
/// g-compensation.
#[must_use]
pub fn gravity_reaction(angle: [f64; 3], g: f64) -> Vector3<f64> {
    let [roll, _, pitch] = angle;
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    Vector3::new(g * sp, g * cp * cr, -g * cp * sr)
}

/// Rigid-body acceleration of the point at `lever_arm` (m), platform axes, m/s^2.
#[must_use]
pub fn lever_arm_accel(w: &Vector3<f64>, dw: &Vector3<f64>, lever_arm: &Vector3<f64>) -> Vector3<f64> {
    dw.cross(lever_arm) + w.cross(&w.cross(lever_arm))
}

/// Specific force at `lever_arm` with the vertical channel g-compensated (`f_y - g`), m/s^2.
#[must_use]
pub fn specific_force(e: &EulerState, lever_arm: &Vector3<f64>, g: f64) -> Vector3<f64> {
    let w = body_rate(e);
    let dw = body_angular_accel(e);
    let mut f = lever_arm_accel(&w, &dw, lever_arm) + gravity_reaction(e.angle, g);
    f.y -= g;
    f
}

/// Small-angle specific force, kept for explanation only: `a + g (pitch, 0, -roll)` with the
/// lever-arm acceleration linearised as `w' x r`.
#[must_use]
pub fn specific_force_small_angle(e: &EulerState, lever_arm: &Vector3<f64>, g: f64) -> Vector3<f64> {
    let dw = Vector3::from(e.accel);
    dw.cross(lever_arm) + Vector3::new(g * e.angle[2], 0.0, -g * e.angle[0])
}

/// Columns of Euler states, axis order `[roll, yaw, pitch]`, one entry per sample.
#[derive(Clone, Debug, Default)]
pub struct EulerSeries {
    /// Angles, rad.
    pub angle: [Vec<f64>; 3],
    /// First derivatives, rad/s.
    pub rate: [Vec<f64>; 3],
    /// Second derivatives, rad/s^2.
    pub accel: [Vec<f64>; 3],
}

impl EulerSeries {
    /// Number of samples (the length of the roll column).
    #[must_use]
    pub fn len(&self) -> usize {
        self.angle[0].len()
    }

    /// True when there are no samples.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The state at sample `n`. Panics if `n` is out of range (an internal invariant, never
    /// input-driven: callers iterate over `0..len()`).
    #[must_use]
    pub fn at(&self, n: usize) -> EulerState {
        let pick = |c: &[Vec<f64>; 3]| [c[0][n], c[1][n], c[2][n]];
        EulerState {
            angle: pick(&self.angle),
            rate: pick(&self.rate),
            accel: pick(&self.accel),
        }
    }

    /// Body rates at every sample, columns `[wx, wy, wz]`.
    #[must_use]
    pub fn body_rates(&self) -> [Vec<f64>; 3] {
        columns(self.len(), |n| body_rate(&self.at(n)))
    }

    /// Specific force (g-compensated) at `lever_arm` at every sample, columns `[fx, fy, fz]`.
    #[must_use]
    pub fn specific_forces(&self, lever_arm: [f64; 3], g: f64) -> [Vec<f64>; 3] {
        let r = Vector3::from(lever_arm);
        columns(self.len(), |n| specific_force(&self.at(n), &r, g))
    }

    /// How the specific force moves with the lever arm at every sample: column `3 i + l` is
    /// `d f_i / d r_l`, 1/s^2 (m/s^2 per m). The force is affine in the lever arm
    /// (`w' x r + w x (w x r)` plus gravity's part, which has none), so this is exact:
    /// `d f_i / d r_l = eps_ijl w'_j + w_i w_l - delta_il |w|^2`.
    #[must_use]
    pub fn lever_arm_jacobian(&self) -> [Vec<f64>; 9] {
        let len = self.len();
        let mut out: [Vec<f64>; 9] = std::array::from_fn(|_| Vec::with_capacity(len));
        for n in 0..len {
            let e = self.at(n);
            let (w, dw) = (body_rate(&e), body_angular_accel(&e));
            let w2 = w.norm_squared();
            for i in 0..3 {
                for l in 0..3 {
                    // eps_ijl w'_j: the one j that is neither i nor l, signed by the permutation.
                    let cross = match (i, l) {
                        (0, 1) => -dw.z,
                        (0, 2) => dw.y,
                        (1, 0) => dw.z,
                        (1, 2) => -dw.x,
                        (2, 0) => -dw.y,
                        (2, 1) => dw.x,
                        _ => 0.0,
                    };
                    let diagonal = if i == l { w2 } else { 0.0 };
                    out[3 * i + l].push(cross + w[i] * w[l] - diagonal);
                }
            }
        }
        out
    }
}

/// Evaluates a vector-valued function at every sample into three columns.
fn columns(len: usize, mut f: impl FnMut(usize) -> Vector3<f64>) -> [Vec<f64>; 3] {
    let mut out = [
        Vec::with_capacity(len),
        Vec::with_capacity(len),
        Vec::with_capacity(len),
    ];
    for n in 0..len {
        let v = f(n);
        for (col, value) in out.iter_mut().zip(v.iter()) {
            col.push(*value);
        }
    }
    out
}

#[cfg(test)]
#[path = "kinematics_tests.rs"]
mod tests;
