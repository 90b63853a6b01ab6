//! Order 0, `W(s) = K e^(-tau s)`.
//!
//! For a fixed delay the gain is closed form element by element,
//! `K_e(tau) = A_e(tau) / S_e` with `A_e = sum_k w_ke Re(W_ke e^(j w_k tau))` and
//! `S_e = sum_k w_ke`, and the residual is `J(tau) = const - F(tau)`,
//! `F = sum_e A_e^2 / S_e`. The delay maximises `F`: a scan over the settings' range with a step of
//! `1 / (16 f_max)` (the phase of the top bin wraps every `1 / f_max`, so no basin is missed; the
//! step grows only if the range would need more than `MAX_SCAN` points), then a safeguarded
//! Newton iteration on `F'` inside the best grid cell, with `F'` and `F''` analytic, to a step
//! below `1e-15` s. The scan allocates nothing: each point costs one `sin_cos` per bin and nine
//! complex multiply-adds.

use num_complex::Complex64;

use super::model::{ELEMENTS, Model, Prepared};

/// The most points of the delay scan.
const MAX_SCAN: usize = 20_000;

/// Sums independent of the delay.
struct Sums<'a> {
    data: &'a Prepared,
    /// `w_ke h_ke`.
    wh: Vec<[Complex64; ELEMENTS]>,
    /// `S_e = sum_k w_ke`.
    s: [f64; ELEMENTS],
}

impl Sums<'_> {
    /// `(F, F', F'')` at `tau`; the derivatives only when `derivatives`.
    fn objective(&self, tau: f64, derivatives: bool) -> (f64, f64, f64) {
        let mut c0 = [Complex64::new(0.0, 0.0); ELEMENTS];
        let mut c1 = c0;
        let mut c2 = c0;
        for (k, wh) in self.wh.iter().enumerate() {
            let omega = self.data.omega[k];
            let (sin, cos) = (omega * tau).sin_cos();
            let z = Complex64::new(cos, sin);
            for e in 0..ELEMENTS {
                let t = wh[e] * z;
                c0[e] += t;
                if derivatives {
                    c1[e] += t * omega;
                    c2[e] += t * (omega * omega);
                }
            }
        }
        let (mut f, mut f1, mut f2) = (0.0, 0.0, 0.0);
        for e in 0..ELEMENTS {
            let (a, a1, a2) = (c0[e].re, -c1[e].im, -c2[e].re);
            f += a * a / self.s[e];
            f1 += 2.0 * a * a1 / self.s[e];
            f2 += 2.0 * (a1 * a1 + a * a2) / self.s[e];
        }
        (f, f1, f2)
    }

    /// The gain for a given delay.
    fn gain(&self, tau: f64) -> [f64; ELEMENTS] {
        let mut a = [0.0; ELEMENTS];
        for (k, wh) in self.wh.iter().enumerate() {
            let (sin, cos) = (self.data.omega[k] * tau).sin_cos();
            let z = Complex64::new(cos, sin);
            for e in 0..ELEMENTS {
                a[e] += (wh[e] * z).re;
            }
        }
        std::array::from_fn(|e| a[e] / self.s[e])
    }
}

/// The order-0 fit on the delay range `[tau_min, tau_max]` (finite, non-empty).
pub(super) fn fit(data: &Prepared, tau_min: f64, tau_max: f64) -> Model {
    let wh = data
        .h
        .iter()
        .zip(&data.w)
        .map(|(h, w)| std::array::from_fn(|e| h[e] * w[e]))
        .collect();
    let mut s = [0.0; ELEMENTS];
    for w in &data.w {
        for e in 0..ELEMENTS {
            s[e] += w[e];
        }
    }
    let sums = Sums { data, wh, s };
    let tau = best_delay(&sums, tau_min, tau_max);
    Model {
        num: vec![sums.gain(tau)],
        den: Vec::new(),
        tau,
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
