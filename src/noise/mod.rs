//! Noise terms of a block (IEEE 952 for gyros, IEEE 1293 for accelerometers) from its
//! disturbance: the residual of the identified model ([`residual`]), not the raw outputs, so that
//! the stand's motion does not pollute them.
//!
//! Per output channel: the overlapping Allan deviation at two averaging times per octave from
//! one sample to a quarter of the record, with one-sigma (68.3 %) chi-square intervals
//! ([`allan`]), and the five power-law terms fitted to it ([`terms`]). Per block: the correlation
//! matrix of the channels' residuals (zero lag).
//!
//! Units: SI of the block's outputs inside (`rad/s`, `m/s^2`, times powers of s); each term also
//! carries its IEEE display unit (`deg/sqrt(h)`, `deg/h`, `m/s/sqrt(h)`, `ug`, ...). Contract: a
//! record shorter than [`MIN_SAMPLES`] after the start transient, or a residual with a
//! non-finite sample, gives `None` (no noise figures), never a panic.

pub mod allan;
pub mod chi2;
pub mod of_model;
pub mod reference;
pub mod residual;
pub mod share;
pub mod terms;

use serde::{Deserialize, Serialize};

use crate::block::Block;
use allan::{AllanPoint, averaging_factors};
use rayon::prelude::*;
use reference::ReferencePsd;
use terms::{AvarPoint, NoiseTerm, PowerLawFit, fit_terms};

/// Fewest residual samples for noise figures.
pub const MIN_SAMPLES: usize = 64;

/// Averaging times per octave of the Allan curves.
pub const TAUS_PER_OCTAVE: u32 = 2;

/// One term of one channel, SI and display units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TermEstimate {
    /// Which term.
    pub term: NoiseTerm,
    /// Its id on the block (`angle_random_walk`, `velocity_random_walk`, ...).
    pub id: String,
    /// Value in the display unit.
    pub value: f64,
    /// One-sigma interval in the display unit.
    pub interval: [f64; 2],
    /// The display unit.
    pub unit: String,
    /// Value in SI units of the block's output.
    pub value_si: f64,
    /// The averaging time where the term has its largest share of the variance, s.
    pub tau_s: f64,
    /// That share (0..1); below one half the term is barely visible in this record.
    pub share: f64,
}

/// One channel's noise figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelNoise {
    /// Output channel name (`gx`, `ax`, ...).
    pub channel: String,
    /// Standard deviation of the residual, output units.
    pub residual_std: f64,
    /// The overlapping Allan deviation curve of the residual, as measured.
    pub allan: Vec<AllanPoint>,
    /// At each point of `allan`: the Allan deviation the reference's angle error contributes
    /// ([`reference`]), subtracted in variance before the fit; points where it is more than half
    /// of the variance are left out of the fit.
    #[serde(default)]
    pub reference_adev: Vec<f64>,
    /// Fitted Allan-variance coefficients of `tau^-2 .. tau^2` and of the correlated noise
    /// (SI; `terms::NoiseTerm::shape`).
    pub coefficients: [f64; 6],
    /// Correlation time of the correlated noise, s (0 when absent).
    #[serde(default)]
    pub correlation_time_s: f64,
    /// The terms present (non-zero in the fit).
    pub terms: Vec<TermEstimate>,
}

impl ChannelNoise {
    /// The estimate of `term`, if the fit found it.
    #[must_use]
    pub fn term(&self, term: NoiseTerm) -> Option<&TermEstimate> {
        self.terms.iter().find(|t| t.term == term)
    }

    /// The fitted Allan deviation at `tau_s`.
    #[must_use]
    pub fn fitted_adev(&self, tau_s: f64) -> f64 {
        PowerLawFit {
            coefficients: self.coefficients,
            correlation_time_s: self.correlation_time_s,
            terms: Vec::new(),
        }
        .avar(tau_s)
        .sqrt()
    }
}

/// Why a block's noise figures are not simply the sensor's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum NoiseWarning {
    /// The identified model does not explain the data: the residual holds a misfit besides the
    /// sensor's noise, so the terms are upper bounds.
    ModelMisfit {
        /// chi2 per degree of freedom of the model.
        chi2_per_dof: f64,
    },
    /// Up to this averaging time the reference's angle noise dominates the residual in some
    /// channel: those points are left out, and terms seen only there are not measured.
    ReferenceDominated {
        /// The longest averaging time left out, s.
        up_to_tau_s: f64,
    },
}

impl std::fmt::Display for NoiseWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoiseWarning::ModelMisfit { chi2_per_dof } => write!(
                f,
                "the model does not explain the data (chi2/dof {chi2_per_dof:.2}): the residual holds \
                 more than the sensor's noise, so these noise terms are upper bounds"
            ),
            NoiseWarning::ReferenceDominated { up_to_tau_s } => write!(
                f,
                "up to tau = {up_to_tau_s:.3} s the stand's angle noise (through the observer) dominates \
                 the residual: those averaging times are left out of the fit"
            ),
        }
    }
}

/// A block's noise figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockNoise {
    /// Residual samples used (after the start transient), and their rate, Hz.
    pub samples: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// One entry per output channel.
    pub channels: [ChannelNoise; 3],
    /// Correlation coefficients of the channels' residuals.
    pub correlation: [[f64; 3]; 3],
    /// Why the figures are not simply the sensor's (empty when nothing is in the way).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<NoiseWarning>,
}

/// Noise figures of `block` from its `residual` channels (see [`residual::residual`]) named
/// `names`, sampled at `sample_rate_hz`, with the reference's share per channel taken out
/// where it is known.
#[must_use]
pub fn block_noise(
    block: Block,
    names: [&str; 3],
    residual: &[Vec<f64>; 3],
    sample_rate_hz: f64,
    reference: Option<&[ReferencePsd; 3]>,
) -> Option<BlockNoise> {
    let len = residual.iter().map(Vec::len).min().unwrap_or(0);
    if len < MIN_SAMPLES
        || !residual.iter().flatten().all(|v| v.is_finite())
        || sample_rate_hz.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return None;
    }
    let ms = averaging_factors(len, TAUS_PER_OCTAVE);
    // The channels in parallel (each is a pass over the record per averaging time, and a fit).
    let mut channels: Vec<ChannelNoise> = (0..3)
        .into_par_iter()
        .map(|i| {
            let reference = reference.map(|r| &r[i]);
            channel_noise(
                block,
                names[i],
                &residual[i][..len],
                sample_rate_hz,
                &ms,
                reference,
            )
        })
        .collect();
    let channels: [ChannelNoise; 3] = std::array::from_fn(|_| channels.remove(0));
    let excluded = channels
        .iter()
        .flat_map(|c: &ChannelNoise| {
            c.allan
                .iter()
                .zip(&c.reference_adev)
                .filter(|(p, r)| r.powi(2) > MAX_REFERENCE_SHARE * p.adev.powi(2))
                .map(|(p, _)| p.tau_s)
        })
        .fold(0.0, f64::max);
    let warnings = if excluded > 0.0 {
        vec![NoiseWarning::ReferenceDominated {
            up_to_tau_s: excluded,
        }]
    } else {
        Vec::new()
    };
    Some(BlockNoise {
        samples: len,
        sample_rate_hz,
        channels,
        correlation: correlation(residual, len),
        warnings,
    })
}

/// Share of a point's variance above which the reference's part leaves it out of the fit.
const MAX_REFERENCE_SHARE: f64 = 0.5;

/// Relative uncertainty of the reference's predicted part: where the reference dominates (the
/// points left out of the fit), the median of `|measured - reference - fitted sensor| /
/// reference`, at least 10 % (the first-order model's own approximations) and at most 100 %.
fn reference_error(measured: &[AvarPoint], fit: &PowerLawFit) -> f64 {
    let mut ratios: Vec<f64> = measured
        .iter()
        .filter(|p| p.reference > MAX_REFERENCE_SHARE * p.avar)
        .map(|p| (p.avar - p.reference - fit.avar(p.tau_s)).abs() / p.reference)
        .collect();
    if ratios.is_empty() {
        return if measured.iter().any(|p| p.reference > 0.0) {
            0.1
        } else {
            0.0
        };
    }
    ratios.sort_by(f64::total_cmp);
    ratios[ratios.len() / 2].clamp(0.1, 1.0)
}

fn channel_noise(
    block: Block,
    name: &str,
    r: &[f64],
    fs: f64,
    ms: &[usize],
    reference: Option<&ReferencePsd>,
) -> ChannelNoise {
    let tau0 = 1.0 / fs;
    let n_phase = r.len() + 1;
    // The fit needs the variances first; the intervals then use its dominant term per point.
    let x = allan::phase(r, fs);
    let measured: Vec<AvarPoint> = ms
        .iter()
        .filter_map(|&m| {
            let tau_s = m as f64 * tau0;
            let avar = allan::overlapping_avar(&x, m, tau0)?;
            let reference = reference.map_or(0.0, |p| p.avar(tau_s));
            Some(AvarPoint {
                m,
                tau_s,
                avar,
                reference,
            })
        })
        .collect();
    let sensor: Vec<AvarPoint> = measured
        .iter()
        .filter(|p| p.reference <= MAX_REFERENCE_SHARE * p.avar)
        .map(|p| AvarPoint {
            avar: p.avar - p.reference,
            ..*p
        })
        .collect();
    let mut fit = fit_terms(&sensor, n_phase, 0.0);
    let error = reference_error(&measured, &fit);
    fit.set_intervals(&sensor, n_phase, error);
    // The curve from the variances already measured (one pass over the record per factor).
    let allan: Vec<AllanPoint> = measured
        .iter()
        .map(|p| allan::point(p.avar, p.m, tau0, n_phase, fit.law_at(p.tau_s)))
        .collect();
    let terms = fit
        .terms
        .iter()
        .map(|t| {
            let (unit, scale) = t.term.unit_on(block);
            TermEstimate {
                term: t.term,
                id: t.term.id_on(block).to_owned(),
                value: t.value * scale,
                interval: [t.lo * scale, t.hi * scale],
                unit: unit.to_owned(),
                value_si: t.value,
                tau_s: t.tau_s,
                share: t.share,
            }
        })
        .collect();
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let residual_std = (r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt();
    ChannelNoise {
        channel: name.to_owned(),
        residual_std,
        allan,
        reference_adev: measured.iter().map(|p| p.reference.sqrt()).collect(),
        coefficients: fit.coefficients,
        correlation_time_s: fit.correlation_time_s,
        terms,
    }
}

fn correlation(r: &[Vec<f64>; 3], len: usize) -> [[f64; 3]; 3] {
    let means: [f64; 3] = std::array::from_fn(|i| r[i][..len].iter().sum::<f64>() / len as f64);
    let cov = |i: usize, j: usize| {
        r[i][..len]
            .iter()
            .zip(&r[j][..len])
            .map(|(a, b)| (a - means[i]) * (b - means[j]))
            .sum::<f64>()
    };
    let var: [f64; 3] = std::array::from_fn(|i| cov(i, i));
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let d = (var[i] * var[j]).sqrt();
            if d > 0.0 {
                cov(i, j) / d
            } else {
                f64::from(u8::from(i == j))
            }
        })
    })
}
