//! The angle noise the observer's model left out: the gain bias it may leave, put into the
//! `K` standard deviations of the blocks whose inputs come from the angles.
//!
//! With a gyro block the observer colours its angle-noise model by what the gyro's outputs leave
//! unexplained in the measured angles (`stand::colour`), except where that part is below a
//! thousandth of the angles' power: there the model keeps the white floor, because the part is
//! as likely the gyro's own low-frequency noise (the simulator's gyro: a coloured noise of
//! 1.5e-4 rad/s/sqrt(Hz) below 0.5 Hz, which on a 300 s cruise run leaves 4e4-1.5e5 times the
//! white floor unexplained at 0.13-0.4 Hz, a hundred to five hundred times a real stand's
//! coloured angle noise there) and the two cannot be told apart in one run. Taking it all as
//! angle noise was tried (2 Dec): it mended long real-stand runs and biased perfect ones the
//! other way. Keeping the floor leaves, if the part is the angles' noise, that noise in the
//! inputs as motion, and on long records under a real stand's coloured noise the gyro's `K`
//! read 4e-4 to 8e-4 off in a fixed pattern, up to 4.3 of its deviations (README, *Long runs*).
//!
//! So the ambiguity is put into the deviations. With the observer's matrix Wiener gain
//! `I - N S_yy^-1` per bin, a model short of the noise by `dN` gives `H1 = K S_uu (S_uu + dN)^-1`,
//! to first order `K (I - dN S_uu^-1)` (in the inputs' units: `dN_u = T dN T^H` with `T` the
//! inputs' linearised response to the angles at the record's mean attitude: for a gyro's body
//! rates `T = j w E`, `E` the Euler-rate-to-body-rate matrix; for an accelerometer's specific
//! force `T = A - w^2 B`, `A` its tilt of gravity and `B` its lever arm's `w' x r`; the inputs'
//! spectra stand in for the motion's). The static gain is fitted over the band, each bin of
//! output `i` weighted by the inverse of its residual density `S_psi,ik = (1 - gamma2_ik)
//! S_xx,ik`, so the row's estimate is `K (sum_k S_uu,k / S_psi,ik) (sum_k (S_uu,k + dN_u,k) /
//! S_psi,ik)^-1`, and its row of `K` shifts by about
//!
//! `dK_i = -(K (sum_k dN_u,k / S_psi,ik) (sum_k Re S_uu,k / S_psi,ik)^-1)_i`,
//!
//! the whole shift if the part left out is all angle noise, none if it is all the gyro's (the
//! sums come before the inverse: a bin whose inputs are nearly collinear is not inverted on its
//! own; averaged per bin, the shifts read ten times the measured on turbulent cruises). Taken
//! as uniform between, the error's rms about the reported gain is `|dK_ij| / sqrt(3)`, added in
//! quadrature to each element's deviation ([`widen_for_left_out_noise`]), of the gyro and of an
//! accelerometer beside it alike (the model is the gyro's, the inputs both blocks'). The off-diagonal
//! elements move too: `S_uu^-1` couples the axes where the motion does (a turbulent cruise's
//! roll and yaw). The delay is untouched (the observer's gain is zero-phase).
//!
//! Approximations, beside first order: `T` at rest at the mean attitude (the terms of the
//! current rates, centripetal and Euler-rate products, left out; a plain mean of each angle);
//! the weights rebuilt from the coherence rather than the fit's own clamped residual model, and
//! without the even gain's or the scatter's reweighting; the whole record's model, whatever the
//! span analysed.
//!
//! Contracts: bins with a NaN coherence or level, a coherence of 1 (no residual to weigh by) or
//! no band of the left-out model are skipped; a row whose summed `S_uu` is singular, or without
//! bins, does not shift (nothing widened). Units: the model's densities are
//! one-sided, rad^2/Hz, as the spectra's (`crate::spectral`).

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

use super::spectra::BlockSpectra;
use super::structural::StructuralFit;
use crate::stand::kinematics::{EulerState, body_rate, specific_force};
use crate::stand::observer::ErrorPsd;

/// What the observer's angle-noise model left out, and how it reaches a block's inputs.
#[derive(Clone, Debug)]
pub struct LeftOutNoise {
    /// The part left out per band, angle axes `[roll, yaw, pitch]`, rad^2/Hz
    /// (`stand::observer::ObserverEstimate::angle_noise_left_out_psd`).
    pub psd: ErrorPsd,
    /// The inputs' linearised response to the Euler angles at the record's mean attitude, at
    /// rest: `du = A dtheta + C dtheta' + B dtheta''` as `[A, C, B]` (module docs).
    pub to_inputs: [Matrix3<f64>; 3],
}

impl LeftOutNoise {
    /// For a gyro: body rates `C = E`, the Euler-rate-to-body-rate matrix at the mean of the Euler
    /// `angles` (`[roll, yaw, pitch]`, rad).
    #[must_use]
    pub fn for_gyro(psd: ErrorPsd, angles: [&[f64]; 3]) -> Self {
        let mean = mean_attitude(angles);
        let c = Matrix3::from_fn(|r, col| {
            let mut rate = [0.0; 3];
            rate[col] = 1.0;
            body_rate(&EulerState {
                angle: mean,
                rate,
                accel: [0.0; 3],
            })[r]
        });
        Self {
            psd,
            to_inputs: [Matrix3::zeros(), c, Matrix3::zeros()],
        }
    }

    /// For an accelerometer at `lever_arm_m` under gravity `g_mps2`: its specific force's tilt of
    /// gravity `A` (central differences of 1e-6 rad) and the lever arm's `w' x r`, `B` (exact:
    /// linear in the Euler accelerations at rest), at the mean attitude.
    #[must_use]
    pub fn for_accel(psd: ErrorPsd, angles: [&[f64]; 3], lever_arm_m: [f64; 3], g_mps2: f64) -> Self {
        let mean = mean_attitude(angles);
        let r = Vector3::from(lever_arm_m);
        let force = |angle: [f64; 3], accel: [f64; 3]| {
            specific_force(
                &EulerState {
                    angle,
                    rate: [0.0; 3],
                    accel,
                },
                &r,
                g_mps2,
            )
        };
        let h = 1e-6;
        let a = Matrix3::from_fn(|row, col| {
            let (mut up, mut down) = (mean, mean);
            up[col] += h;
            down[col] -= h;
            (force(up, [0.0; 3])[row] - force(down, [0.0; 3])[row]) / (2.0 * h)
        });
        let b = Matrix3::from_fn(|row, col| {
            let mut accel = [0.0; 3];
            accel[col] = 1.0;
            force(mean, accel)[row] - force(mean, [0.0; 3])[row]
        });
        Self {
            psd,
            to_inputs: [a, Matrix3::zeros(), b],
        }
    }

    /// `dN_u = Re(T dN T^H)` at `f_hz`, `T = A + j w C - w^2 B`, in the inputs' units squared per
    /// Hz; `None` outside the model's bands.
    fn in_inputs(&self, f_hz: f64) -> Option<Matrix3<f64>> {
        let b = crate::spectral::bands::band_holding(&self.psd.edges_hz, f_hz)?;
        let left = self.psd.psd.get(b)?;
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let [a, c, bb] = self.to_inputs;
        let t = (a - bb * (w * w)).map(Complex64::from) + c.map(|v| Complex64::new(0.0, w * v));
        let dn = Matrix3::from_diagonal(&Vector3::from(*left).map(Complex64::from));
        Some((t * dn * t.adjoint()).map(|v| v.re))
    }
}

/// The mean of each Euler angle over the record, rad.
fn mean_attitude(angles: [&[f64]; 3]) -> [f64; 3] {
    angles.map(|a| a.iter().sum::<f64>() / a.len().max(1) as f64)
}

/// `dK` (module docs) for the gains `k` over the `band` bins of `spectra`, with the multiple
/// `coherence` per bin: what `K` would read more if the part left out were all angle noise
/// (negated: the gains read low).
#[must_use]
pub fn gain_shift(
    spectra: &BlockSpectra,
    coherence: &[[f64; 3]],
    band: &[usize],
    k: &[[f64; 3]; 3],
    left_out: &LeftOutNoise,
) -> [[f64; 3]; 3] {
    let k = Matrix3::from_fn(|i, j| k[i][j]);
    // Per output row, the weighted sums of the inputs' (real) spectra and of the part left out.
    let mut inputs = [Matrix3::<f64>::zeros(); 3];
    let mut left = [Matrix3::<f64>::zeros(); 3];
    for &b in band {
        let (Some(c), Some(s_uu), Some(s_xx), Some(&f)) = (
            coherence.get(b),
            spectra.s_uu.get(b),
            spectra.s_xx.get(b),
            spectra.frequency_hz.get(b),
        ) else {
            continue;
        };
        let Some(dn) = left_out.in_inputs(f) else { continue };
        let s_uu = s_uu.map(|v| v.re);
        if !(s_uu.iter().all(|v| v.is_finite()) && dn.iter().all(|v| v.is_finite())) {
            continue;
        }
        for i in 0..3 {
            // The output's residual density: the fit weighs the bin by its inverse.
            let residual = (1.0 - c[i]) * s_xx[(i, i)].re;
            let w = residual.recip();
            if !(w.is_finite() && w > 0.0) {
                continue;
            }
            inputs[i] += s_uu * w;
            left[i] += dn * w;
        }
    }
    std::array::from_fn(|i| {
        let row = inputs[i]
            .try_inverse()
            .map(|inv| (k * left[i] * inv).row(i).transpose());
        std::array::from_fn(|j| row.map_or(0.0, |r| if r[j].is_finite() { -r[j] } else { 0.0 }))
    })
}

/// Widens the fit's `K` deviations by the `shift` taken as uniform between none and all of it:
/// `|dK_ij| / sqrt(3)` in quadrature (module docs).
pub fn widen_for_left_out_noise(fit: &mut StructuralFit, shift: &[[f64; 3]; 3]) {
    for (i, row) in shift.iter().enumerate() {
        for (j, &d) in row.iter().enumerate() {
            fit.set_k_std(i, j, widened_by_shift(fit.k_std[i][j], d));
        }
    }
}

/// A deviation `std` with a `shift` taken as uniform between none and all of it in quadrature:
/// also what an extended model's deviations get (`model::BlockModel::set_effects`).
#[must_use]
pub fn widened_by_shift(std: f64, shift: f64) -> f64 {
    std.hypot(shift.abs() / 3.0_f64.sqrt())
}

#[cfg(test)]
#[path = "left_out_noise_tests.rs"]
mod tests;
