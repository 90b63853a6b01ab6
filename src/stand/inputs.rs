//! The blocks' inputs computed from an estimate of the platform motion (the paper's coordinate
//! converter): body rate for the gyro block, specific force at the declared lever arm, vertical
//! channel g-compensated, for the accelerometer block. Units rad/s and m/s^2, platform axes.

use super::kinematics::EulerSeries;

/// Input channel names of the gyro block (contract section 4).
pub const GYRO_INPUTS: [&str; 3] = ["wx", "wy", "wz"];
/// Input channel names of the accelerometer block (contract section 4).
pub const ACCEL_INPUTS: [&str; 3] = ["fx", "fy", "fz"];

/// Gyro block input: body angular rate, columns `[wx, wy, wz]`, rad/s.
#[must_use]
pub fn gyro_input(motion: &EulerSeries) -> [Vec<f64>; 3] {
    motion.body_rates()
}

/// Accelerometer block input: specific force at `lever_arm_m` with `f_y - g`, columns
/// `[fx, fy, fz]`, m/s^2.
#[must_use]
pub fn accel_input(motion: &EulerSeries, lever_arm_m: [f64; 3], g_mps2: f64) -> [Vec<f64>; 3] {
    motion.specific_forces(lever_arm_m, g_mps2)
}

/// Plain numerical differentiation of measured angles (central differences, one-sided at the
/// ends), the reference the observer is compared against. Needs at least 3 samples; fewer gives
/// zero derivatives.
#[must_use]
pub fn differentiate(angles: [&[f64]; 3], sample_rate_hz: f64) -> EulerSeries {
    let mut out = EulerSeries::default();
    for axis in 0..3 {
        let x = angles[axis];
        let n = x.len();
        out.angle[axis] = x.to_vec();
        let mut rate = vec![0.0; n];
        let mut accel = vec![0.0; n];
        if n >= 3 {
            for i in 1..n - 1 {
                rate[i] = (x[i + 1] - x[i - 1]) * sample_rate_hz / 2.0;
                accel[i] = (x[i + 1] - 2.0 * x[i] + x[i - 1]) * sample_rate_hz * sample_rate_hz;
            }
            rate[0] = (x[1] - x[0]) * sample_rate_hz;
            rate[n - 1] = (x[n - 1] - x[n - 2]) * sample_rate_hz;
            accel[0] = accel[1];
            accel[n - 1] = accel[n - 2];
        }
        out.rate[axis] = rate;
        out.accel[axis] = accel;
    }
    out
}
