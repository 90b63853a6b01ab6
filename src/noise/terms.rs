//! Noise terms from an Allan variance curve (IEEE 952-1997 Annex C for gyros, IEEE 1293-2018
//! for accelerometers): the independent power-law processes add in the Allan variance,
//!
//! `sigma^2(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2`,
//!
//! with `Q` quantisation, `N` angle (velocity) random walk, `B` bias instability, `K` rate
//! (acceleration) random walk and `R` rate ramp, all in SI units of the block's output (rad/s or
//! m/s^2 times the power of s that each term needs). The five non-negative coefficients are
//! fitted by weighted least squares on the variance (weights `edf / (2 sigma^4)` from the model
//! itself, refined over a few passes), exactly under the non-negativity constraint (every support
//! tried, 31 small problems).
//!
//! Each term's interval is the chi-square interval of the single Allan variance where that term
//! has its largest share, with all of that point's uncertainty put on the term: wider than the
//! least-squares covariance, which ignores the strong correlation of neighbouring overlapping
//! estimates. Where a reference part was subtracted from the point, its relative uncertainty
//! (measured by the caller where the reference dominates) widens the interval further.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::allan::{ONE_SIGMA, PowerLaw, edf};
use super::chi2::chi2_quantile;
use crate::block::Block;

/// One power-law noise term.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseTerm {
    /// Quantisation `Q` (`sigma^2 = 3 Q^2 / tau^2`).
    Quantisation,
    /// Angle random walk (gyro) or velocity random walk (accelerometer) `N` (`N^2 / tau`).
    RandomWalk,
    /// Bias instability `B` (flat at `0.664 B`).
    BiasInstability,
    /// Rate random walk (gyro) or acceleration random walk (accelerometer) `K` (`K^2 tau / 3`).
    RateRandomWalk,
    /// Rate ramp `R` (`R^2 tau^2 / 2`).
    RateRamp,
    /// Exponentially correlated (first-order Markov) noise of standard deviation `sigma_c` and
    /// correlation time `T_c` (IEEE 952 C.1.6): `sigma^2 = sigma_c^2 g(tau / T_c)`, with
    /// `g = (2 T_c / tau) (1 - (T_c / 2 tau) (3 - 4 e^(-tau/T_c) + e^(-2 tau/T_c)))`: a rate
    /// random walk well below `T_c`, a white rate well above it.
    Correlated,
}

/// Gravity used to express accelerometer biases in micro-g, m/s^2.
const STANDARD_G: f64 = 9.806_65;

impl NoiseTerm {
    /// The six terms: the five power laws in the order of their `tau` exponents `-2..=2`, then
    /// the correlated noise.
    pub const ALL: [NoiseTerm; 6] = [
        NoiseTerm::Quantisation,
        NoiseTerm::RandomWalk,
        NoiseTerm::BiasInstability,
        NoiseTerm::RateRandomWalk,
        NoiseTerm::RateRamp,
        NoiseTerm::Correlated,
    ];

    /// The term's Allan variance per unit coefficient at `tau_s`: `tau^k` for the power laws,
    /// `g(tau / T_c)` for the correlated noise (0 when `correlation_time_s` is not positive).
    #[must_use]
    pub fn shape(self, tau_s: f64, correlation_time_s: f64) -> f64 {
        match self {
            NoiseTerm::Quantisation => tau_s.powi(-2),
            NoiseTerm::RandomWalk => 1.0 / tau_s,
            NoiseTerm::BiasInstability => 1.0,
            NoiseTerm::RateRandomWalk => tau_s,
            NoiseTerm::RateRamp => tau_s * tau_s,
            NoiseTerm::Correlated if correlation_time_s > 0.0 => {
                let x = tau_s / correlation_time_s;
                // 1 - (3 - 4 e^-x + e^-2x) / 2x, by its series where it cancels.
                let bracket = if x < 1e-3 {
                    x * x / 3.0 - x.powi(3) / 4.0 + 7.0 * x.powi(4) / 60.0
                } else {
                    1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x)
                };
                2.0 / x * bracket
            }
            NoiseTerm::Correlated => 0.0,
        }
    }

    /// `value^2 / coefficient`: the term's value is `sqrt(coefficient * this)`.
    fn coefficient_scale(self) -> f64 {
        match self {
            NoiseTerm::Quantisation => 1.0 / 3.0,
            NoiseTerm::RandomWalk | NoiseTerm::Correlated => 1.0,
            NoiseTerm::BiasInstability => std::f64::consts::PI / (2.0 * std::f64::consts::LN_2),
            NoiseTerm::RateRandomWalk => 3.0,
            NoiseTerm::RateRamp => 2.0,
        }
    }

    /// The term's SI value from its Allan-variance coefficient (negative coefficients: 0).
    #[must_use]
    pub fn value_of(self, coefficient: f64) -> f64 {
        (coefficient.max(0.0) * self.coefficient_scale()).sqrt()
    }

    /// The noise type whose degrees of freedom apply where this term dominates at `tau_s`.
    /// Rate ramp is deterministic; its points are counted as random-walk ones. Correlated noise
    /// is a random walk below its correlation time and white above.
    #[must_use]
    pub fn law(self, tau_s: f64, correlation_time_s: f64) -> PowerLaw {
        match self {
            NoiseTerm::Quantisation => PowerLaw::WhitePhase,
            NoiseTerm::Correlated if tau_s < correlation_time_s => PowerLaw::RandomWalkRate,
            NoiseTerm::RandomWalk | NoiseTerm::Correlated => PowerLaw::WhiteRate,
            NoiseTerm::BiasInstability => PowerLaw::FlickerRate,
            NoiseTerm::RateRandomWalk | NoiseTerm::RateRamp => PowerLaw::RandomWalkRate,
        }
    }

    /// The term's id on `block` (the key of specification limits, e.g. `angle_random_walk`).
    #[must_use]
    pub fn id_on(self, block: Block) -> &'static str {
        match (self, block) {
            (NoiseTerm::Quantisation, _) => "quantisation",
            (NoiseTerm::RandomWalk, Block::Gyro) => "angle_random_walk",
            (NoiseTerm::RandomWalk, Block::Accel) => "velocity_random_walk",
            (NoiseTerm::BiasInstability, _) => "bias_instability",
            (NoiseTerm::RateRandomWalk, Block::Gyro) => "rate_random_walk",
            (NoiseTerm::RateRandomWalk, Block::Accel) => "acceleration_random_walk",
            (NoiseTerm::RateRamp, Block::Gyro) => "rate_ramp",
            (NoiseTerm::RateRamp, Block::Accel) => "acceleration_ramp",
            (NoiseTerm::Correlated, _) => "correlated_noise",
        }
    }

    /// The term's name on `block`, in words.
    #[must_use]
    pub fn name_on(self, block: Block) -> String {
        self.id_on(block).replace('_', " ")
    }

    /// The display unit on `block` (IEEE 952 / 1293 usage) and the factor from SI to it.
    #[must_use]
    pub fn unit_on(self, block: Block) -> (&'static str, f64) {
        let deg = 180.0 / std::f64::consts::PI;
        match (self, block) {
            (NoiseTerm::Quantisation, Block::Gyro) => ("urad", 1e6),
            (NoiseTerm::RandomWalk, Block::Gyro) => ("deg/sqrt(h)", deg * 60.0),
            (NoiseTerm::BiasInstability | NoiseTerm::Correlated, Block::Gyro) => ("deg/h", deg * 3600.0),
            (NoiseTerm::RateRandomWalk, Block::Gyro) => ("deg/h/sqrt(h)", deg * 3600.0 * 60.0),
            (NoiseTerm::RateRamp, Block::Gyro) => ("deg/h/h", deg * 3600.0 * 3600.0),
            (NoiseTerm::Quantisation, Block::Accel) => ("mm/s", 1e3),
            (NoiseTerm::RandomWalk, Block::Accel) => ("m/s/sqrt(h)", 60.0),
            (NoiseTerm::BiasInstability | NoiseTerm::Correlated, Block::Accel) => ("ug", 1e6 / STANDARD_G),
            (NoiseTerm::RateRandomWalk, Block::Accel) => ("ug/sqrt(h)", 1e6 / STANDARD_G * 60.0),
            (NoiseTerm::RateRamp, Block::Accel) => ("ug/h", 1e6 / STANDARD_G * 3600.0),
        }
    }
}

/// One fitted term with its one-sigma interval, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TermFit {
    /// Which term.
    pub term: NoiseTerm,
    /// Its value, SI.
    pub value: f64,
    /// Lower end of its one-sigma interval, SI.
    pub lo: f64,
    /// Upper end of its one-sigma interval, SI.
    pub hi: f64,
    /// The averaging time where it has its largest share of the variance, s.
    pub tau_s: f64,
    /// That share (0..1): a term that never reaches half is barely visible in this record.
    pub share: f64,
}

/// The Allan variance at averaging factor `m` (`tau = m tau0`), as measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvarPoint {
    /// Averaging factor.
    pub m: usize,
    /// Averaging time, s.
    pub tau_s: f64,
    /// Overlapping Allan variance of the sensor (the reference's part subtracted).
    pub avar: f64,
    /// The reference's part that was subtracted (0 where none is known).
    pub reference: f64,
}

/// The fitted coefficients of `sigma^2(tau) = sum_k c_k shape_k(tau)` and the terms present.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PowerLawFit {
    /// Coefficients `c_k` in the order of [`NoiseTerm::ALL`] (0 for an absent term).
    pub coefficients: [f64; 6],
    /// Correlation time of the correlated noise, s (0 when absent).
    pub correlation_time_s: f64,
    /// The present terms (non-zero coefficient), with intervals.
    pub terms: Vec<TermFit>,
}

impl PowerLawFit {
    /// The fitted Allan variance at `tau_s`.
    #[must_use]
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.coefficients
            .iter()
            .zip(NoiseTerm::ALL)
            .map(|(c, t)| c * t.shape(tau_s, self.correlation_time_s))
            .sum()
    }

    /// The term dominating the fitted variance at `tau_s` (white rate when nothing is fitted).
    #[must_use]
    pub fn dominant(&self, tau_s: f64) -> NoiseTerm {
        let mut best = (NoiseTerm::RandomWalk, 0.0);
        for (c, t) in self.coefficients.iter().zip(NoiseTerm::ALL) {
            let part = c * t.shape(tau_s, self.correlation_time_s);
            if part > best.1 {
                best = (t, part);
            }
        }
        best.0
    }

    /// The noise type of the dominant term at `tau_s` (for the degrees of freedom).
    #[must_use]
    pub fn law_at(&self, tau_s: f64) -> PowerLaw {
        self.dominant(tau_s).law(tau_s, self.correlation_time_s)
    }
}

/// Correlation times tried for the correlated noise, per decade.
const CORRELATION_TIMES_PER_DECADE: f64 = 4.0;

/// What the correlated noise must buy in weighted cost to be kept (two more parameters; the
/// neighbouring overlapping estimates are correlated, so the cost is not a plain chi-square).
const CORRELATED_PENALTY: f64 = 25.0;

/// Fits the terms to `points` (from a record of `n_phase` phase points): the five power laws,
/// and the correlated noise where it lowers the weighted cost by more than its penalty (its
/// correlation time searched on a grid from the third point's averaging time to a third of the
/// longest). Points with a non-finite or non-positive variance are ignored; fewer than two
/// usable points give no terms. `reference_error` is the relative uncertainty of the subtracted
/// reference parts, added to each term's interval.
#[must_use]
pub fn fit_terms(points: &[AvarPoint], n_phase: usize, reference_error: f64) -> PowerLawFit {
    let usable = usable(points);
    if usable.len() < 2 {
        return PowerLawFit::default();
    }
    let mut fit = iterate(&usable, n_phase, 0.0);
    if usable.len() >= 8 {
        // Correlation times compared on the power-law fit's weights.
        let weights = model_weights(&fit, &usable, n_phase);
        let cost = |f: &PowerLawFit| weighted_cost(f, &usable, &weights);
        let base = cost(&fit);
        let (lo, hi) = (usable[2].tau_s, usable[usable.len() - 1].tau_s / 3.0);
        let mut best: Option<(f64, f64)> = None;
        let mut tc = lo;
        while tc <= hi {
            let trial = PowerLawFit {
                coefficients: nonnegative_least_squares(&usable, &weights, tc),
                correlation_time_s: tc,
                terms: Vec::new(),
            };
            let c = cost(&trial);
            if best.is_none_or(|(b, _)| c < b) {
                best = Some((c, tc));
            }
            tc *= 10f64.powf(1.0 / CORRELATION_TIMES_PER_DECADE);
        }
        if let Some((c, tc)) = best
            && c < base - CORRELATED_PENALTY
        {
            let with = iterate(&usable, n_phase, tc);
            if with.coefficients[5] > 0.0 {
                fit = with;
            }
        }
    }
    // A term that nowhere reaches a millionth of the variance is rounding, not noise.
    for (k, term) in NoiseTerm::ALL.iter().enumerate() {
        let c = fit.coefficients[k];
        let visible = usable
            .iter()
            .any(|p| c * term.shape(p.tau_s, fit.correlation_time_s) > 1e-6 * fit.avar(p.tau_s));
        if !visible {
            fit.coefficients[k] = 0.0;
        }
    }
    if fit.coefficients[5] == 0.0 {
        fit.correlation_time_s = 0.0;
    }
    fit.set_intervals(points, n_phase, reference_error);
    fit
}

/// The points a fit uses: finite, positive variance at a positive averaging time.
fn usable(points: &[AvarPoint]) -> Vec<AvarPoint> {
    points
        .iter()
        .copied()
        .filter(|p| p.avar.is_finite() && p.avar > 0.0 && p.tau_s > 0.0)
        .collect()
}

impl PowerLawFit {
    /// The present terms with their intervals (see the module docs) for the fitted coefficients
    /// on `points`, with `reference_error` the relative uncertainty of the subtracted reference
    /// parts: the fit itself does not depend on it, so a caller that learns it from a first fit
    /// sets the intervals again instead of fitting twice.
    pub fn set_intervals(&mut self, points: &[AvarPoint], n_phase: usize, reference_error: f64) {
        let usable = usable(points);
        if usable.is_empty() {
            self.terms.clear();
            return;
        }
        self.terms = NoiseTerm::ALL
            .iter()
            .zip(self.coefficients)
            .filter(|(_, c)| *c > 0.0)
            .map(|(&term, c)| term_interval(self, &usable, n_phase, term, c, reference_error))
            .collect();
    }
}

/// Reweighted fits (weights `edf / (2 sigma^4)` from the model itself) at a fixed correlation
/// time (`0`: power laws only).
fn iterate(usable: &[AvarPoint], n_phase: usize, correlation_time_s: f64) -> PowerLawFit {
    // First pass: every point white-rate, its own variance as the model.
    let mut weights: Vec<f64> = usable
        .iter()
        .map(|p| edf(n_phase, p.m, PowerLaw::WhiteRate) / (2.0 * p.avar * p.avar))
        .collect();
    let mut fit = PowerLawFit {
        correlation_time_s,
        ..PowerLawFit::default()
    };
    for _ in 0..5 {
        fit.coefficients = nonnegative_least_squares(usable, &weights, correlation_time_s);
        weights = model_weights(&fit, usable, n_phase);
    }
    fit
}

fn model_weights(fit: &PowerLawFit, usable: &[AvarPoint], n_phase: usize) -> Vec<f64> {
    usable
        .iter()
        .map(|p| {
            let model = fit.avar(p.tau_s).max(1e-300);
            edf(n_phase, p.m, fit.law_at(p.tau_s)) / (2.0 * model * model)
        })
        .collect()
}

fn weighted_cost(fit: &PowerLawFit, usable: &[AvarPoint], weights: &[f64]) -> f64 {
    usable
        .iter()
        .zip(weights)
        .map(|(p, w)| w * (p.avar - fit.avar(p.tau_s)).powi(2))
        .sum()
}

/// The term's value and its interval from the point where its share is largest.
fn term_interval(
    fit: &PowerLawFit,
    points: &[AvarPoint],
    n_phase: usize,
    term: NoiseTerm,
    c: f64,
    reference_error: f64,
) -> TermFit {
    let tc = fit.correlation_time_s;
    let share = |p: &AvarPoint| c * term.shape(p.tau_s, tc) / fit.avar(p.tau_s).max(1e-300);
    let best = points
        .iter()
        .max_by(|a, b| share(a).total_cmp(&share(b)))
        .copied()
        .unwrap_or(points[0]);
    let model = fit.avar(best.tau_s);
    let dof = edf(n_phase, best.m, fit.law_at(best.tau_s));
    let tail = 0.5 * (1.0 - ONE_SIGMA);
    let (low_factor, high_factor) = (
        dof / chi2_quantile(1.0 - tail, dof),
        dof / chi2_quantile(tail, dof),
    );
    let per_unit = term.shape(best.tau_s, tc);
    // The chi-square interval is the measured variance's (sensor and reference); the
    // reference's own uncertainty comes on top.
    let measured = model + best.reference;
    let reference = reference_error * best.reference;
    let c_lo = c + (measured * (low_factor - 1.0) - reference) / per_unit;
    let c_hi = c + (measured * (high_factor - 1.0) + reference) / per_unit;
    TermFit {
        term,
        value: term.value_of(c),
        lo: term.value_of(c_lo),
        hi: term.value_of(c_hi),
        tau_s: best.tau_s,
        share: share(&best),
    }
}

/// Weighted least squares of the variance on the terms' shapes under `c >= 0` (the correlated
/// noise only when `correlation_time_s > 0`): every support is solved unconstrained and the
/// cheapest feasible one kept (exact for so few unknowns).
fn nonnegative_least_squares(points: &[AvarPoint], weights: &[f64], correlation_time_s: f64) -> [f64; 6] {
    let rows = points.len();
    let terms = if correlation_time_s > 0.0 { 6 } else { 5 };
    // Columns scaled to unit norm: tau^-2 .. tau^2 span many decades.
    let mut a = DMatrix::<f64>::zeros(rows, terms);
    let mut b = DVector::<f64>::zeros(rows);
    for (i, (p, w)) in points.iter().zip(weights).enumerate() {
        let sw = w.sqrt();
        for (k, t) in NoiseTerm::ALL.iter().take(terms).enumerate() {
            a[(i, k)] = sw * t.shape(p.tau_s, correlation_time_s);
        }
        b[i] = sw * p.avar;
    }
    let norms: Vec<f64> = (0..terms).map(|k| a.column(k).norm().max(1e-300)).collect();
    for (k, n) in norms.iter().enumerate() {
        a.column_mut(k).scale_mut(1.0 / n);
    }
    let mut best: Option<(f64, [f64; 6])> = None;
    for support in 1_u32..(1 << terms) {
        let cols: Vec<usize> = (0..terms).filter(|k| support & (1 << k) != 0).collect();
        if cols.len() > rows {
            continue;
        }
        let sub = DMatrix::from_fn(rows, cols.len(), |i, j| a[(i, cols[j])]);
        let Ok(x) = sub.clone().svd(true, true).solve(&b, 1e-12) else {
            continue;
        };
        if x.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            continue;
        }
        let cost = (&sub * &x - &b).norm_squared();
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            let mut coefficients = [0.0; 6];
            for (j, &k) in cols.iter().enumerate() {
                coefficients[k] = x[j] / norms[k];
            }
            best = Some((cost, coefficients));
        }
    }
    best.map_or([0.0; 6], |(_, c)| c)
}

#[cfg(test)]
#[path = "terms_tests.rs"]
mod tests;
