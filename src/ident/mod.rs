//! The identifier: from a run's block inputs and outputs to the block's transfer matrix and the
//! spectral model of its disturbances (READING.md, "The identification problem").
//!
//! Staged so that each change redoes only what depends on it: signals (observer) -> spectra
//! (Welch) -> factorisation (Wilson, causal projection) -> regularised Wiener (A, Lambda) ->
//! structural fit (order).

pub mod excitation;
pub mod factorisation;
pub mod identify;
pub mod settings;
pub mod signals;
pub mod spectra;
pub mod structural;
pub mod warnings;
pub mod wiener;

/// Why an identification step failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IdentError {
    /// A spectral factorisation was refused or could not be inverted.
    #[error("spectral factorisation failed: {0}")]
    Factor(String),
    /// No Welch bin inside the analysis band.
    #[error("no frequency bin between {low} and {high} Hz: widen the band or lengthen the segment")]
    EmptyBand {
        /// Low edge, Hz.
        low: f64,
        /// High edge, Hz.
        high: f64,
    },
    /// Settings refused for this run.
    #[error("settings: {0}")]
    Settings(String),
    /// The observer refused the angles.
    #[error("observer: {0}")]
    Observer(String),
    /// The run lacks a block the settings name.
    #[error("the run has no {0} block")]
    MissingBlock(&'static str),
    /// The spectral estimate failed.
    #[error("spectra: {0}")]
    Spectra(String),
    /// The structural fit failed.
    #[error("structural fit: {0}")]
    Structural(String),
    /// An input direction of a block carries (almost) no power in the band: a stand axis held
    /// still. Its response cannot be identified from this run.
    #[error(
        "{block} block: axis {axis} not excited between {low_hz} and {high_hz} Hz (weakest input \
         direction has {relative_power:.1e} of the strongest's power): move that stand axis, or \
         identify from a run that does"
    )]
    NotExcited {
        /// The block (`"gyro"` or `"accel"`).
        block: &'static str,
        /// The input axis (`"wz"`, `"fx"`, ...) with the largest share of the weakest direction.
        axis: &'static str,
        /// Low edge of the band, Hz.
        low_hz: f64,
        /// High edge of the band, Hz.
        high_hz: f64,
        /// Weakest over strongest principal input power over the band.
        relative_power: f64,
    },
    /// A matrix that must be inverted is singular.
    #[error("{0} is singular")]
    Singular(&'static str),
}

#[cfg(test)]
#[path = "ident_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "edges_tests.rs"]
mod edges_tests;
