//! Checking settings against a run: the error that names the broken rule, the shrink limit on
//! `lambda` ([`MAX_SHRINK`]) and the rules themselves ([`Settings::validate`]).

use nalgebra::Matrix3;

use super::{
    AUTO_MIN_SEGMENT_LEN, LambdaSetting, MAX_ORDER, MIN_EQUIVALENT_AVERAGES, OrderSetting, Settings,
    enough_to_identify, equivalent_averages_of,
};
use crate::block::Block;
use crate::ident::band::BandSetting;
use crate::spectral::{MIN_SEGMENT_LEN, WelchSettings};

/// Largest eigenvalue of `A^-1 Lambda` allowed: the regularised estimate `(I - A^-1 Lambda) W`
/// is shrunk by at most half. With `A` symmetric positive definite and `Lambda >= 0` diagonal,
/// the eigenvalues of `A^-1 Lambda` are real and non-negative (it is similar to
/// `A^-1/2 Lambda A^-1/2`); a negative `lambda` would amplify the estimate, which the constraint
/// (that corrects an estimate's leakage) never justifies.
pub const MAX_SHRINK: f64 = 0.5;

/// Largest eigenvalue of `A^-1 Lambda` (`+inf` when `A` is singular).
#[must_use]
pub fn max_shrink(a: &Matrix3<f64>, lambda: &[f64; 3]) -> f64 {
    let Some(c) = (*a).cholesky() else {
        return f64::INFINITY;
    };
    let l_inv = c.l().try_inverse().unwrap_or_else(Matrix3::zeros);
    let m = l_inv * Matrix3::from_diagonal(&(*lambda).into()) * l_inv.transpose();
    m.symmetric_eigen().eigenvalues.max()
}

/// Why settings were refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// `span_s` is not an ordered stretch inside the record.
    #[error("span_s [{from}, {to}] s is not an ordered stretch inside the record ({start} to {end} s)")]
    Span {
        /// Requested start, s.
        from: f64,
        /// Requested end, s.
        to: f64,
        /// The record's first time, s.
        start: f64,
        /// Its last time, s.
        end: f64,
    },
    /// The settings file is not valid JSON or has a wrong field.
    #[error("{file}:{line}:{column}: {detail}")]
    Parse {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        detail: String,
    },
    /// The band is empty, non-finite or outside `(0, Nyquist]`.
    #[error("band_hz [{low}, {high}] is not inside (0, {nyquist}] Hz with low < high")]
    Band {
        /// Low edge.
        low: f64,
        /// High edge.
        high: f64,
        /// The run's Nyquist frequency.
        nyquist: f64,
    },
    /// A is not symmetric positive definite.
    #[error("weight_A is not symmetric positive definite: {reason}")]
    WeightNotSpd {
        /// Which property fails.
        reason: String,
    },
    /// `I - A^-1 Lambda` is singular (or a lambda is not finite).
    #[error("lambda {lambda:?} makes I - A^-1 Lambda singular (determinant {determinant:.3e})")]
    SingularLambda {
        /// The multipliers.
        lambda: [f64; 3],
        /// `det(I - A^-1 Lambda)`.
        determinant: f64,
    },
    /// Lambda outside what the regularising constraint can justify.
    #[error("lambda {lambda:?} is out of range: {reason}")]
    LambdaOutOfRange {
        /// The multipliers.
        lambda: [f64; 3],
        /// Which limit, in words.
        reason: String,
    },
    /// Order above [`MAX_ORDER`].
    #[error("order {0} is above the highest structural order {MAX_ORDER}")]
    Order(usize),
    /// Welch settings refused.
    #[error("welch: {0}")]
    Welch(String),
    /// The record holds too few Welch averages for the 3-input estimate
    /// ([`MIN_EQUIVALENT_AVERAGES`]).
    #[error(
        "welch: too few samples for the chosen spectral segment: {n_samples} samples hold \
         {segments} segments of {segment_len} (overlap {overlap}), {averages:.1} equivalent \
         averages, and the identifier needs at least {min}: {advice}"
    )]
    TooFewSegments {
        /// Samples in the record (or span).
        n_samples: usize,
        /// The segment length.
        segment_len: usize,
        /// The overlap.
        overlap: f64,
        /// Segments the record holds.
        segments: usize,
        /// Their equivalent number of averages.
        averages: f64,
        /// Fewest accepted ([`MIN_EQUIVALENT_AVERAGES`]).
        min: f64,
        /// What to do, in words.
        advice: String,
    },
    /// A block the run does not have.
    #[error("block '{0}' is not in this run")]
    MissingBlock(&'static str),
    /// No block to identify.
    #[error("the run has no sensor block to identify")]
    NoBlocks,
}

impl Settings {
    /// Checks the settings against a run (or its span) of `n_samples` at `sample_rate_hz` having
    /// `blocks`.
    ///
    /// # Errors
    /// The first violated rule of the module docs.
    pub fn validate(
        &self,
        n_samples: usize,
        sample_rate_hz: f64,
        blocks: &[Block],
    ) -> Result<(), SettingsError> {
        let nyquist = sample_rate_hz / 2.0;
        if let BandSetting::Fixed([low, high]) = self.band_hz
            && !(low.is_finite() && high.is_finite() && low > 0.0 && low < high && high <= nyquist)
        {
            return Err(SettingsError::Band { low, high, nyquist });
        }
        self.validate_weight_and_lambda()?;
        for block in Block::BOTH {
            if let OrderSetting::Fixed(n) = self.order.of(block)
                && n > MAX_ORDER
            {
                return Err(SettingsError::Order(n));
            }
        }
        self.welch
            .validate(n_samples)
            .map_err(|e| SettingsError::Welch(e.to_string()))?;
        let averages = equivalent_averages_of(&self.welch, n_samples);
        if averages < MIN_EQUIVALENT_AVERAGES {
            return Err(self.too_few_segments(n_samples, averages));
        }
        if blocks.is_empty() {
            return Err(SettingsError::NoBlocks);
        }
        if let Some(b) = self.blocks.iter().find(|b| !blocks.contains(b)) {
            return Err(SettingsError::MissingBlock(b.name()));
        }
        Ok(())
    }

    /// The refusal of a record holding `averages` equivalent averages of the settings' segment,
    /// with what would do: the longest power-of-two segment that is enough, or the record length
    /// the program's shortest segment needs.
    fn too_few_segments(&self, n_samples: usize, averages: f64) -> SettingsError {
        let mut shorter = self.welch;
        while shorter.segment_len > MIN_SEGMENT_LEN && !enough_to_identify(&shorter, n_samples) {
            shorter.segment_len = (shorter.segment_len / 2).max(MIN_SEGMENT_LEN) & !1;
        }
        let advice = match (self.welch.segment_auto, enough_to_identify(&shorter, n_samples)) {
            (true, _) => {
                let floor = WelchSettings {
                    segment_len: AUTO_MIN_SEGMENT_LEN,
                    ..self.welch
                };
                let needed = (AUTO_MIN_SEGMENT_LEN..)
                    .step_by(floor.step().max(1))
                    .find(|&n| enough_to_identify(&floor, n))
                    .unwrap_or(usize::MAX);
                format!(
                    "the record needs at least {needed} samples for the program's shortest \
                     segment ({AUTO_MIN_SEGMENT_LEN}), or give a shorter segment"
                )
            }
            (false, true) => format!(
                "give a segment of {} samples (the longest power of two that fits), or a longer \
                 record",
                shorter.segment_len
            ),
            (false, false) => "the record is too short to identify".to_owned(),
        };
        SettingsError::TooFewSegments {
            n_samples,
            segment_len: self.welch.segment_len,
            overlap: self.welch.overlap,
            segments: self.welch.n_segments(n_samples),
            averages,
            min: MIN_EQUIVALENT_AVERAGES,
            advice,
        }
    }

    /// Checks `A` (symmetric positive definite) and `Lambda` (`I - A^-1 Lambda` invertible).
    ///
    /// # Errors
    /// [`SettingsError::WeightNotSpd`] or [`SettingsError::SingularLambda`].
    pub fn validate_weight_and_lambda(&self) -> Result<(), SettingsError> {
        let a = self.weight();
        if a.iter().any(|v| !v.is_finite()) {
            return Err(SettingsError::WeightNotSpd {
                reason: "an entry is not a finite number".into(),
            });
        }
        let asym = (a - a.transpose()).abs().max();
        if asym > 1e-12 * a.abs().max().max(1.0) {
            return Err(SettingsError::WeightNotSpd {
                reason: format!("not symmetric (largest |A - A^T| = {asym:.3e})"),
            });
        }
        let eig = a.symmetric_eigen().eigenvalues;
        let min = eig.min();
        if min <= 1e-12 * eig.max().abs().max(f64::MIN_POSITIVE) {
            return Err(SettingsError::WeightNotSpd {
                reason: format!("smallest eigenvalue {min:.3e} is not positive"),
            });
        }
        if let LambdaSetting::Values(l) = self.lambda {
            let det = a.try_inverse().map_or(0.0, |inv| {
                (Matrix3::identity() - inv * Matrix3::from_diagonal(&l.into())).determinant()
            });
            if !(det.is_finite() && det.abs() > 1e-9) {
                return Err(SettingsError::SingularLambda {
                    lambda: l,
                    determinant: det,
                });
            }
            if let Some(channel) = l.iter().position(|&v| v < 0.0) {
                return Err(SettingsError::LambdaOutOfRange {
                    lambda: l,
                    reason: format!(
                        "lambda[{channel}] = {} is negative: it would amplify the Wiener estimate \
                         (the gain of output {channel} multiplied by more than 1); the constraint \
                         can only shrink it, 0 <= lambda",
                        l[channel]
                    ),
                });
            }
            let shrink = max_shrink(&a, &l);
            if shrink.is_nan() || shrink > MAX_SHRINK {
                return Err(SettingsError::LambdaOutOfRange {
                    lambda: l,
                    reason: format!(
                        "A^-1 Lambda has an eigenvalue of {shrink:.3}: the gain would be shrunk by \
                         more than {:.0} % (at most {MAX_SHRINK} is allowed, A - Lambda / {MAX_SHRINK} \
                         positive definite)",
                        MAX_SHRINK * 100.0
                    ),
                });
            }
        }
        Ok(())
    }
}
