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
//!    (a sensor cannot answer before the stand moves);
//! 5. its static gain agrees with its in-band gain: at the band's lowest frequency the model,
//!    delay removed, is within [`STATIC_GAIN_AGREEMENT`] of `K` (relative Frobenius). Otherwise
//!    `K` is an extrapolation below the data.
//!
//! Order 0 is always admissible (it is the paper's model); its own plausibility (delay sign,
//! gain) is checked by the self-check of the identification, not here.
//!
//! Units: poles in rad/s, band in rad/s, delays in s. Every rule is reported by [`Rejection`].

use std::f64::consts::PI;
use std::fmt;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::model::{ELEMENTS, Model, Prepared};
use super::rational;

/// How far outside the band a pole may lie and still be resolved: `[f_low / r, r f_high]`.
pub const POLE_REACH: f64 = 4.0;

/// Largest relative Frobenius difference between the static gain and the model's gain at the
/// band's lowest frequency (delay removed).
pub const STATIC_GAIN_AGREEMENT: f64 = 0.05;

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
    /// The static gain is an extrapolation: it differs from the in-band gain.
    StaticGainDisagrees {
        /// Relative Frobenius difference at the band's lowest frequency.
        difference: f64,
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
            Rejection::StaticGainDisagrees { difference } => write!(
                f,
                "its static gain differs from its in-band gain by {:.1} % (an extrapolation)",
                difference * 100.0
            ),
        }
    }
}

/// The first rule `model` breaks, or `None` when it is admissible. The parameter standard
/// deviations ([`Model::parameter_std`]) are widened by `inflation` (`sqrt(max(1, chi2 / dof))`)
/// and computed only when the cheap rules pass.
pub(super) fn rejection(data: &Prepared, model: &Model, inflation: f64) -> Option<Rejection> {
    let order = model.order();
    if order == 0 {
        return None;
    }
    if !rational::is_stable(&model.den) {
        return Some(Rejection::Unstable);
    }
    let w_ref = data.omega_ref;
    let low = data.omega.first().copied().unwrap_or(w_ref) / POLE_REACH;
    let high = data.omega.last().copied().unwrap_or(w_ref) * POLE_REACH;
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

/// `||N(j x_0) / d(j x_0) - K||_F / ||K||_F` at the band's lowest bin.
fn static_in_band_difference(data: &Prepared, model: &Model) -> f64 {
    let Some(&x) = data.x.first() else {
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
