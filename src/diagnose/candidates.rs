//! The catalogue's effects as candidate extensions of the current model: each is added, the
//! extended model is fitted (its new parameters initialised by a coarse grid where the cost is
//! not smooth in them: the lag's time constant, a resonance's frequency and damping), and the
//! reduction of `chi2` it achieves is its evidence.

use std::f64::consts::PI;

use super::design::Design;
use super::fit::{Fitted, cheapest, fit};
use super::state::State;
use super::structure::{LagShape, Structure, lag_damping_held};
use super::tone::{TONE_PARAMETERS, Tone, strongest_line};
use crate::block::Block;
use crate::effect::Effect;

/// What a candidate adds to the model.
#[derive(Clone, Debug)]
pub enum Extension {
    /// A structural effect: the refitted model with it.
    Structural(Box<Fitted>),
    /// A tone, fitted on the residual.
    Tone(Tone),
    /// The outputs re-timed for a drifting block clock, and the model refitted on them.
    ClockCorrected {
        /// Clock rate error, s per s.
        drift: f64,
        /// Its standard deviation (`None`: the cost's curvature was not found positive).
        drift_std: Option<f64>,
        /// The design with the re-timed outputs.
        design: Box<Design>,
        /// The current structure refitted on it.
        fitted: Box<Fitted>,
    },
}

/// One candidate effect, fitted.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Which catalogue entry.
    pub effect: Effect,
    /// The extended model or the tone.
    pub extension: Extension,
    /// Reduction of `chi2` over the current model.
    pub delta_chi2: f64,
    /// Number of real parameters it adds.
    pub added_params: usize,
}

impl Candidate {
    /// The band limit's shape this candidate adds (`None` for any other effect).
    #[must_use]
    pub fn band_limit_shape(&self) -> Option<crate::model::band_limit::BandLimitShape> {
        match &self.extension {
            Extension::Structural(f) if self.effect == Effect::ReferenceBandLimit => f.structure.band_limit,
            _ => None,
        }
    }

    /// The lag's shape this candidate adds (`None` for any other effect).
    #[must_use]
    pub fn lag_shape(&self) -> Option<LagShape> {
        match &self.extension {
            Extension::Structural(f) if self.effect == Effect::SensorLag => f.structure.lag,
            _ => None,
        }
    }
}

/// The flag of [`Structure`] that turns an effect on.
type Switch = fn(&mut Structure) -> &mut bool;

pub(super) fn structural(effect: Effect, state: &State, fitted: Option<Fitted>) -> Option<Candidate> {
    let fitted = fitted?;
    let current = &state.fitted;
    Some(Candidate {
        effect,
        delta_chi2: current.chi2() - fitted.chi2(),
        added_params: fitted.n_params().saturating_sub(current.n_params()),
        extension: Extension::Structural(Box::new(fitted)),
    })
}

/// How many candidates a round tried, for its look-elsewhere cost: each one offered, and a band
/// limit's or a lag's shapes all where any is offered (a causal shape set aside by
/// `super::band_limit::without_needless_phase`, or a shape whose fit failed, was tried too;
/// before 30 Nov a failed shape was not counted; other effects' failed fits still are not).
#[must_use]
pub(super) fn tried(cands: &[Candidate]) -> usize {
    let offered = |effect: Effect, all: usize| {
        let shapes = cands.iter().filter(|c| c.effect == effect).count();
        (shapes, if shapes > 0 { all } else { 0 })
    };
    let (band_limits, all_band_limits) = offered(
        Effect::ReferenceBandLimit,
        crate::model::band_limit::BandLimitShape::SHAPES.len(),
    );
    let (lags, all_lags) = offered(Effect::SensorLag, LagShape::SHAPES.len());
    cands.len() - band_limits - lags + all_band_limits + all_lags
}

/// Every candidate for the block that the current model does not already hold.
#[must_use]
pub fn candidates(state: &State, band_hz: [f64; 2]) -> Vec<Candidate> {
    candidates_among(state, band_hz, &|_| true)
}

/// The candidates of the effects `wanted` accepts (the others are not fitted at all).
#[must_use]
pub fn candidates_among(state: &State, band_hz: [f64; 2], wanted: &dyn Fn(Effect) -> bool) -> Vec<Candidate> {
    let design = &state.design;
    let current = &state.fitted;
    let s0 = &current.structure;
    let run_fit = |structure: &Structure, theta: &super::structure::Theta| {
        fit(design, &state.grams, structure, theta, band_hz)
    };
    let mut out = Vec::new();
    // The effects that are a switch of the structure, fitted from the current parameters.
    let switches: [(Effect, bool, Switch); 4] = [
        (Effect::GSensitivity, design.block == Block::Gyro, |s| {
            &mut s.g_sensitivity
        }),
        (Effect::LeverArmError, design.block == Block::Accel, |s| {
            &mut s.lever_arm
        }),
        (Effect::ScaleNonlinearity, true, |s| &mut s.k2),
        (Effect::AxisTimeSkew, true, |s| &mut s.skew),
    ];
    for (effect, applies, switch) in switches {
        let mut s = s0.clone();
        if applies && wanted(effect) && !std::mem::replace(switch(&mut s), true) {
            out.extend(structural(effect, state, run_fit(&s, &current.theta)));
        }
    }
    if wanted(Effect::SensorLag) && s0.lag.is_none() {
        // Each shape a candidate of its own (as the band limit's are), the second order with
        // its extra parameter paid for by the criterion.
        let mut s = s0.clone();
        s.lag = Some(LagShape::FirstOrder);
        let best = LAG_STARTS_S
            .into_iter()
            .filter_map(|t| {
                let mut theta = current.theta.clone();
                theta.lag_s = t;
                theta.tau_s = lag_start_delay(theta.tau_s, t);
                run_fit(&s, &theta)
            })
            .min_by(|a, b| a.profile.cost.total_cmp(&b.profile.cost));
        out.extend(structural(Effect::SensorLag, state, best));
        s.lag = Some(LagShape::SecondOrder);
        // Held at a bound of its damping it is not a low-pass of this form: set aside. Nor is
        // one that takes more phase than the block's whole delay (a delay below 0 where the
        // delay-only model's is not): a sensor's filter sits behind its own delay, which is not
        // negative (the tapping recording with one channel moved 3 ms: a second-order lag of
        // 7.7 ms at damping 0.62 and a delay of -6.3 ms for the recording's 4.2 ms).
        let causal = |f: &Fitted| current.theta.tau_s < 0.0 || f.theta.tau_s >= 0.0;
        let second = second_order_start(state, &s)
            .and_then(|theta| run_fit(&s, &theta))
            .filter(|f| !lag_damping_held(f.theta.lag_damping) && causal(f));
        out.extend(structural(Effect::SensorLag, state, second));
    }
    if wanted(Effect::ReferenceBandLimit) && s0.band_limit.is_none() {
        out.extend(super::band_limit::band_limit_candidates(state, band_hz));
    }
    for axis in 0..3 {
        if !wanted(Effect::PlatformResonance) || s0.resonance_axes.contains(&axis) {
            continue;
        }
        let mut s = s0.clone();
        s.resonance_axes.push(axis);
        let start = resonance_start(state, &s, band_hz);
        out.extend(structural(
            Effect::PlatformResonance,
            state,
            start.and_then(|t| run_fit(&s, &t)),
        ));
    }
    if wanted(Effect::ClockDrift) {
        out.extend(super::clock::clock_candidate(state, band_hz));
    }
    // The strongest line in the fit's band or above it (up to 0.45 of the rate).
    let line = if wanted(Effect::VibrationTone) {
        let upper = state.upper.as_deref().and_then(|u| {
            strongest_line(u, &state.upper_residual, &u.outputs()).map(|t| Tone { upper: true, ..t })
        });
        strongest_line(design, &state.residual, &state.outputs)
            .into_iter()
            .chain(upper)
            .max_by(|a, b| a.delta_chi2.total_cmp(&b.delta_chi2))
    } else {
        None
    };
    if let Some(tone) = line {
        out.push(Candidate {
            effect: Effect::VibrationTone,
            delta_chi2: tone.delta_chi2,
            // Frequency, cosine and sine per channel, and the gate's parameters.
            added_params: TONE_PARAMETERS + tone.gate.as_ref().map_or(0, |g| g.parameters),
            extension: Extension::Tone(tone),
        });
    }
    out
}

/// The delay a candidate that adds `lag_s` of low-frequency phase lag starts from: the model's
/// `tau_s` without that lag, not below 0 (a sensor's own delay is not negative) where the
/// model's delay is not; where it is, the angles lag the outputs (a reference's latency beyond
/// the sensor's delay) and nothing bounds it. Clamped at 0 there too, a run whose angles lagged
/// by 50 ms (delay -47 ms) started every lag and resonance 47 ms off: their fits failed (chi2
/// gains of -3e7), a true gyro lag came second behind a false `g_sensitivity`, and a true mount
/// resonance was named on one seed of three (30 Nov, a helper's campaign;
/// `tests/diagnose_negative_delay.rs`).
fn lag_start_delay(tau_s: f64, lag_s: f64) -> f64 {
    if tau_s < 0.0 {
        tau_s - lag_s
    } else {
        (tau_s - lag_s).max(0.0)
    }
}

/// The lag's time constants each search starts from (corners from 318 to 11 Hz).
const LAG_STARTS_S: [f64; 4] = [0.5e-3, 2e-3, 6e-3, 15e-3];

/// The best point, by the cost without a search, of a grid over a second-order lag's time
/// constant ([`LAG_STARTS_S`] and the points between) and damping (from a resonant to an
/// overdamped section); its low-frequency phase lag `2 zeta T` taken out of the start's delay.
fn second_order_start(state: &State, structure: &Structure) -> Option<super::structure::Theta> {
    let grid = [0.5e-3, 1e-3, 2e-3, 4e-3, 6e-3, 10e-3, 15e-3]
        .into_iter()
        .flat_map(|t| [0.6, 0.8, 1.1, 1.8].map(|zeta| (t, zeta)))
        .map(|(t, zeta)| {
            let mut theta = state.fitted.theta.clone();
            theta.lag_s = t;
            theta.lag_damping = zeta;
            theta.tau_s = lag_start_delay(theta.tau_s, 2.0 * zeta * t);
            theta
        });
    cheapest(&state.design, &state.grams, structure, grid)
}

/// The best point of a grid over a new resonance's frequency (log-spaced inside the band, from
/// 1 Hz) and damping.
fn resonance_start(
    state: &State,
    structure: &Structure,
    band_hz: [f64; 2],
) -> Option<super::structure::Theta> {
    let (lo, hi) = (band_hz[0].max(1.0), band_hz[1] * 0.98);
    if hi <= lo {
        return None;
    }
    let n: u32 = 48;
    let grid = (0..n)
        .map(|m| lo * (hi / lo).powf(f64::from(m) / f64::from(n - 1)))
        .flat_map(|f| [0.03, 0.1, 0.3, 0.7].map(|zeta| (f, zeta)))
        .map(|(f, zeta)| {
            let mut theta = state.fitted.theta.clone();
            theta.resonances.push((f, zeta));
            // A resonance adds phase lag 2 zeta f / f_r below f_r: start tau without it.
            theta.tau_s = lag_start_delay(theta.tau_s, zeta / (PI * f));
            theta
        });
    cheapest(&state.design, &state.grams, structure, grid)
}
