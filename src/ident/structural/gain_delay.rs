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
//! inside the best grid cell to a step below `1e-15` s. The scan allocates nothing: each point
//! costs one complex product per bin for its phase factor (`super::phasor`) and nine complex
//! multiply-adds.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::model::{ELEMENTS, Model, Prepared};

/// The most points of the delay scan.
const MAX_SCAN: usize = 20_000;

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

/// The order-0 fit on the delay range `[tau_min, tau_max]` (finite, non-empty).
pub(super) fn fit(data: &Prepared, tau_min: f64, tau_max: f64) -> Model {
    let sums = sums(data);
    let tau = best_delay(&sums, tau_min, tau_max);
    Model {
        num: vec![sums.gain(tau)],
        den: Vec::new(),
        tau,
    }
}

/// The order-0 fit whose delay is known to lie within a scan step (`1 / (16 f_max)`) of `near`
/// (data changed a little since a fit gave `near`): refined inside that cell alone, or by the
/// whole scan over `[tau_min, tau_max]` when the cell does not hold a maximum.
pub(super) fn fit_near(data: &Prepared, near: f64, tau_min: f64, tau_max: f64) -> Model {
    let sums = sums(data);
    let step = 2.0 * std::f64::consts::PI / data.omega_ref / 16.0;
    let (lo, hi) = ((near - step).max(tau_min), (near + step).min(tau_max));
    let (_, g_lo, _) = sums.objective(lo, true);
    let (_, g_hi, _) = sums.objective(hi, true);
    let tau = if lo < hi && g_lo > 0.0 && g_hi < 0.0 {
        refine(&sums, lo, hi, near.clamp(lo, hi))
    } else {
        best_delay(&sums, tau_min, tau_max)
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
        .zip(&data.rows)
        .map(|(h, rows)| {
            std::array::from_fn(|e| {
                let (i, j) = (e / 3, e % 3);
                (0..3).map(|l| h[3 * i + l] * rows[i].omega[(l, j)]).sum()
            })
        })
        .collect();
    let mut a = [Matrix3::<f64>::zeros(); 3];
    for rows in &data.rows {
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

/// Scan, then refine inside the best cell.
fn best_delay(sums: &Sums, tau_min: f64, tau_max: f64) -> f64 {
    let top = 2.0 * std::f64::consts::PI / sums.data.omega_ref;
    let span = tau_max - tau_min;
    let points = ((span / (top / 16.0)).ceil() as usize).clamp(2, MAX_SCAN);
    let step = span / (points - 1) as f64;
    let at = |i: usize| {
        if i + 1 == points {
            tau_max
        } else {
            tau_min + step * i as f64
        }
    };
    let (mut best_i, mut best_f) = (0, f64::NEG_INFINITY);
    for i in 0..points {
        let f = sums.objective(at(i), false).0;
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
