//! Orders 1..=4: `W(s) = N(s) / d(s) e^(-tau s)` with a common denominator.
//!
//! Everything is computed in `sigma = s / omega_ref` (`omega_ref` the band's top) so that the
//! monomials stay within `[0, 1]` in modulus.
//!
//! 1. Start: Sanathanan–Koerner iterations at a fixed delay. Each iteration solves the linearised
//!    weighted least squares `sum w |N_e - d H_e|^2 / |d_prev|^2` (`H = W e^(s tau)`, real
//!    unknowns, rows the real and imaginary parts) by eliminating each element's numerator with a
//!    faer QR of its block and solving the stacked reduced rows for `d`. A start with unstable
//!    roots is refined both as it is and with those roots reflected into the left half-plane.
//!    These iterations use the diagonal approximation `w = Re(Omega_i)_jj` of the row weights
//!    (exact on the variance path): they only provide a start, and the refinement below minimises
//!    the full generalised least-squares objective.
//! 2. Refinement: variable projection. For given `(d, tau)` each output row's numerator is the
//!    exact generalised least-squares solution (a `3 max(n,1)`-square normal system), so the
//!    Levenberg–Marquardt iteration runs over the `n + 1` nonlinear parameters only, with a
//!    forward-difference Jacobian of the projected residual vector.
//!
//! Several starts are refined (SK at the previous order's delay; the previous order's
//! denominator times a far pole `1 + sigma / 10`, whose projected residual cannot exceed the
//! previous order's from order 2 on, since the numerator space then holds the previous numerator
//! times the same factor). The
//! best is also refined once more from its mirror image (same magnitude response), the delay moved
//! to keep the phase slope: at order 1 always (`1 - T s`), from order 2 when it has poles in the
//! right half plane. A right-half-plane pole plus a longer delay is otherwise easy to confuse with
//! a stable pole: a gyro behind a 100 Hz second-order filter (an independent simulator's run) was
//! fitted at order 2 with an unstable pair and a delay of 6.75 ms, its true 3 ms never tried.
//! Order 2 also starts from a sensor's anti-alias pairs, at 1.5, 3 and 6 times the band's top
//! ([`filter_pairs`]), on every fit: when they ran only after an unstable best, a 1 kHz run of
//! our simulator behind a 100 Hz filter found a stable pair at 340 Hz first (outside the band,
//! rejected) and kept order 0 with the filter's lag in its delay. The smallest residual wins unless it is unstable and
//! the data do not prefer it significantly to the best stable one (Vuong's test,
//! [`Fitted::preferred`]); an unstable fit the data do prefer is returned and flagged as such by
//! the caller, never swapped silently for a worse stable one.

use faer::prelude::SolveLstsq;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::project::Projector;
use num_complex::Complex64;

use super::UnstableSetAside;
use super::model::{ELEMENTS, Model, Prepared};

/// Sanathanan–Koerner iterations per start.
const SK_ITERATIONS: usize = 8;
/// Natural frequencies of the order-2 filter starts, in units of the band's top ([`filter_pairs`]).
const FILTER_RATIOS: [f64; 3] = [1.5, 3.0, 6.0];
/// Vuong's statistic beyond which an order's unstable best fit is preferred to its best stable
/// one ([`Fitted::preferred`]): three deviations, the project's bar for evidence against what a
/// sensor physically is (a negative delay, zeros that lead). The statistic is only as exact as
/// the weights and the bins' correlation (chi2/dof 0.8-1.8 on the campaigns); at two deviations
/// an independent simulator's accelerometer behind a 100 Hz filter with pink noise and
/// quantisation (`m1_fn`) kept an unstable pair over the true one (pair at 645 rad/s, damping
/// 0.70, delay 2.07 ms against 2.00) at z 2.16-2.62 and its `K` 0.54 % off at order 0.
pub(super) const PREFERENCE_Z: f64 = 3.0;
/// Damping of the order-2 filter starts (a Butterworth pair).
const FILTER_DAMPING: f64 = std::f64::consts::FRAC_1_SQRT_2;
/// When a refinement from scratch stops (see [`refine`]).
const COLD: Stop = Stop {
    patience: 5,
    enough: 0.0,
};
/// When a refinement from a previous optimum (a retune) stops: it starts in the valley, and its
/// result is provisional (the app refits from scratch once the settings rest), so a predicted
/// gain below `0.01` in chi2 (parameters within about `0.1` standard deviation of the optimum)
/// is enough.
const WARM: Stop = Stop {
    patience: 1,
    enough: 0.01,
};

/// Stopping rules of [`refine`] beyond convergence to rounding.
#[derive(Clone, Copy)]
struct Stop {
    /// Iterations over which a crawl at the noise level (less than `0.05` gained) stops.
    patience: usize,
    /// A predicted decrease of chi2 at or below this stops.
    enough: f64,
}

/// An order's fit: the refined start of smallest chi2, and, when that one is unstable, the best
/// stable one too (the caller decides between them, [`Fitted::preferred`]).
pub(super) struct Fitted {
    /// The smallest chi2 of every refined start, stable or not.
    pub best: (Model, f64),
    /// The stable refined start of smallest chi2, when `best` is unstable.
    pub stable: Option<(Model, f64)>,
}

impl Fitted {
    /// `best`, unless it is unstable and the data do not prefer it to `stable` significantly:
    /// Vuong's test for two models of as many parameters, on the per-bin differences of their
    /// chi2 terms (`d_k`, bins `correlation` apart counted as one), prefers the unstable fit
    /// only when `sum d_k` exceeds `PREFERENCE_Z` of its standard deviation. A sensor's dynamics
    /// are stable: an order judged by (and rejected for) an unstable fit its data do not prefer
    /// leaves a lower order that is wrong. An independent simulator's gyro behind a 100 Hz
    /// second-order filter at 1 kHz: the true pair (`omega_n` 630 rad/s, damping 0.71, delay
    /// 3.02 ms against 3) had a chi2 4 above an unstable fit (poles at +890 and -391 rad/s,
    /// delay 6.6 ms), and order 0 was kept with its delay 10 deviations off.
    ///
    /// Returns the model, and the unstable fit when it was set aside (its chi2 and `z`).
    pub fn preferred(self, data: &Prepared, correlation: f64) -> (Model, Option<UnstableSetAside>) {
        let Some((stable, _)) = self.stable else {
            return (self.best.0, None);
        };
        let vuong_z = preference_z(data, &self.best.0, &stable, correlation);
        if vuong_z > PREFERENCE_Z {
            (self.best.0, None)
        } else {
            let set_aside = UnstableSetAside {
                chi2: self.best.1,
                vuong_z,
            };
            (stable, Some(set_aside))
        }
    }
}

/// Vuong's statistic of `a` over `b` on `data` ([`vuong_z`] of the per-bin differences of
/// their chi2 terms, `b`'s less `a`'s: positive when `a` fits better).
fn preference_z(data: &Prepared, a: &Model, b: &Model, correlation: f64) -> f64 {
    let d: Vec<f64> = a
        .chi2_rows(data)
        .iter()
        .zip(b.chi2_rows(data))
        .map(|(ra, rb)| rb.iter().sum::<f64>() - ra.iter().sum::<f64>())
        .collect();
    vuong_z(&d, correlation)
}

/// `sum d_k / sqrt(correlation n var(d_k))`: the sum of `n` differences over its standard
/// deviation, neighbouring bins `correlation` apart counted as one (`bin_correlation`, the
/// variance inflation of the bins' errors). With every difference equal there is no spread: the
/// evidence is then as large as its sign (`+-inf`, or 0 when they are 0). Any non-finite
/// difference gives 0: no evidence either way. Fewer than two differences give 0.
pub(super) fn vuong_z(d: &[f64], correlation: f64) -> f64 {
    if d.len() < 2 || !d.iter().all(|v| v.is_finite()) {
        return 0.0;
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let sd = (correlation.max(1.0) * n * var).sqrt();
    if sd > 0.0 {
        mean * n / sd
    } else if mean == 0.0 {
        0.0
    } else {
        mean.signum() * f64::INFINITY
    }
}

/// Fits order `order >= 1` starting from `prev` (the fit of order `order - 1`).
pub(super) fn fit(data: &Prepared, order: usize, prev: &Model, max_iter: usize) -> Option<Fitted> {
    let mut starts = Vec::new();
    if let Some(den) = sk_denominator(data, order, prev.tau) {
        let reflected = reflect_unstable(&den);
        if reflected != den {
            starts.push((den, prev.tau));
        }
        starts.push((reflected, prev.tau));
    }
    starts.push((extended(&prev.den), prev.tau));
    if order == 2 {
        starts.extend(filter_pairs(prev, data.omega_ref));
    }
    // The starts are refined in parallel and compared in order, as a sequential loop would.
    let mut fits: Vec<(Model, f64)> = starts
        .into_par_iter()
        .filter_map(|(den, tau)| refined(data, den, tau, max_iter))
        .collect();
    // The mirror image of the best: at order 1 always (`1 - T s`), from order 2 when the best has
    // poles in the right half plane (those reflected into the left). A pole and its mirror have
    // the same magnitude response, so each is a local optimum the other start can miss; the delay
    // moves to keep the low-frequency phase slope (`d_1 / omega_ref`, the poles' lag).
    let mirror = smallest(&fits, |_| true).and_then(|(m, _)| {
        let den = if order == 1 {
            vec![-m.den[0]]
        } else {
            Some(reflect_unstable(&m.den)).filter(|r| *r != m.den)?
        };
        let tau = m.tau + (m.den[0] - den[0]) / data.omega_ref;
        Some((den, tau))
    });
    if let Some((den, tau)) = mirror {
        fits.extend(refined(data, den, tau, max_iter));
    }
    let best = smallest(&fits, |_| true)?.clone();
    let stable = if is_stable(&best.0.den) {
        None
    } else {
        smallest(&fits, |m| is_stable(&m.den)).cloned()
    };
    Some(Fitted { best, stable })
}

/// The fit of smallest finite chi2 among those `keep` accepts (the first of equals).
fn smallest(fits: &[(Model, f64)], keep: impl Fn(&Model) -> bool) -> Option<&(Model, f64)> {
    fits.iter()
        .filter(|(m, chi2)| chi2.is_finite() && keep(m))
        .reduce(|a, b| if b.1 < a.1 { b } else { a })
}

/// Refines `start`, a fit of its order to nearby data (a retune), with the looser stopping rules
/// of [`WARM`]: the model and its chi2, `None` if the refinement fails.
pub(super) fn refine_warm(data: &Prepared, start: &Model, max_iter: usize) -> Option<(Model, f64)> {
    let model = refine(data, start.den.clone(), start.tau, max_iter, WARM)?;
    let chi2 = model.chi2(data);
    chi2.is_finite().then_some((model, chi2))
}

/// `d(sigma) (1 + sigma / 10)`: the denominator `den` with a pole ten times above the band.
fn extended(den: &[f64]) -> Vec<f64> {
    let mut padded = den.to_vec();
    padded.push(0.0);
    let mut out = padded.clone();
    out[0] += 0.1;
    for m in 1..out.len() {
        out[m] += 0.1 * padded[m - 1];
    }
    out
}

/// Order-2 starts from a sensor's own anti-alias filter, the commonest dynamics a block has: a
/// Butterworth pair (damping `FILTER_DAMPING`) at each of `FILTER_RATIOS` times the band's top,
/// the delay less the pair's lag at low frequency (`2 zeta / omega_n`) so that the phase slope of
/// `prev` (its delay plus its poles' lag, `d_1 / omega_ref`) is kept. Without them an order-2 fit
/// behind a real right-half-plane pole can miss a stable complex pair whose magnitude it cannot
/// reach by mirroring: an independent simulator's gyro behind a 100 Hz filter at 1 kHz was
/// fitted with poles at -1603 and +716 rad/s and a delay of 6.5 ms, and kept order 0.
fn filter_pairs(prev: &Model, omega_ref: f64) -> impl Iterator<Item = (Vec<f64>, f64)> {
    let lag = prev.tau + prev.den.first().copied().unwrap_or(0.0) / omega_ref;
    FILTER_RATIOS.iter().map(move |ratio| {
        let r = 1.0 / ratio;
        let d1 = 2.0 * FILTER_DAMPING * r;
        (vec![d1, r * r], lag - d1 / omega_ref)
    })
}

/// Refines from `(den, tau)`; the model and its chi2.
fn refined(data: &Prepared, den: Vec<f64>, tau: f64, max_iter: usize) -> Option<(Model, f64)> {
    let model = refine(data, den, tau, max_iter, COLD)?;
    let chi2 = model.chi2(data);
    Some((model, chi2))
}

/// Whether every root of `1 + sum den[m-1] sigma^m` has a negative real part.
pub(super) fn is_stable(den: &[f64]) -> bool {
    den.iter().all(|c| c.is_finite()) && roots(den).iter().all(|r| r.re < 0.0)
}

/// The finite roots of `1 + sum den[m-1] sigma^m` (a vanishing leading coefficient sends its
/// root to infinity, which is not listed); NaN for non-finite coefficients, which the caller's
/// final check turns into an error.
pub(super) fn roots(den: &[f64]) -> Vec<Complex64> {
    if !den.iter().all(|c| c.is_finite()) {
        return vec![Complex64::new(f64::NAN, f64::NAN); den.len()];
    }
    let scale = den.iter().fold(1.0_f64, |a, c| a.max(c.abs()));
    let Some(deg) = den.iter().rposition(|c| c.abs() > 1e-14 * scale) else {
        return Vec::new();
    };
    let n = deg + 1;
    let lead = den[deg];
    // Companion matrix of the monic polynomial sigma^n + ... + 1 / lead.
    let companion = DMatrix::from_fn(n, n, |i, j| {
        if i == 0 {
            let m = n - 1 - j; // coefficient of sigma^m
            let c = if m == 0 { 1.0 } else { den[m - 1] };
            -c / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion.complex_eigenvalues().iter().copied().collect()
}

/// The denominator with each right-half-plane root mirrored to the left.
fn reflect_unstable(den: &[f64]) -> Vec<f64> {
    let r = roots(den);
    if r.len() != den.len() || r.iter().all(|z| z.re < 0.0) {
        return den.to_vec();
    }
    // prod (1 - sigma / r_i), with r_i -> -conj(r_i) where Re r_i >= 0.
    let mut coef = vec![Complex64::new(1.0, 0.0)];
    for z in r {
        let z = if z.re >= 0.0 { -z.conj() } else { z };
        if z.norm() == 0.0 {
            return den.to_vec();
        }
        let mut next = vec![Complex64::new(0.0, 0.0); coef.len() + 1];
        for (m, c) in coef.iter().enumerate() {
            next[m] += c;
            next[m + 1] -= c / z;
        }
        coef = next;
    }
    coef[1..].iter().map(|c| c.re).collect()
}

/// Sanathanan–Koerner estimate of the denominator at a fixed delay.
fn sk_denominator(data: &Prepared, order: usize, tau: f64) -> Option<Vec<f64>> {
    let n_num = order;
    let cols = n_num + order + 1;
    let rows = 2 * data.bins();
    if rows < cols {
        return None;
    }
    let mut den = vec![0.0; order];
    for _ in 0..SK_ITERATIONS {
        let prev = Model {
            num: Vec::new(),
            den: den.clone(),
            tau,
        };
        let mut reduced = faer::Mat::<f64>::zeros(ELEMENTS * (order + 1), order);
        let mut rhs = faer::Mat::<f64>::zeros(ELEMENTS * (order + 1), 1);
        let mut block = faer::Mat::<f64>::zeros(rows, cols);
        for e in 0..ELEMENTS {
            for k in 0..data.bins() {
                let x = data.x[k];
                let sigma = Complex64::new(0.0, x);
                let q = (data.w[k][e] / prev.den_at(x).norm_sqr()).sqrt();
                let h = data.h[k][e] * Complex64::from_polar(q, data.omega[k] * tau);
                let mut pw = Complex64::new(1.0, 0.0);
                for c in 0..cols {
                    let z = if c < n_num {
                        pw * q
                    } else if c < cols - 1 {
                        -h * pw
                    } else {
                        h
                    };
                    block[(2 * k, c)] = z.re;
                    block[(2 * k + 1, c)] = z.im;
                    pw = if c + 1 == n_num { sigma } else { pw * sigma };
                }
            }
            let qr = block.qr();
            let r = qr.thin_R();
            for i in 0..=order {
                for c in 0..order {
                    reduced[(e * (order + 1) + i, c)] = r[(n_num + i, n_num + c)];
                }
                rhs[(e * (order + 1) + i, 0)] = r[(n_num + i, cols - 1)];
            }
        }
        let next = reduced.col_piv_qr().solve_lstsq(&rhs);
        let next: Vec<f64> = (0..order).map(|m| next[(m, 0)]).collect();
        if next.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let change = next
            .iter()
            .zip(&den)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        den = next;
        if change <= 1e-12 {
            break;
        }
    }
    Some(den)
}

/// Levenberg–Marquardt over `(den, tau omega_ref)` with the numerator projected out, with a
/// forward-difference Jacobian of the projected residual (step `1e-7 max(|theta|, 0.1)`). Stops
/// when the undamped Gauss–Newton step predicts a decrease of chi2 below
/// `max(1e-10 chi2 + 1e-20, stop.enough)` (converged), after ten rejected steps in a row (nothing
/// left at machine precision), when chi2 has reached the noise level (`chi2 > 0.1 * 18 n_bins`)
/// and `stop.patience` iterations
/// together lowered it by less than `0.05` (a crawl along the flat valley of an
/// over-parameterised order: such a difference is far below the criterion's penalty of `~8.7` per
/// parameter and moves a parameter by well under its standard deviation), or after `max_iter`
/// iterations.
fn refine(data: &Prepared, den: Vec<f64>, tau: f64, max_iter: usize, stop: Stop) -> Option<Model> {
    let patience = stop.patience;
    let n = den.len();
    let rows = data.real_data();
    let w_ref = data.omega_ref;
    let mut projector = Projector::new(data, n.max(1));
    let mut theta: Vec<f64> = den;
    theta.push(tau * w_ref);
    let mut r = vec![0.0; rows];
    let mut eval = |t: &[f64], out: &mut [f64]| -> Option<f64> {
        projector.project(&t[..n], t[n] / w_ref, out)?;
        let c: f64 = out.iter().map(|v| v * v).sum();
        c.is_finite().then_some(c)
    };
    let mut cost = eval(&theta, &mut r)?;
    let mut jac = vec![vec![0.0; rows]; n + 1];
    let mut plus = vec![0.0; rows];
    let mut lambda = 1e-3;
    let mut history = vec![cost];
    let noise_level = 0.1 * rows as f64;
    'outer: for _ in 0..max_iter {
        for (i, col) in jac.iter_mut().enumerate() {
            let h = 1e-7 * theta[i].abs().max(0.1);
            let mut t = theta.clone();
            t[i] = theta[i] + h;
            eval(&t, &mut plus)?;
            for ((c, p), r0) in col.iter_mut().zip(&plus).zip(&r) {
                *c = (p - r0) / h;
            }
        }
        let a = DMatrix::from_fn(n + 1, n + 1, |i, j| dot(&jac[i], &jac[j]));
        let g = DVector::from_fn(n + 1, |i, _| dot(&jac[i], &r));
        let predicted = a.clone().cholesky().map(|c| g.dot(&c.solve(&g)));
        if predicted.is_some_and(|p| p <= (1e-10 * cost + 1e-20).max(stop.enough)) {
            break;
        }
        let mut rejected = 0;
        loop {
            if rejected >= 10 {
                break 'outer;
            }
            let mut damped = a.clone();
            for i in 0..=n {
                damped[(i, i)] += lambda * a[(i, i)].max(1e-30);
            }
            let trial: Option<Vec<f64>> = damped
                .cholesky()
                .map(|c| c.solve(&(-&g)))
                .filter(|s| s.iter().all(|v| v.is_finite()))
                .map(|s| theta.iter().zip(s.iter()).map(|(t, s)| t + s).collect());
            let Some(trial) = trial else {
                lambda *= 4.0;
                rejected += 1;
                continue;
            };
            match eval(&trial, &mut plus) {
                Some(c) if c < cost => {
                    theta = trial;
                    cost = c;
                    std::mem::swap(&mut r, &mut plus);
                    lambda = (lambda / 3.0).max(1e-12);
                    history.push(cost);
                    break;
                }
                _ => {
                    lambda *= 4.0;
                    rejected += 1;
                }
            }
        }
        let stalled = history.len() > patience && history[history.len() - 1 - patience] - cost < 0.05;
        if cost > noise_level && stalled {
            break;
        }
    }
    let num = projector.project(&theta[..n], theta[n] / w_ref, &mut r)?;
    Some(Model {
        num,
        den: theta[..n].to_vec(),
        tau: theta[n] / w_ref,
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
