//! Which fitted orders may be chosen: a candidate above order 0 must describe dynamics the data
//! can actually see. BIC alone cannot guarantee that: its weights come from the estimated noise,
//! and where that estimate is off (coloured reference noise, a misfit the model cannot hold) the
//! extra poles of a high order chase the error and extrapolate nonsense (a static gain of 1e8, a
//! delay of -58 ms). A candidate of order `n >= 1` is **admissible** only if
//! 1. it is stable (every pole in the left half plane);
//! 2. every pole is finite and lies where the band can resolve it: `|p| / 2 pi` between half the
//!    band's lowest frequency / [`POLE_REACH`] and its highest x [`POLE_REACH`]; a pole far above
//!    the band only adds delay, one far below it only rescales the static gain, and neither is measured;
//! 3. its parameters are determined: the delay's standard deviation is finite, and every
//!    denominator coefficient's is below its value (a pole the data cannot place is not a finding);
//! 4. its delay is physically sensible: not negative beyond three of its standard deviations
//!    (a sensor cannot answer before the stand moves), and not negative at all when the data do
//!    not tell it from the poles' own lag: when two of its standard deviations cover the lag the
//!    poles add at low frequency (`d_1`, the sum of their time constants), a model with that lag
//!    moved into the delay fits as well, and a negative delay is then the poles standing in for
//!    it, not a finding. Found on 60 s stretches of real recordings: a pair near 50 Hz (`d_1`
//!    3.6 ms) with a delay of -3.7 +- 4.5 ms fitted the reference's band limit (a gain rise with
//!    no phase) better than the delay alone, and predicted the other half better too. A positive
//!    delay is not judged by it: from order 2 the delay also trades with the numerator's first
//!    coefficient, so an all-pole sensor filter can leave it undetermined, and such a candidate
//!    stays admissible as before. A real sensor lag in simulated runs has `d_1` about 4.5 ms and
//!    its delay known to 0.01-0.02 ms. Nor is a negative delay admissible when the numerator's
//!    zeros give its lead back as lag (their low-frequency lag, minus the mean of `N_0^-1 N_1`'s
//!    eigenvalues, positive beyond two of its standard deviations, bounded as if its parameters
//!    were fully correlated: zeros in the right half plane). A sensor's filters have no such zeros, and a lead with a lag that cancels it is the
//!    delay-only phase with a gain rising across the band, the reference's band limit again. Found
//!    on 20-40 s pieces of the real recordings (after the rule on the poles' lag): order 2 with
//!    a pair near 35 Hz, a delay of -6.6 +- 2.3 ms and zeros adding 4.78 +- 0.40 ms, whose whole
//!    phase is that of a 4.13-4.24 ms delay and whose gain rises by 10 % across the band;
//! 5. its static gain agrees with its in-band gain: at the band's lowest frequency the model,
//!    delay removed, is within [`STATIC_GAIN_AGREEMENT`] of `K` (relative Frobenius). Otherwise
//!    `K` is an extrapolation below the data;
//! 6. (checked after rule 2) no lightly damped pole pair (damping below [`EDGE_DAMPING`]) has its natural frequency at or
//!    beyond the band's top edge (above [`EDGE_MARGIN`] of the highest band frequency): the data
//!    then show only the resonance's skirt, a gain rising towards the band's top with little
//!    phase, which is what a band-limited reference gives too (the inputs are computed from
//!    angles whose measurement falls off there: `W / B` rises). Measured on simulated stands with
//!    a reference band limit at 30 Hz: order 4 was chosen on 3 of 24 block fits with a pair at
//!    32-34 Hz of damping 0.0004-0.02 and delays 1.5-3.5 ms wrong.
//!
//! 7. it predicts data it was not fitted to better than every lower order: fitted to one half of
//!    the record, it predicts the other half (both ways, summed) with a smaller chi2
//!    ([`not_predictive`], from the held-out figures of [`super::held_out_chi2`]; not applied
//!    when the record is too short to halve). BIC judges the candidates on their own data, with
//!    weights that may be wrong; poles that fit noise lower chi2 there and raise it on the
//!    other half, while a real pole lowers it on both.
//!
//! Order 0 is always admissible (it is the paper's model); its own plausibility (delay sign,
//! gain) is checked by the self-check of the identification, not here.
//!
//! Units: poles in rad/s, band in rad/s, delays in s. Every rule is reported by [`Rejection`].

use std::f64::consts::PI;
use std::fmt;

use nalgebra::Matrix3;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::model::{ELEMENTS, Model, Prepared};
use super::rational;

/// How far outside the band a pole may lie and still be resolved: `[f_low / r, r f_high]`.
pub const POLE_REACH: f64 = 4.0;

/// Largest relative Frobenius difference between the static gain and the model's gain at the
/// band's lowest frequency (delay removed).
pub const STATIC_GAIN_AGREEMENT: f64 = 0.05;

/// Pole pairs damped less than this are resonances whose peak the data must contain (rule 6).
/// Below a 4th-order Butterworth's lighter pair (0.38), so a sensor's anti-alias filter near the
/// band's top is not excluded by it; the pairs measured at a band-limited reference's edge had
/// 0.0004-0.02.
pub const EDGE_DAMPING: f64 = 0.2;

/// A resonance's natural frequency must lie below this fraction of the band's highest frequency
/// (rule 6).
pub const EDGE_MARGIN: f64 = 0.9;

/// Why a candidate order was not admissible.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Rejection {
    /// A pole in the right half plane (or on the axis).
    Unstable,
    /// A vanished leading denominator coefficient: a pole at infinity (the order is really lower).
    PoleAtInfinity,
    /// A pole outside the resolvable range.
    PoleOutsideBand {
        /// The pole's magnitude, Hz.
        pole_hz: f64,
        /// Lowest resolvable magnitude, Hz.
        low_hz: f64,
        /// Highest resolvable magnitude, Hz.
        high_hz: f64,
    },
    /// A delay that is negative beyond its uncertainty.
    NegativeDelay {
        /// The delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
    },
    /// A denominator coefficient or the delay the data do not determine.
    Undetermined {
        /// Largest relative standard deviation of a denominator coefficient.
        relative_std: f64,
    },
    /// A negative delay the data do not tell from the poles' lag (rule 4): two standard
    /// deviations of the delay cover the lag the poles add at low frequency.
    DelayTradedForPoles {
        /// The delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
        /// The poles' lag at low frequency (`d_1`, the sum of their time constants), s.
        pole_lag_s: f64,
    },
    /// A negative delay whose lead the numerator's zeros give back as lag (rule 4): zeros in the
    /// right half plane, which a sensor's filters do not have.
    DelayTradedForZeros {
        /// The delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
        /// The lag the numerator adds at low frequency (minus the mean of `N_0^-1 N_1`'s
        /// eigenvalues), s.
        zero_lag_s: f64,
        /// Its standard deviation, s.
        zero_lag_std_s: f64,
    },
    /// The static gain is an extrapolation: it differs from the in-band gain.
    StaticGainDisagrees {
        /// Relative Frobenius difference at the band's lowest frequency.
        difference: f64,
    },
    /// A lightly damped resonance at or beyond the band's top edge: only its skirt is measured.
    ResonanceAtBandEdge {
        /// The pair's natural frequency, Hz.
        natural_hz: f64,
        /// Its damping ratio.
        damping: f64,
        /// The band's highest frequency, Hz.
        band_top_hz: f64,
    },
    /// Fitted to one half of the record, it predicts the other half no better than a lower order
    /// does (rule 7): its extra poles fit noise.
    NotPredictive {
        /// Its held-out chi2 (each half predicted by the fit to the other, summed); absent when
        /// it could not be fitted to both halves.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        held_out_chi2: Option<f64>,
        /// The lower order that predicts better.
        lower_order: usize,
        /// That order's held-out chi2.
        lower_held_out_chi2: f64,
    },
}

impl fmt::Display for Rejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Rejection::Unstable => write!(f, "unstable (a pole in the right half plane)"),
            Rejection::PoleAtInfinity => write!(f, "a pole at infinity (the order is really lower)"),
            Rejection::PoleOutsideBand {
                pole_hz,
                low_hz,
                high_hz,
            } => write!(
                f,
                "a pole at {pole_hz:.3} Hz, outside what the band can resolve ({low_hz:.3}-{high_hz:.3} Hz)"
            ),
            Rejection::NegativeDelay { tau_s, tau_std_s } => write!(
                f,
                "delay {:.3} ms (+- {:.3} ms) is negative: the block cannot answer before the stand moves",
                tau_s * 1e3,
                tau_std_s * 1e3
            ),
            Rejection::Undetermined { relative_std } => write!(
                f,
                "its poles are not determined by the data (relative standard deviation {relative_std:.2})"
            ),
            Rejection::ResonanceAtBandEdge {
                natural_hz,
                damping,
                band_top_hz,
            } => write!(
                f,
                "a resonance at {natural_hz:.2} Hz (damping {damping:.3}) at the band's top edge \
                 ({band_top_hz:.2} Hz): only its skirt is measured, which a band-limited reference \
                 gives too"
            ),
            Rejection::NotPredictive {
                held_out_chi2: Some(own),
                lower_order,
                lower_held_out_chi2,
            } => write!(
                f,
                "fitted to one half of the record it predicts the other half no better than order \
                 {lower_order} (held-out chi2 {own:.1} against {lower_held_out_chi2:.1}): its extra \
                 poles fit noise"
            ),
            Rejection::NotPredictive {
                held_out_chi2: None,
                lower_order,
                ..
            } => write!(
                f,
                "it could not be fitted to each half of the record, so nothing shows it predicts \
                 data it was not fitted to better than order {lower_order}"
            ),
            Rejection::DelayTradedForPoles {
                tau_s,
                tau_std_s,
                pole_lag_s,
            } => write!(
                f,
                "its delay is negative ({:.3} +- {:.3} ms) and cannot be told from its poles' lag \
                 ({:.3} ms): a model with that lag moved into the delay fits as well, so the poles \
                 stand in for the delay",
                tau_s * 1e3,
                tau_std_s * 1e3,
                pole_lag_s * 1e3
            ),
            Rejection::DelayTradedForZeros {
                tau_s,
                tau_std_s,
                zero_lag_s,
                zero_lag_std_s,
            } => write!(
                f,
                "its delay is negative ({:.3} +- {:.3} ms) and its numerator's zeros add a lag \
                 ({:.3} +- {:.3} ms, zeros in the right half plane) that gives the lead back: \
                 a sensor's filters have no such zeros, so the zeros and the delay stand in for \
                 each other",
                tau_s * 1e3,
                tau_std_s * 1e3,
                zero_lag_s * 1e3,
                zero_lag_std_s * 1e3
            ),
            Rejection::StaticGainDisagrees { difference } => write!(
                f,
                "its static gain differs from its in-band gain by {:.1} % (an extrapolation)",
                difference * 100.0
            ),
        }
    }
}

/// Rule 7, for order `order >= 1`: `held_out[n]` is order `n`'s held-out chi2 (fitted to each
/// half of the record, predicting the other, summed; `None` where an order was not fitted to both
/// halves). The order must predict better than every lower order that has a held-out chi2.
/// Nothing is rejected when no lower order has one.
pub(super) fn not_predictive(order: usize, held_out: &[Option<f64>]) -> Option<Rejection> {
    let (lower_order, lower) = held_out
        .iter()
        .take(order)
        .enumerate()
        .filter_map(|(n, c)| c.map(|c| (n, c)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let own = held_out.get(order).copied().flatten();
    match own {
        Some(own) if own < lower => None,
        _ => Some(Rejection::NotPredictive {
            held_out_chi2: own,
            lower_order,
            lower_held_out_chi2: lower,
        }),
    }
}

/// The first rule `model` breaks, or `None` when it is admissible. The parameter standard
/// deviations ([`Model::parameter_std`]) are widened by `inflation` (`sqrt(max(1, chi2 / dof))`)
/// and computed only when the cheap rules pass; rule 7 is checked last, with `held_out` (each
/// order's held-out chi2), and not at all without it.
pub(super) fn rejection(
    data: &Prepared,
    model: &Model,
    inflation: f64,
    held_out: Option<&[Option<f64>]>,
) -> Option<Rejection> {
    physical_rejection(data, model, inflation)
        .or_else(|| held_out.and_then(|h| not_predictive(model.order(), h)))
}

/// Rules 1-6.
fn physical_rejection(data: &Prepared, model: &Model, inflation: f64) -> Option<Rejection> {
    let order = model.order();
    if order == 0 {
        return None;
    }
    if !rational::is_stable(&model.den) {
        return Some(Rejection::Unstable);
    }
    let w_ref = data.omega_ref;
    let low = data.omega.iter().copied().reduce(f64::min).unwrap_or(w_ref) / POLE_REACH;
    let high = data.omega.iter().copied().reduce(f64::max).unwrap_or(w_ref) * POLE_REACH;
    let (low_hz, high_hz) = (low / (2.0 * PI), high / (2.0 * PI));
    let poles = rational::roots(&model.den);
    if poles.len() < order {
        return Some(Rejection::PoleAtInfinity);
    }
    for p in &poles {
        let magnitude = p.norm() * w_ref;
        if !magnitude.is_finite() {
            return Some(Rejection::PoleAtInfinity);
        }
        if !(low..=high).contains(&magnitude) {
            return Some(Rejection::PoleOutsideBand {
                pole_hz: magnitude / (2.0 * PI),
                low_hz,
                high_hz,
            });
        }
    }
    if let Some(edge) = resonance_at_edge(
        &poles,
        w_ref,
        data.omega.iter().copied().reduce(f64::max).unwrap_or(w_ref),
    ) {
        return Some(edge);
    }
    let std: Vec<f64> = model
        .parameter_std(data)
        .into_iter()
        .map(|s| s * inflation)
        .collect();
    let tau_std_s = std.last().copied().unwrap_or(f64::INFINITY) / w_ref;
    if !tau_std_s.is_finite() {
        return Some(Rejection::Undetermined {
            relative_std: f64::MAX,
        });
    }
    if model.tau + 3.0 * tau_std_s < 0.0 {
        return Some(Rejection::NegativeDelay {
            tau_s: model.tau,
            tau_std_s,
        });
    }
    let pole_lag_s = model.den.first().copied().unwrap_or(0.0) / w_ref;
    if model.tau < 0.0 && 2.0 * tau_std_s >= pole_lag_s {
        return Some(Rejection::DelayTradedForPoles {
            tau_s: model.tau,
            tau_std_s,
            pole_lag_s,
        });
    }
    if model.tau < 0.0
        && let Some((zero_lag_s, zero_lag_std_s)) = numerator_lag(model, &std, w_ref)
        && zero_lag_s > 2.0 * zero_lag_std_s
    {
        return Some(Rejection::DelayTradedForZeros {
            tau_s: model.tau,
            tau_std_s,
            zero_lag_s,
            zero_lag_std_s,
        });
    }
    let n_num = model.num.len();
    let relative_std = (0..order)
        .map(|m| std[ELEMENTS * n_num + m] / model.den[m].abs())
        .fold(0.0, f64::max);
    if relative_std.is_nan() || relative_std >= 1.0 {
        return Some(Rejection::Undetermined {
            relative_std: relative_std.min(f64::MAX),
        });
    }
    let difference = static_in_band_difference(data, model);
    if difference.is_nan() || difference > STATIC_GAIN_AGREEMENT {
        return Some(Rejection::StaticGainDisagrees {
            difference: difference.min(f64::MAX),
        });
    }
    None
}

/// The lag the numerator adds at low frequency and its standard deviation, s: `N(s) = N_0 (I +
/// N_0^-1 N_1 s + ...)`, so its phase there is a lead of `N_0^-1 N_1` (a matrix, s); the lag is
/// minus a third of its trace (the mean over the axes, whatever their order or mixing). Positive
/// for zeros in the right half plane. The deviation is bounded from the parameters' `std`
/// (normalised, as [`Model::parameter_std`] gives them) to first order: each parameter's
/// contribution added in magnitude, as if all were fully correlated (the diagonal `N_1` terms all
/// trade with the one delay, so they move together), which no correlation can exceed; the rule's
/// "two deviations" is then at least two. `None` without a first-order numerator coefficient
/// (orders 0 and 1) or when `N_0` is singular.
pub(super) fn numerator_lag(model: &Model, std: &[f64], w_ref: f64) -> Option<(f64, f64)> {
    let matrix = |c: &[f64; ELEMENTS]| Matrix3::from_fn(|i, j| c[3 * i + j]);
    let (n0, n1) = (matrix(model.num.first()?), matrix(model.num.get(1)?));
    let a = n0.try_inverse()?;
    let lag = -(a * n1).trace() / 3.0 / w_ref;
    // d tr(A N_1) = tr(A dN_1) - tr(A dN_0 A N_1).
    let (by_n1, by_n0) = (a.transpose(), (a * n1 * a).transpose());
    let bound: f64 = (0..ELEMENTS)
        .map(|e| {
            let (i, j) = (e / 3, e % 3);
            let (s0, s1) = (std.get(e)?, std.get(ELEMENTS + e)?);
            Some((by_n1[(i, j)] * s1).abs() + (by_n0[(i, j)] * s0).abs())
        })
        .sum::<Option<f64>>()?;
    let lag_std = bound / 3.0 / w_ref;
    (lag.is_finite() && lag_std.is_finite()).then_some((lag, lag_std))
}

/// Rule 6: the first lightly damped pair (poles scaled by `w_ref`, rad/s) whose natural frequency
/// is above [`EDGE_MARGIN`] of the band's top `omega_high` (rad/s).
fn resonance_at_edge(poles: &[Complex64], w_ref: f64, omega_high: f64) -> Option<Rejection> {
    poles.iter().filter(|p| p.im > 0.0).find_map(|p| {
        let natural = p.norm() * w_ref;
        let damping = -p.re / p.norm();
        (damping < EDGE_DAMPING && natural > EDGE_MARGIN * omega_high).then(|| {
            Rejection::ResonanceAtBandEdge {
                natural_hz: natural / (2.0 * PI),
                damping,
                band_top_hz: omega_high / (2.0 * PI),
            }
        })
    })
}

/// `||N(j x_0) / d(j x_0) - K||_F / ||K||_F` at the band's lowest frequency (the bins are at
/// their centroids, not necessarily ascending).
fn static_in_band_difference(data: &Prepared, model: &Model) -> f64 {
    let Some(x) = data.x.iter().copied().reduce(f64::min) else {
        return f64::INFINITY;
    };
    let d = model.den_at(x);
    let (mut diff, mut norm) = (0.0, 0.0);
    for e in 0..ELEMENTS {
        let k = model.num[0][e];
        let at: Complex64 = Model::poly(model.num.iter().map(|c| c[e]), x, 0) / d;
        diff += (at - k).norm_sqr();
        norm += k * k;
    }
    (diff / norm.max(f64::MIN_POSITIVE)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pole pair of natural frequency `hz` and damping `zeta`, scaled by `w_ref` as fits are.
    fn pair(hz: f64, zeta: f64, w_ref: f64) -> Vec<Complex64> {
        let wn = 2.0 * PI * hz / w_ref;
        let p = Complex64::new(-zeta * wn, wn * (1.0 - zeta * zeta).sqrt());
        vec![p, p.conj()]
    }

    /// A model `N_0 (1 + a s) / d(s) e^(-tau s)` in the fits' normalised units (`s / w_ref`).
    fn with_numerator(n0: [f64; ELEMENTS], a_s: f64, w_ref: f64) -> Model {
        Model {
            num: vec![n0, n0.map(|v| v * a_s * w_ref)],
            den: vec![0.3, 0.02],
            tau: -0.006,
        }
    }

    /// The numerator's lag is `-a` for `N_0 (1 + a s)` whatever `N_0` mixes (here a permutation of
    /// the axes with scale factors, whose diagonal is zero): positive for a zero in the right half
    /// plane, negative for one in the left; none without a first-order coefficient or with a
    /// singular `N_0`.
    #[test]
    fn the_numerator_s_lag_is_the_zeros_low_frequency_lag() {
        let w_ref = 80.0;
        let mixed = [0.0, 1.01, 0.0, 0.0, 0.0, 0.98, 1.02, 0.0, 0.0];
        let std = vec![0.0; 2 * ELEMENTS + 3];
        for n0 in [[1.0, 0.01, 0.0, 0.0, 0.99, 0.02, 0.0, 0.0, 1.0], mixed] {
            for a_s in [-4.78e-3, 2.0e-3] {
                let (lag, lag_std) = numerator_lag(&with_numerator(n0, a_s, w_ref), &std, w_ref).unwrap();
                assert!((lag + a_s).abs() < 1e-15, "{lag} for {a_s}");
                assert!(lag_std.abs() < f64::MIN_POSITIVE, "{lag_std}");
            }
        }
        let first_order = Model {
            num: vec![mixed],
            den: vec![0.3],
            tau: -0.006,
        };
        assert!(numerator_lag(&first_order, &std, w_ref).is_none());
        assert!(numerator_lag(&with_numerator([0.0; ELEMENTS], -1e-3, w_ref), &std, w_ref).is_none());
    }

    /// The lag's deviation bound, propagated analytically, against central differences of the
    /// lag in each parameter (their contributions added in magnitude, as the bound takes them).
    #[test]
    fn the_numerator_s_lag_deviation_is_its_first_order_propagation() {
        let w_ref = 80.0;
        let mut rng = crate::rng::Rng::new(5);
        let mut model = with_numerator(
            [1.0, 0.01, -0.02, 0.005, 0.99, 0.02, 0.01, 0.0, 1.0],
            -3e-3,
            w_ref,
        );
        for v in &mut model.num[1] {
            *v += rng.uniform_in(-0.02, 0.02);
        }
        let std: Vec<f64> = (0..2 * ELEMENTS + 3)
            .map(|_| rng.uniform_in(1e-4, 1e-3))
            .collect();
        let (_, analytic) = numerator_lag(&model, &std, w_ref).unwrap();
        let mut bound = 0.0;
        for m in 0..2 {
            for e in 0..ELEMENTS {
                let h = 1e-6;
                let lag_at = |d: f64| {
                    let mut moved = model.clone();
                    moved.num[m][e] += d;
                    numerator_lag(&moved, &std, w_ref).unwrap().0
                };
                let slope = (lag_at(h) - lag_at(-h)) / (2.0 * h);
                bound += (slope * std[m * ELEMENTS + e]).abs();
            }
        }
        let numeric = bound;
        assert!(
            (analytic - numeric).abs() < 1e-6 * numeric,
            "{analytic:e} {numeric:e}"
        );
    }

    #[test]
    fn a_light_resonance_at_or_beyond_the_band_top_is_not_admissible() {
        let (w_ref, top) = (100.0, 2.0 * PI * 32.5);
        // As measured on a band-limited reference: 34 Hz, damping 0.007, band top 32.5 Hz.
        let Some(Rejection::ResonanceAtBandEdge {
            natural_hz,
            damping,
            band_top_hz,
        }) = resonance_at_edge(&pair(34.0, 0.007, w_ref), w_ref, top)
        else {
            panic!("admitted")
        };
        assert!((natural_hz - 34.0).abs() < 1e-9 && (damping - 0.007).abs() < 1e-12);
        assert!((band_top_hz - 32.5).abs() < 1e-12);
        // Just inside the edge (above 0.9 of the top) it is still the skirt.
        assert!(resonance_at_edge(&pair(30.0, 0.05, w_ref), w_ref, top).is_some());
        let shown = Rejection::ResonanceAtBandEdge {
            natural_hz,
            damping,
            band_top_hz,
        }
        .to_string();
        assert!(
            shown.contains("34.00 Hz") && shown.contains("top edge"),
            "{shown}"
        );
    }

    #[test]
    fn resonances_inside_the_band_and_damped_or_real_poles_are_admissible_by_rule_6() {
        let (w_ref, top) = (100.0, 2.0 * PI * 32.5);
        assert!(resonance_at_edge(&pair(20.0, 0.02, w_ref), w_ref, top).is_none());
        assert!(resonance_at_edge(&pair(34.0, 0.8, w_ref), w_ref, top).is_none());
        // A 4th-order Butterworth's lighter pair (0.38) at the edge: a sensor's filter, kept.
        assert!(resonance_at_edge(&pair(34.0, 0.38, w_ref), w_ref, top).is_none());
        // A light pair just below 0.9 of the top: its peak is in the data.
        assert!(resonance_at_edge(&pair(29.0, 0.02, w_ref), w_ref, top).is_none());
        let real = [Complex64::new(-2.0 * PI * 60.0 / w_ref, 0.0)];
        assert!(resonance_at_edge(&real, w_ref, top).is_none());
    }
}
