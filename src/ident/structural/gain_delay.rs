//! Order 0, `W(s) = K e^(-tau s)`, by generalised least squares.
//!
//! For a fixed delay each row of the gain is closed form: with `W~ = W e^(j w tau)` and the row
//! weight `Omega_i`, `K_i(tau) = b_i(tau) P_i`, `b_i = sum_k Re(W~_ki Omega_ki)` (a real 1x3 row),
//! `P_i` the pseudo-inverse of `A_i = sum_k Re(Omega_ki)` (eigenvalues below `1e-12` of the
//! largest are dropped: a gain direction no bin weighs is set to zero, and its standard deviation
//! is infinite). The residual is `J(tau) = const - F(tau)`, `F = sum_i b_i P_i b_i^T`, and
//! `b_i' = -sum_k w_k Im(v_ki e^(j w_k tau))`, `b_i'' = -sum_k w_k^2 Re(v_ki e^(j w_k tau))` with
//! `v_ki = W_ki Omega_ki` fixed, so `F' = 2 b' P b^T` and `F'' = 2 (b' P b'^T + b'' P b^T)` are
//! exact. The delay maximises `F`: a scan over the settings' range with a step of `1 / (16 f_max)`
//! (the phase of the top bin wraps every `1 / f_max`, so no basin is missed; the step grows only if
//! the range would need more than `MAX_SCAN` points), then a safeguarded Newton iteration on `F'`
//! inside the best grid cell to a step below `1e-15` s. Beyond the range, `[-DELAY_REACH_S,
//! DELAY_REACH_S]` is scanned too, at the same step, and its best is taken when the range's best
//! is the range's end and the two lie in one lobe (the range cut the maximum off), or when it
//! beats the range's by more than [`WIDER_EVIDENCE`] in chi2 (scaled by the misfit and the bins'
//! correlation): the self-check then says so
//! (`delay_outside_usual_range`). Without it a range's end passed for a maximum: a gyro 50.17 ms
//! behind the angles (a real recording, its outputs delayed) came out at 50.0000 ms, six of its
//! deviations off, said by nothing; at 100 ms an interior local maximum at 1 ms was taken. The
//! evidence bar keeps the range's best where a periodic motion (one sine) gives lobes of equal
//! height beyond it. Each scan point costs one complex product per bin for its phase factor (a
//! recurrence in the delay, exact every `phasor::RESYNC` points, as over bins) and nine pairs of real
//! multiply-adds per bin; the scan allocates two vectors of phase factors.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::model::{ELEMENTS, Model, Prepared};

/// The most points of the delay scan.
const MAX_SCAN: usize = 20_000;

/// How far from zero the delay is also searched, s, beyond the settings' range ([`scan`]): the
/// reach of the stationarity stretches' own scan, wide enough for a logging or transport latency
/// between the angles' and the outputs' clocks, and short beside the segments the program picks
/// (which the delay's overlap loss of the Welch windows is measured against, in the self-check).
pub const DELAY_REACH_S: f64 = crate::ident::stretches::STRETCH_DELAY_REACH_S;

/// How much smaller (in chi2, times `max(1, chi2/dof)` and the bins' correlation, which the
/// weights here do not include) a delay in another lobe beyond the settings' range must make the
/// residual to be taken instead of the range's best: 25, five deviations of a one-parameter
/// difference.
const WIDER_EVIDENCE: f64 = 25.0;

/// Sums independent of the delay.
struct Sums<'a> {
    data: &'a Prepared,
    /// `v_k = W_ki Omega_ki`, row `i` in elements `3 i..3 i + 3`.
    v: Vec<[Complex64; ELEMENTS]>,
    /// `P_i`, the pseudo-inverse of `sum_k Re(Omega_ki)`.
    p: [Matrix3<f64>; 3],
}

/// `a P b^T` for rows `a`, `b`.
fn form(a: &[f64], p: &Matrix3<f64>, b: &[f64]) -> f64 {
    let mut s = 0.0;
    for j in 0..3 {
        for l in 0..3 {
            s += a[j] * p[(j, l)] * b[l];
        }
    }
    s
}

impl Sums<'_> {
    /// `(F, F', F'')` at `tau`; the derivatives only when `derivatives`.
    fn objective(&self, tau: f64, derivatives: bool) -> (f64, f64, f64) {
        let mut c0 = [Complex64::new(0.0, 0.0); ELEMENTS];
        let mut c1 = c0;
        let mut c2 = c0;
        for ((v, &omega), phase) in self.v.iter().zip(&self.data.omega).zip(self.data.phasors(tau)) {
            let z = phase.conj();
            for e in 0..ELEMENTS {
                let t = v[e] * z;
                c0[e] += t;
                if derivatives {
                    c1[e] += t * omega;
                    c2[e] += t * (omega * omega);
                }
            }
        }
        let a: [f64; ELEMENTS] = std::array::from_fn(|e| c0[e].re);
        let a1: [f64; ELEMENTS] = std::array::from_fn(|e| -c1[e].im);
        let a2: [f64; ELEMENTS] = std::array::from_fn(|e| -c2[e].re);
        let (mut f, mut f1, mut f2) = (0.0, 0.0, 0.0);
        for (i, p) in self.p.iter().enumerate() {
            let r = 3 * i..3 * i + 3;
            let (a, a1, a2) = (&a[r.clone()], &a1[r.clone()], &a2[r]);
            f += form(a, p, a);
            f1 += 2.0 * form(a1, p, a);
            f2 += 2.0 * (form(a1, p, a1) + form(a2, p, a));
        }
        (f, f1, f2)
    }

    /// `F` alone, with the phase factors `e^(-j w_k tau)` of each bin given.
    fn value(&self, phases: &[Complex64]) -> f64 {
        let mut a = [0.0; ELEMENTS];
        for (v, z) in self.v.iter().zip(phases) {
            for e in 0..ELEMENTS {
                // Re(v conj(z)).
                a[e] += v[e].re * z.re + v[e].im * z.im;
            }
        }
        self.p
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let r = &a[3 * i..3 * i + 3];
                form(r, p, r)
            })
            .sum()
    }

    /// The gain for a given delay.
    fn gain(&self, tau: f64) -> [f64; ELEMENTS] {
        let mut a = [0.0; ELEMENTS];
        for (v, phase) in self.v.iter().zip(self.data.phasors(tau)) {
            let z = phase.conj();
            for e in 0..ELEMENTS {
                a[e] += (v[e] * z).re;
            }
        }
        std::array::from_fn(|e| {
            let (i, j) = (e / 3, e % 3);
            (0..3).map(|l| a[3 * i + l] * self.p[i][(l, j)]).sum()
        })
    }
}

/// The pseudo-inverse of a real symmetric positive semi-definite matrix: eigenvalues below
/// `1e-12` of the largest count as zero.
fn pseudo_inverse(a: Matrix3<f64>) -> Matrix3<f64> {
    let eigen = a.symmetric_eigen();
    let top = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
    let inv = eigen
        .eigenvalues
        .map(|l| if l > 1e-12 * top { 1.0 / l } else { 0.0 });
    let v = eigen.eigenvectors;
    v * Matrix3::from_diagonal(&inv) * v.transpose()
}

/// The order-0 fit on the delay range `[tau_min, tau_max]` (finite, non-empty), or beyond it
/// ([`scan`]); `correlation` is the bins' (`bin_correlation`, at least 1).
pub(super) fn fit(data: &Prepared, tau_min: f64, tau_max: f64, correlation: f64) -> Model {
    let sums = sums(data);
    let tau = scan(&sums, tau_min, tau_max, correlation);
    Model {
        num: vec![sums.gain(tau)],
        den: Vec::new(),
        tau,
    }
}

/// The order-0 fit whose delay is known to lie within a scan step (`1 / (16 f_max)`) of `near`
/// (data changed a little since a fit gave `near`): refined inside that cell alone, or by the
/// whole scan over `[tau_min, tau_max]` (widened as [`fit`] widens it) when the cell does not
/// hold a maximum. The cell stays inside the range when `near` is (a maximum beyond it is only
/// taken on the scan's evidence), inside the wider reach when `near` is already beyond it.
pub(super) fn fit_near(data: &Prepared, near: f64, tau_min: f64, tau_max: f64, correlation: f64) -> Model {
    let sums = sums(data);
    let step = scan_step(data);
    let (bound_min, bound_max) = if (tau_min..=tau_max).contains(&near) {
        (tau_min, tau_max)
    } else {
        reach(tau_min, tau_max)
    };
    let (lo, hi) = ((near - step).max(bound_min), (near + step).min(bound_max));
    let (_, g_lo, _) = sums.objective(lo, true);
    let (_, g_hi, _) = sums.objective(hi, true);
    let tau = if lo < hi && g_lo > 0.0 && g_hi < 0.0 {
        refine(&sums, lo, hi, near.clamp(lo, hi))
    } else {
        scan(&sums, tau_min, tau_max, correlation)
    };
    Model {
        num: vec![sums.gain(tau)],
        den: Vec::new(),
        tau,
    }
}

/// The sums of the order-0 objective for `data`.
fn sums(data: &Prepared) -> Sums<'_> {
    let v = data
        .h
        .iter()
        .zip(data.rows.iter())
        .map(|(h, rows)| {
            std::array::from_fn(|e| {
                let (i, j) = (e / 3, e % 3);
                (0..3).map(|l| h[3 * i + l] * rows[i].omega[(l, j)]).sum()
            })
        })
        .collect();
    let mut a = [Matrix3::<f64>::zeros(); 3];
    for rows in data.rows.iter() {
        for i in 0..3 {
            a[i] += rows[i].omega.map(|z| z.re);
        }
    }
    Sums {
        data,
        v,
        p: a.map(pseudo_inverse),
    }
}

/// The scan's step, s: `1 / (16 f_max)`, a sixteenth of the top bin's phase period.
fn scan_step(data: &Prepared) -> f64 {
    2.0 * std::f64::consts::PI / data.omega_ref / 16.0
}

/// The widest range searched: `[tau_min, tau_max]` widened to `+-DELAY_REACH_S`.
fn reach(tau_min: f64, tau_max: f64) -> (f64, f64) {
    (tau_min.min(-DELAY_REACH_S), tau_max.max(DELAY_REACH_S))
}

/// The best delay over `[tau_min, tau_max]`, or over the wider [`reach`]: when the range's best
/// is its end (within a step) and the wider best lies in the same lobe (within half a top-bin
/// period: the same maximum, which the range cut off), or when the data prefer the wider best by
/// [`WIDER_EVIDENCE`] (module docs).
fn scan(sums: &Sums, tau_min: f64, tau_max: f64, correlation: f64) -> f64 {
    let step = scan_step(sums.data);
    let near = best_delay(sums, tau_min, tau_max, step);
    let (lo, hi) = reach(tau_min, tau_max);
    if lo >= tau_min && hi <= tau_max {
        return near;
    }
    let far = best_delay(sums, lo, hi, step);
    let at_end = near <= tau_min + step || near >= tau_max - step;
    if at_end && (far - near).abs() < 8.0 * step {
        return far;
    }
    let chi2 = |tau: f64| {
        Model {
            num: vec![sums.gain(tau)],
            den: Vec::new(),
            tau,
        }
        .chi2(sums.data)
    };
    let (chi2_near, chi2_far) = (chi2(near), chi2(far));
    let dof = sums.data.real_data().saturating_sub(ELEMENTS + 1).max(1) as f64;
    let bar = WIDER_EVIDENCE * correlation.max(1.0) * (chi2_far / dof).max(1.0);
    if chi2_near - chi2_far > bar { far } else { near }
}

/// Scan every `step` (fewer points if that needs more than [`MAX_SCAN`]), then refine inside
/// the best cell.
fn best_delay(sums: &Sums, tau_min: f64, tau_max: f64, step: f64) -> f64 {
    let span = tau_max - tau_min;
    let points = ((span / step).ceil() as usize).clamp(2, MAX_SCAN);
    let step = span / (points - 1) as f64;
    let at = |i: usize| {
        if i + 1 == points {
            tau_max
        } else {
            tau_min + step * i as f64
        }
    };
    // The points' phase factors by a recurrence in the delay, `e^(-j w (tau + step)) = e^(-j w
    // tau) e^(-j w step)`, exact again every `super::phasor::RESYNC` points: the fit's frequencies are
    // the bins' input power centroids, not equally spaced, so the recurrence over bins
    // (`super::phasor`) does not apply, and a `sin_cos` per bin and point was most of a retune.
    let omega = &sums.data.omega;
    let exact = |tau: f64, phases: &mut Vec<Complex64>| {
        phases.clear();
        phases.extend(omega.iter().map(|&w| Complex64::from_polar(1.0, -w * tau)));
    };
    let turn: Vec<Complex64> = omega
        .iter()
        .map(|&w| Complex64::from_polar(1.0, -w * step))
        .collect();
    let mut phases = Vec::with_capacity(omega.len());
    let (mut best_i, mut best_f) = (0, f64::NEG_INFINITY);
    for i in 0..points {
        if i % super::phasor::RESYNC == 0 || i + 1 == points {
            exact(at(i), &mut phases);
        } else {
            phases.iter_mut().zip(&turn).for_each(|(z, t)| *z *= t);
        }
        let f = sums.value(&phases);
        if f > best_f {
            (best_i, best_f) = (i, f);
        }
    }
    let lo = at(best_i.saturating_sub(1));
    let hi = at((best_i + 1).min(points - 1));
    refine(sums, lo, hi, at(best_i))
}

/// Safeguarded Newton on `F'` in `[lo, hi]` from `start`; where `F'` does not change sign across
/// the cell the better end (or the start) is kept, since the maximum then lies on the boundary.
fn refine(sums: &Sums, mut lo: f64, mut hi: f64, start: f64) -> f64 {
    let (f_lo, g_lo, _) = sums.objective(lo, true);
    let (f_hi, g_hi, _) = sums.objective(hi, true);
    if !(g_lo >= 0.0 && g_hi <= 0.0) {
        let f_start = sums.objective(start, false).0;
        return [(lo, f_lo), (hi, f_hi), (start, f_start)]
            .into_iter()
            .fold((start, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b })
            .0;
    }
    let mut tau = start;
    for _ in 0..200 {
        let (_, g, g2) = sums.objective(tau, true);
        if g > 0.0 {
            lo = tau;
        } else {
            hi = tau;
        }
        let newton = tau - g / g2;
        let next = if g2 < 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let moved = (next - tau).abs();
        tau = next;
        if moved <= 1e-15 || hi - lo <= 1e-15 || g == 0.0 {
            break;
        }
    }
    tau
}
