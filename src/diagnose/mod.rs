//! The missing-effect workflow (issue 5, contract section 5): where does the identified model,
//! driven by the observer's inputs, disagree with the measured outputs, which catalogue effect
//! explains the disagreement, how large is it, and how much of the gap does adding it close.
//!
//! 1. Identify the run with the paper's model `K e^(-tau s)` (order 0). Its disturbance model
//!    `S_psi` (median-smoothed across frequency, so lines do not hide in it) sets the level every
//!    residual bin is expected to have.
//! 2. Whole-record spectra of outputs, inputs and the effects' regressors ([`design`]).
//! 3. Refit the base model on them, then, round by round, fit every catalogue effect the model
//!    does not hold yet ([`candidates`]), measure the `chi2` it removes, and penalise its added
//!    parameters by BIC (`ln n` each, `n` the real degrees of freedom of the band). The best
//!    effect with a positive gain is added, everything is refitted, and the next round starts;
//!    when no effect gains, the search stops. No effect at all gives `no_missing_effect`.
//!
//! Nothing here reads a simulated run's answer key: only the measured angles, outputs and the
//! sidecar's declared lever arms, `g` and angle noise. Units: SI; gaps in dB of power; `chi2` in
//! units of the expected disturbance. Empty or too-short records are refused with
//! [`DiagnoseError::TooShort`]; non-finite samples cannot reach here (the loader refuses them).

pub mod accepted;
pub mod band_limit;
pub mod candidates;
pub mod clock;
pub mod describe;
pub mod design;
pub mod extend;
pub mod fit;
pub mod gate;
pub mod halves;
pub mod identified;
pub mod input_limit;
pub mod limits;
pub mod map;
pub mod noisy_angles;
pub mod not_named;
mod prepared;
pub mod profile;
pub mod report;
mod rules;
pub mod simplex;
pub mod size_limit;
pub mod state;
pub mod step_caveat;
pub mod structure;
pub mod suspect;
pub mod tone;
pub mod tone_limit;
pub mod uncertainty;
pub mod usable_band;
pub mod white_angles;
mod workflow;

pub use report::{DISCREPANCY_SCHEMA, Finding, Report, Verdict};
pub use workflow::{
    DiagnoseOptions, Prepared, PreparedBlock, diagnose_prepared, diagnose_run, diagnose_session, prepare,
};

/// Why a diagnosis could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// The identification the diagnosis starts from failed.
    #[error(transparent)]
    Ident(#[from] crate::ident::IdentError),
    /// The band holds too few whole-record bins.
    #[error("the {block} block's record is too short for a diagnosis between {low} and {high} Hz")]
    TooShort {
        /// Block name.
        block: &'static str,
        /// Band low edge, Hz.
        low: f64,
        /// Band high edge, Hz.
        high: f64,
    },
    /// The base model could not be fitted (degenerate inputs).
    #[error("the {0} block's base model cannot be fitted: its inputs are degenerate")]
    Degenerate(&'static str),
}

impl DiagnoseError {
    /// Whether the error is the user's input (the run, or settings that do not fit it): exit
    /// status 2 and an error panel, where anything else is our fault (exit status 1).
    #[must_use]
    pub fn is_input_error(&self) -> bool {
        match self {
            DiagnoseError::Ident(e) => e.is_input_error(),
            DiagnoseError::TooShort { .. } | DiagnoseError::Degenerate(_) => true,
        }
    }
}

#[cfg(test)]
mod tests;
