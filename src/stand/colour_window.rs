//! One smoothing window of [`super::colour`]: the part of the measured angles `y` that no linear
//! filter of the witness `w` explains, from sums over the window's bins.
//!
//! The witness's transfer to the angles is fitted as a **straight line in frequency** across the
//! window, `y ~ (A + (f - f_c) B) w` with `f_c` the window's centre: six complex regressors per
//! angle, `w` and `(f - f_c) w`. A transfer taken as constant over the window (three regressors)
//! leaves unexplained whatever it does inside one: a gyro's own resonance of damping 0.05 at
//! 30 Hz is 3 Hz wide, and across a window 1.7 Hz wide its phase turns by about 50 degrees. That
//! turn, some tenths of the angles' power at the mode, was taken for angle noise; the observer
//! shrank the inputs there by as much and the diagnosis read the mode's damping 2-10 % low (4-9
//! standard deviations) on clean simulated runs, where a run without the witness read it within
//! 2. A line leaves the transfer's curvature, about a tenth of the constant's misfit there; a
//! parabola (nine regressors) measured no better on those runs and costs three more degrees of
//! freedom per window.
//!
//! The unexplained part is `N_c = S_yy - S_yz S_zz^-1 S_zy` with `z = [w; d w]`,
//! `d = (k - k_c) / h` (bins from the centre over the half-width), corrected by `M / (M - 6)` for
//! the six regressors fitted in a window of `M` independent bins. What is explained does not
//! depend on where `d` is counted from or in what unit (`[w; (d + c) s w]` spans what `[w; d w]`
//! does), so sums are accumulated about any origin and moved ([`Sums::about`]) only to keep
//! `|d|` near 1: the window slides over cells of bins summed once.
//!
//! Units: the sums are of the Hann-windowed spectra as they come; [`unexplained`] scales them to
//! periodogram levels (rad^2 per sample). NaN cannot arise from finite input; a window with too
//! few bins or a singular `S_zz` says nothing (`None`).

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

/// Regressors per angle: the witness's three channels and the same times the distance from the
/// window's centre.
pub(super) const REGRESSORS: f64 = 6.0;

/// Sums over bins of `y y^H`, and of `y w^H` and `w w^H` weighted by the powers 0..=1 and 0..=2 of
/// `u`, the bin's distance from the sums' origin (in bins, over a scale fixed by the caller).
#[derive(Clone, Copy)]
pub(super) struct Sums {
    yy: Matrix3<Complex64>,
    yw: [Matrix3<Complex64>; 2],
    ww: [Matrix3<Complex64>; 3],
}

impl Sums {
    pub(super) fn zero() -> Self {
        Self {
            yy: Matrix3::zeros(),
            yw: [Matrix3::zeros(); 2],
            ww: [Matrix3::zeros(); 3],
        }
    }

    /// Adds one bin at distance `u` from the origin.
    pub(super) fn add(&mut self, y: &Vector3<Complex64>, w: &Vector3<Complex64>, u: f64) {
        let yw = y * w.adjoint();
        let ww = w * w.adjoint();
        self.yy += y * y.adjoint();
        self.yw[0] += yw;
        self.yw[1] += yw * Complex64::from(u);
        self.ww[0] += ww;
        self.ww[1] += ww * Complex64::from(u);
        self.ww[2] += ww * Complex64::from(u * u);
    }

    /// The same sums with distances counted from an origin `shift` before this one and in units
    /// `stretch` times smaller (`u' = (u + shift) stretch`): exact, by the binomial expansion of
    /// `(u + shift)^j`.
    pub(super) fn about(&self, shift: f64, stretch: f64) -> Self {
        let (d, s) = (Complex64::from(shift), Complex64::from(stretch));
        Self {
            yy: self.yy,
            yw: [self.yw[0], (self.yw[1] + self.yw[0] * d) * s],
            ww: [
                self.ww[0],
                (self.ww[1] + self.ww[0] * d) * s,
                (self.ww[2] + self.ww[1] * (d * 2.0) + self.ww[0] * (d * d)) * (s * s),
            ],
        }
    }

    /// Adds (`sign` 1) or removes (`sign` -1) sums about the same origin.
    pub(super) fn merge(&mut self, other: &Self, sign: f64) {
        let s = Complex64::from(sign);
        self.yy += other.yy * s;
        for (a, b) in self.yw.iter_mut().zip(&other.yw) {
            *a += b * s;
        }
        for (a, b) in self.ww.iter_mut().zip(&other.ww) {
            *a += b * s;
        }
    }
}

/// What a window's sums say, per axis, as periodogram levels: the angles' power `S_yy`, and the
/// part no straight-line transfer of the witness explains, corrected for the regressors fitted
/// (`None` where the window says nothing: `independent` bins too few, or `S_zz` singular).
///
/// `sums` with distances near 1 across the window (any origin and unit: module docs); `count`
/// bins, `independent` equivalent independent bins among them; `power_norm` the Hann window's
/// `sum w^2`.
pub(super) fn unexplained(
    sums: &Sums,
    count: f64,
    independent: f64,
    power_norm: f64,
) -> ([f64; 3], Option<[f64; 3]>) {
    let scale = Complex64::from(1.0 / (count.max(1.0) * power_norm));
    let syy = sums.yy * scale;
    let total = [syy[(0, 0)].re, syy[(1, 1)].re, syy[(2, 2)].re];
    if independent <= REGRESSORS + 1.0 {
        return (total, None);
    }
    let [a0, a1, a2] = sums.ww.map(|m| m * scale);
    let [b0, b1] = sums.yw.map(|m| m * scale);
    let Some(a0_inv) = a0.try_inverse() else {
        return (total, None);
    };
    // The six-regressor fit by blocks: what the witness explains, then what its slope explains
    // beyond that (the Schur complement of `S_zz`: two 3x3 inverses, not one 6x6). A slope that
    // adds nothing (`S` singular) leaves the witness's part.
    let g = a0_inv * a1;
    let beyond = b1 - b0 * g;
    let mut explained = b0 * a0_inv * b0.adjoint();
    if let Some(s_inv) = (a2 - a1.adjoint() * g).try_inverse() {
        explained += beyond * s_inv * beyond.adjoint();
    }
    let correction = independent / (independent - REGRESSORS);
    let left = [0, 1, 2].map(|a| (total[a] - explained[(a, a)].re) * correction);
    (total, Some(left))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_bins(rng: &mut Rng, n: usize) -> Vec<(Vector3<Complex64>, Vector3<Complex64>)> {
        let mut c = || Complex64::new(rng.normal(), rng.normal());
        (0..n)
            .map(|_| (Vector3::new(c(), c(), c()), Vector3::new(c(), c(), c())))
            .collect()
    }

    /// Moving the origin after summing equals summing about the new origin (brute force).
    #[test]
    fn moving_the_origin_is_exact() {
        let mut rng = Rng::new(7);
        let bins = random_bins(&mut rng, 40);
        let (mut far, mut near) = (Sums::zero(), Sums::zero());
        for (k, (y, w)) in bins.iter().enumerate() {
            far.add(y, w, k as f64 - 3.0);
            near.add(y, w, (k as f64 - 25.0) / 8.0);
        }
        let moved = far.about(3.0 - 25.0, 1.0 / 8.0);
        let pairs = moved.yw.iter().zip(&near.yw).chain(moved.ww.iter().zip(&near.ww));
        for (a, b) in pairs {
            assert!((a - b).norm() <= 1e-12 * b.norm().max(1.0), "{a} vs {b}");
        }
    }

    /// A witness whose transfer turns across the window is explained but for the turn's
    /// curvature (a constant transfer would leave much more); with a transfer exactly a line and
    /// independent noise added to the angles, what is left is that noise's power (the
    /// `M / (M - 6)` correction makes it unbiased: the mean over many windows within 3 %, where the three regressors' `M / (M - 3)` would be 7 % low).
    #[test]
    fn a_transfer_turning_across_the_window_is_explained_and_the_noise_is_measured() {
        let mut rng = Rng::new(11);
        let n = 48;
        let half = 24.0;
        let mut exact_left = Vec::new();
        let mut noisy_left = Vec::new();
        for _ in 0..200 {
            let bins = random_bins(&mut rng, n);
            let (mut exact, mut noisy) = (Sums::zero(), Sums::zero());
            for (k, (noise, w)) in bins.iter().enumerate() {
                let u = (k as f64 - 23.5) / half;
                // Phase turning by 1 rad across the window, gain 2, cross-coupled.
                let turn = Complex64::from_polar(2.0, 0.5 * u);
                let y = Vector3::new(turn * w[0], turn * w[1] + w[0] * 0.3, turn * w[2]);
                exact.add(&y, w, u);
                // A transfer exactly a line in frequency, and noise of known power.
                let line = Complex64::new(1.5, 0.4 * u);
                noisy.add(&(w * line + noise * Complex64::from(0.1)), w, u);
            }
            let (total, left) = unexplained(&exact, n as f64, n as f64, 1.0);
            let left = left.expect("the window says something");
            exact_left.push(left[0].max(left[1]).max(left[2]) / total[0]);
            noisy_left.push(unexplained(&noisy, n as f64, n as f64, 1.0).1.expect("says")[1]);
        }
        let worst = exact_left.iter().copied().fold(0.0_f64, f64::max);
        // A line leaves the turn's curvature, the variance of (0.5 u)^2 / 2 over the window,
        // 1.4e-3 of the power on average; a constant would leave the variance of 0.5 u, 8e-2.
        assert!(worst < 5e-3, "a line leaves {worst} of the power unexplained");
        let mean = noisy_left.iter().sum::<f64>() / noisy_left.len() as f64;
        // Each complex noise component has variance 2 x 0.01.
        assert!(
            (mean / 0.02 - 1.0).abs() < 0.03,
            "mean unexplained {mean}, noise 0.02"
        );
    }

    /// Too few bins for six regressors: nothing is said.
    #[test]
    fn too_few_bins_say_nothing() {
        let mut rng = Rng::new(3);
        let mut sums = Sums::zero();
        for (k, (y, w)) in random_bins(&mut rng, 7).iter().enumerate() {
            sums.add(y, w, k as f64 / 7.0);
        }
        assert!(unexplained(&sums, 7.0, 7.0, 1.0).1.is_none());
    }
}
