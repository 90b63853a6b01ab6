//! The identifier: from a run's block inputs and outputs to the block's transfer matrix and the
//! spectral model of its disturbances (READING.md, "The identification problem").
//!
//! Staged so that each change redoes only what depends on it: signals (observer) -> spectra
//! (Welch) -> factorisation (Wilson, causal projection) -> regularised Wiener (A, Lambda) ->
//! structural fit (order).

pub mod factorisation;
pub mod identify;
pub mod settings;
pub mod signals;
pub mod spectra;
pub mod structural;
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
    /// A matrix that must be inverted is singular.
    #[error("{0} is singular")]
    Singular(&'static str),
}

#[cfg(test)]
#[path = "ident_tests.rs"]
mod tests;
