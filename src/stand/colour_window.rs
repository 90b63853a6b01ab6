//! The smoothing windows of [`super::colour`]: per window, the part of the measured angles `y`
//! that no linear filter of the witness `w` explains, from sums over the window's bins; the
//! windows slide over cells of bins ([`slide`]).
//!
//! Per angle, where the data show it, the witness's transfer is fitted as a **straight line in
//! frequency** across the window, `y ~ (A + (f - f_c) B) w` with `f_c` the window's centre: six
//! complex regressors, `w` and `(f - f_c) w`. A transfer taken as constant over the window (three
//! regressors) leaves unexplained whatever it does inside one: a gyro's own resonance of damping
//! 0.05 at 30 Hz is 3 Hz wide, and across a window 1.7 Hz wide its phase turns by about 50
//! degrees. That turn, some tenths of the angles' power at the mode, was taken for angle noise;
//! the observer shrank the inputs there by as much and the diagnosis read the mode's damping
//! 2-10 % low (3.5-9.5 standard deviations) on clean simulated runs, where a run without the
//! witness read it within 2. A line leaves the transfer's curvature, about a tenth of the
//! constant's misfit there; a parabola (nine regressors) measured no better on those runs.
//!
//! The slope is kept where it explains significantly more than noise would (an F test,
//! [`SLOPE_F`]), else the constant is: a slope fitted everywhere takes `3 / M` more of the noise
//! in every window, and the rules downstream that read the model's level (where the angles are
//! mostly their noise, `diagnose::noisy_angles`; where the inputs stop being the motion,
//! `diagnose::input_limit`) were measured with the constant's. So was the level's correction for
//! the regressors fitted, `M / (M - p)` with `M` the window's bins times the Hann window's
//! `2n/3` equivalent samples over the grid: it falls short, as the bins' correlation (35/18)
//! would count it, by 3-6 % of a noise's level (`a_hann_windowed_white_noise_reads_its_variance`;
//! made right, 29 Nov, the model of a simulated 0.2 mrad noise read within 2.5 %, false findings
//! beside strong coloured angle noise fell, and on a 120 Hz interpolated reference a clean run's
//! accelerometer band was no longer ended and a true lag was set aside: kept as it was until
//! those rules are measured again with it).
//!
//! On top of the constant or the line, each angle may also take its split regressors (the
//! witness's parts each gyro axis makes, [`super::colour_split`]) where they explain
//! significantly more; the sums carry them (`v`).
//!
//! The unexplained part is `N_c = S_yy - S_yz S_zz^-1 S_zy`, with `z = [w; d w]` or `z = w` (and
//! the axis's split regressors `v` where they are kept),
//! `d = (k - k_c) / h` (bins from the centre over the half-width). What is explained does not
//! depend on where `d` is counted from or in what unit (`[w; (d + c) s w]` spans what `[w; d w]`
//! does), so sums are accumulated about any origin and moved ([`Sums::about`]) only to keep `d`
//! of order 1 (within -1..1 but at the spectrum's ends, where a window is cut to one side): the
//! window slides over cells of bins summed once, its sums moved to a new origin whenever its
//! centre has gone a half-width from the last (which also bounds the sliding sums' rounding).
//! The slope's part is fitted by blocks (the Schur complement of `S_zz`: two 3x3 inverses, not
//! one 6x6), the Hermitian blocks inverted by Cholesky with a relative pivot floor; with the split
//! regressors, the whole system (at most 8x8) by Cholesky ([`super::colour_split`]).
//!
//! Units: the sums are of the Hann-windowed spectra as they come; [`unexplained`] scales them to
//! periodogram levels (rad^2 per sample). NaN cannot arise from finite input; a window with too
//! few bins or a singular `S_ww` says nothing (`None`); a slope block that is singular (the slope
//! adds nothing) leaves the constant's fit.

use nalgebra::{Cholesky, Matrix3, Matrix3x4, Matrix4, Vector3, Vector4};
use num_complex::Complex64;

use super::colour_split::{SPLIT_F, SplitSums, split_residual};
use super::observer::daniell_half_width;
use super::witness_floor::WitnessFloor;

/// Regressors per angle with the slope: the witness's three channels and the same times the
/// distance from the window's centre.
pub(super) const REGRESSORS: f64 = 6.0;

/// Sums over bins of `y y^H`, and of `y w^H` and `w w^H` weighted by the powers 0..=1 and 0..=2 of
/// `u`, the bin's distance from the sums' origin (in bins, over a scale fixed by the caller); and
/// with the split regressors `v` ([`super::colour_split`]), `y v^H`, `w v^H` (powers 0..=1) and
/// `v v^H`.
#[derive(Clone, Copy)]
pub(super) struct Sums {
    yy: Matrix3<Complex64>,
    yw: [Matrix3<Complex64>; 2],
    ww: [Matrix3<Complex64>; 3],
    yv: Matrix3x4<Complex64>,
    wv: [Matrix3x4<Complex64>; 2],
    vv: Matrix4<Complex64>,
}

impl Sums {
    pub(super) fn zero() -> Self {
        Self {
            yy: Matrix3::zeros(),
            yw: [Matrix3::zeros(); 2],
            ww: [Matrix3::zeros(); 3],
            yv: Matrix3x4::zeros(),
            wv: [Matrix3x4::zeros(); 2],
            vv: Matrix4::zeros(),
        }
    }

    /// Adds one bin at distance `u` from the origin.
    pub(super) fn add(
        &mut self,
        y: &Vector3<Complex64>,
        w: &Vector3<Complex64>,
        v: &Vector4<Complex64>,
        u: f64,
    ) {
        let yw = y * w.adjoint();
        let ww = w * w.adjoint();
        let wv = w * v.adjoint();
        self.yy += y * y.adjoint();
        self.yw[0] += yw;
        self.yw[1] += yw * Complex64::from(u);
        self.ww[0] += ww;
        self.ww[1] += ww * Complex64::from(u);
        self.ww[2] += ww * Complex64::from(u * u);
        self.yv += y * v.adjoint();
        self.wv[0] += wv;
        self.wv[1] += wv * Complex64::from(u);
        self.vv += v * v.adjoint();
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
            yv: self.yv,
            wv: [self.wv[0], (self.wv[1] + self.wv[0] * d) * s],
            vv: self.vv,
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
        self.yv += other.yv * s;
        for (a, b) in self.wv.iter_mut().zip(&other.wv) {
            *a += b * s;
        }
        self.vv += other.vv * s;
    }
}

/// What a window's sums say, per axis, as periodogram levels: the angles' power `S_yy`, and the
/// part the witness leaves unexplained, corrected for the regressors fitted (`None` where the
/// window says nothing: too few bins, or `S_ww` singular). Per axis the witness's transfer is a
/// straight line across the window where its slope explains significantly more than a constant
/// would ([`SLOPE_F`]), else a constant (module docs); on top of either, the axis's split
/// regressors where they explain significantly more ([`SPLIT_F`], [`super::colour_split`]).
///
/// `sums` with distances of order 1 across the window (any origin and unit: module docs);
/// `count` bins; `dof`: the window's equivalent samples, which the level's correction counts,
/// and its independent bins, which the slope's test counts; `power_norm` the Hann window's
/// `sum w^2`.
pub(super) fn unexplained(
    sums: &Sums,
    count: f64,
    dof: Dof,
    power_norm: f64,
) -> ([f64; 3], Option<[f64; 3]>) {
    let scale = Complex64::from(1.0 / (count.max(1.0) * power_norm));
    let syy = sums.yy * scale;
    let total = [syy[(0, 0)].re, syy[(1, 1)].re, syy[(2, 2)].re];
    let Dof {
        equivalent,
        independent,
    } = dof;
    if equivalent <= REGRESSORS + 1.0 || independent <= REGRESSORS + 1.0 {
        return (total, None);
    }
    let [a0, a1, a2] = sums.ww.map(|m| m * scale);
    let [b0, b1] = sums.yw.map(|m| m * scale);
    let Some(a0_inv) = hermitian_inverse(&a0) else {
        return (total, None);
    };
    let constant = b0 * a0_inv * b0.adjoint();
    let half = REGRESSORS / 2.0;
    // The slope's part by blocks: what it explains beyond the witness (the Schur complement of
    // `S_zz`: two 3x3 inverses, not one 6x6); none where it adds nothing (`S` singular).
    let g = a0_inv * a1;
    let beyond = b1 - b0 * g;
    let slope = hermitian_inverse(&(a2 - a1.adjoint() * g)).map(|s_inv| beyond * s_inv * beyond.adjoint());
    let (yv, vv) = (sums.yv * scale, sums.vv * scale);
    let [wv0, wv1] = sums.wv.map(|m| m * scale);
    let split = SplitSums {
        a: [&a0, &a1, &a2],
        b: [&b0, &b1],
        yv: &yv,
        wv: [&wv0, &wv1],
        vv: &vv,
    };
    let left = [0, 1, 2].map(|a| {
        let after_constant = total[a] - constant[(a, a)].re;
        // Rounding can take a residual the slope explains wholly below 0: it is 0.
        let after_line = slope.map(|sl| (sl[(a, a)].re, (after_constant - sl[(a, a)].re).max(0.0)));
        // The window's own fit. The slope's power against what three regressors of noise would
        // take, `3 / M` of the noise's level, itself `residual M / (M - 6)`: the F ratio above
        // `SLOPE_F`, without a division (a NaN keeps the constant).
        let (residual, fitted) = match after_line {
            Some((sl, r)) if explains_more(sl, r, half, REGRESSORS, SLOPE_F, dof) => (r, REGRESSORS),
            _ => (after_constant, half),
        };
        // The witness split by gyro axis where it explains significantly more (`colour_split`),
        // tested beside the fullest fit (the line, where its block is not singular): a part of
        // the split left in would also hide the line's slope from its own test.
        let (fullest, full_fitted) = after_line.map_or((after_constant, half), |(_, r)| (r, REGRESSORS));
        let split_full =
            split_residual(&split, a, after_line.is_some(), total[a], PIVOT_FLOOR).filter(|&(left, q)| {
                let q = q as f64;
                explains_more(fullest - left, left, q, full_fitted + q, SPLIT_F, dof)
            });
        let Some((left_full, q)) = split_full else {
            return residual * equivalent / (equivalent - fitted);
        };
        let q = q as f64;
        // With the split kept, the line only where its slope explains significantly more beside it.
        if after_line.is_some()
            && let Some((left_constant, _)) = split_residual(&split, a, false, total[a], PIVOT_FLOOR)
            && !explains_more(
                left_constant - left_full,
                left_full,
                half,
                REGRESSORS + q,
                SLOPE_F,
                dof,
            )
        {
            return left_constant * equivalent / (equivalent - half - q);
        }
        left_full * equivalent / (equivalent - full_fitted - q)
    });
    (total, Some(left))
}

/// The F test of two nested fits in one window: whether `more`, the power that `added` complex
/// regressors explain beyond the smaller fit, exceeds `f_ratio` times what noise alone would give
/// them, `added / (M - fitted)` of the residual `left` (`M` the independent bins, `fitted` the
/// regressors of the larger fit). False where the window has no more samples or bins than
/// `fitted + 1`, and where any figure is NaN.
fn explains_more(more: f64, left: f64, added: f64, fitted: f64, f_ratio: f64, dof: Dof) -> bool {
    dof.equivalent > fitted + 1.0
        && dof.independent > fitted + 1.0
        && more * (dof.independent - fitted) > f_ratio * added * left
}

/// A window's degrees of freedom.
#[derive(Clone, Copy, Debug)]
pub(super) struct Dof {
    /// The Hann window's equivalent samples (`2n/3`) spread over the window's bins: what the
    /// level's correction for the regressors counts (module docs).
    pub equivalent: f64,
    /// The window's independent bins by the Hann bins' correlation (35/18): what the slope's
    /// and the split's tests count.
    pub independent: f64,
}

/// The F ratio of the slope's explained power (per axis, three complex regressors) over what
/// noise alone would give it, above which the slope is kept: 4, about the 0.3 % point of
/// `F(6, 2 (M - 6))` for the windows' 18-50 independent bins (false slopes in three windows of a
/// thousand, each taking the noise's level down by about `3 / M`); nearer 5 % in the windows cut
/// to half at the spectrum's ends (DC and Nyquist, 9-10 bins).
pub(super) const SLOPE_F: f64 = 4.0;

/// Pivots (squared) below this fraction of the largest diagonal element make a Hermitian block
/// singular: its inverse would be rounding.
const PIVOT_FLOOR: f64 = 1e-12;

/// The inverse of a Hermitian positive-definite 3x3 block, by Cholesky; `None` where a pivot is
/// not above [`PIVOT_FLOOR`] of the largest diagonal element (or NaN).
fn hermitian_inverse(m: &Matrix3<Complex64>) -> Option<Matrix3<Complex64>> {
    let largest = (0..3).map(|i| m[(i, i)].re).fold(0.0_f64, f64::max);
    let c = Cholesky::new(*m)?;
    let l = c.l_dirty();
    let fine = (0..3).all(|i| l[(i, i)].norm_sqr() > PIVOT_FLOOR * largest);
    fine.then(|| c.inverse())
}

/// How the smoothing windows lie on a grid of bins.
pub(super) struct Windows {
    /// Bins per Hz.
    pub bins_per_hz: f64,
    /// The observer's smoothing, `(smoothing_hz, smoothing_fraction)`: a window at `f` is
    /// `max(smoothing_hz, smoothing_fraction f)` wide.
    pub smoothing: (f64, f64),
    /// Fewest bins either side of a window's centre.
    pub min_half: usize,
    /// Bins per cell: one window per cell, its edges on cells.
    pub cell: usize,
    /// Per bin, the window's equivalent samples and independent bins ([`Dof`]).
    pub per_bin: Dof,
    /// The Hann window's `sum w^2`.
    pub power_norm: f64,
    /// The witness's own white floor, taken out of what it leaves unexplained
    /// ([`super::witness_floor`]; `None`: nothing taken out).
    pub witness_floor: Option<WitnessFloor>,
}

fn bin(spectra: &[Vec<Complex64>; 3], k: usize) -> Vector3<Complex64> {
    Vector3::new(spectra[0][k], spectra[1][k], spectra[2][k])
}

fn split_bin(spectra: &[Vec<Complex64>; 4], k: usize) -> Vector4<Complex64> {
    Vector4::new(spectra[0][k], spectra[1][k], spectra[2][k], spectra[3][k])
}

/// Per cell of `windows.cell` bins of the spectra `y` and `w` (and the split regressors `v`,
/// [`super::colour_split::SPLIT`]), what the window centred on it says ([`unexplained`]). The
/// window covers the cells within its half-width of the cell (widened to `min_half` bins), cut
/// at the spectrum's ends.
pub(super) fn slide(
    y: &[Vec<Complex64>; 3],
    w: &[Vec<Complex64>; 3],
    v: &[Vec<Complex64>; 4],
    windows: &Windows,
) -> Vec<([f64; 3], Option<[f64; 3]>)> {
    let Windows {
        bins_per_hz,
        smoothing,
        min_half,
        cell,
        per_bin,
        power_norm,
        witness_floor,
    } = *windows;
    let bins = y[0].len().min(w[0].len()).min(v[0].len());
    // Distances from the sums' origin in units of `min_half` bins.
    let unit = min_half as f64;
    let cells: Vec<(Sums, usize, f64)> = (0..bins.div_ceil(cell))
        .map(|c| {
            let mut sums = Sums::zero();
            let range = c * cell..((c + 1) * cell).min(bins);
            let centre = (range.start + range.end - 1) as f64 / 2.0;
            for k in range.clone() {
                sums.add(
                    &bin(y, k),
                    &bin(w, k),
                    &split_bin(v, k),
                    (k as f64 - centre) / unit,
                );
            }
            (sums, range.len(), centre)
        })
        .collect();
    let mut sums = Sums::zero();
    let mut count = 0_usize;
    let (mut lo, mut hi) = (0, 0);
    let mut origin = 0.0;
    let mut out = Vec::with_capacity(cells.len());
    for c in 0..cells.len() {
        let centre = (c * cell + cell / 2) as f64;
        let half_bins = daniell_half_width(smoothing, centre / bins_per_hz, bins_per_hz).max(min_half);
        let half = half_bins.div_ceil(cell);
        let (new_lo, new_hi) = (c.saturating_sub(half), (c + half + 1).min(cells.len()));
        if (centre - origin).abs() > half_bins as f64 {
            origin = centre;
            (sums, count) = cells_about(&cells[new_lo..new_hi], origin, unit);
        } else {
            let (added, more) = cells_about(&cells[hi..new_hi], origin, unit);
            let (removed, fewer) = cells_about(&cells[lo..new_lo], origin, unit);
            sums.merge(&added, 1.0);
            sums.merge(&removed, -1.0);
            count = count + more - fewer;
        }
        (lo, hi) = (new_lo, new_hi);
        let about_centre = sums.about((origin - centre) / unit, unit / half_bins as f64);
        let dof = Dof {
            equivalent: count as f64 * per_bin.equivalent,
            independent: count as f64 * per_bin.independent,
        };
        let (total, left) = unexplained(&about_centre, count as f64, dof, power_norm);
        let centre_hz = centre / bins_per_hz;
        let left = match (left, witness_floor) {
            (Some(left), Some(floor)) if centre_hz <= floor.top_hz => Some(beyond_witness_noise(
                &about_centre,
                (count as f64, power_norm),
                left,
                floor.in_angle_units(centre_hz),
            )),
            (left, _) => left,
        };
        out.push((total, left));
    }
    out
}

/// `left` with the witness's own noise `floor` (angle units) taken out, as the witness's fit sees
/// it: `S_yw ((S_ww - S_e)^-1 - S_ww^-1) S_wy`, the unexplained part's excess over what a
/// noiseless witness would leave ([`super::witness_floor`]), with each axis's `S_e` at most half
/// its `S_ww` (where the witness is mostly its own noise it says little, and the correction's
/// factor `S_ww / (S_ww - S_e)` would grow without bound). Not below 0; unchanged where `S_ww`, or
/// `S_ww - S_e`, is singular. `sums` over `count` bins, `power_norm` as [`unexplained`]'s.
fn beyond_witness_noise(
    sums: &Sums,
    (count, power_norm): (f64, f64),
    left: [f64; 3],
    floor: [f64; 3],
) -> [f64; 3] {
    let scale = Complex64::from(1.0 / (count.max(1.0) * power_norm));
    let (a0, b0) = (sums.ww[0] * scale, sums.yw[0] * scale);
    let Some(a0_inv) = hermitian_inverse(&a0) else {
        return left;
    };
    let mut less = a0;
    for (j, f) in floor.iter().enumerate() {
        less[(j, j)] -= Complex64::from(f.min(0.5 * a0[(j, j)].re).max(0.0));
    }
    let Some(less_inv) = hermitian_inverse(&less) else {
        return left;
    };
    let seen = b0 * (less_inv - a0_inv) * b0.adjoint();
    [0, 1, 2].map(|a| {
        let v = left[a] - seen[(a, a)].re;
        if v.is_finite() { v.max(0.0) } else { left[a] }
    })
}

/// The sums of `cells` (each about its centre bin) about the bin `origin`, and their bins.
fn cells_about(cells: &[(Sums, usize, f64)], origin: f64, unit: f64) -> (Sums, usize) {
    let mut sums = Sums::zero();
    for (s, _, at) in cells {
        sums.merge(&s.about((at - origin) / unit, 1.0), 1.0);
    }
    (sums, cells.iter().map(|c| c.1).sum())
}

#[cfg(test)]
#[path = "colour_window_tests.rs"]
mod tests;
