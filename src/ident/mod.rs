//! The identifier: from a run's block inputs and outputs to the block's transfer matrix and the
//! spectral model of its disturbances (READING.md, "The identification problem").
//!
//! Staged so that each change redoes only what depends on it: signals (observer) -> spectra
//! (Welch) -> factorisation (Wilson, causal projection) -> regularised Wiener (A, Lambda) ->
//! structural fit (order).

pub mod alignment;
pub mod band;
pub mod band_cache;
pub mod band_top;
pub mod block_orders;
pub mod causal_stage;
pub mod coherent_spans;
pub mod dead_output;
mod delay_excursion;
pub mod delay_scatter;
pub mod delay_step;
pub mod even_gain;
pub mod excitation;
pub mod explained;
pub mod factorisation;
pub mod factorisation_warnings;
pub mod gain_curvature;
pub mod gain_pattern;
pub mod holdout;
pub mod identify;
pub mod left_out_noise;
pub mod odd_gain;
pub mod selfcheck;
pub mod session;
pub mod settings;
pub mod signals;
pub mod spectra;
pub mod stretches;
pub mod structural;
pub mod suspicion;
mod warning_words;
pub mod warnings;
pub mod wiener;
pub mod witness_noise;

/// Why an identification step failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IdentError {
    /// A spectral factorisation was refused or could not be inverted.
    #[error("spectral factorisation failed: {0}")]
    Factor(#[from] FactorStageError),
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
    Settings(#[from] settings::SettingsError),
    /// The observer refused the angles.
    #[error("observer: {0}")]
    Observer(#[from] crate::stand::observer::ObserverError),
    /// The run lacks a block the settings name.
    #[error("the run has no {0} block")]
    MissingBlock(&'static str),
    /// The spectral estimate failed.
    #[error("spectra: {0}")]
    Spectra(#[from] crate::spectral::SpectralError),
    /// The structural fit failed.
    #[error("structural fit: {0}")]
    Structural(#[from] structural::StructuralError),
    /// No stretch of the band where the block's outputs are coherent with the inputs computed
    /// from the angles: nothing in this run can be trusted for this block.
    #[error(
        "{block} block: no usable band between {low_hz} and {high_hz} Hz: the outputs are nowhere \
         coherent with the inputs computed from the angles (best multiple coherence {best_coherence:.2}, \
         at least {min:.2} needed over {bins} bins){}; check the angle columns and the block's \
         outputs{}",
        coherent_words(coherent_s),
        or_leave_out(*others, "give band_hz")
    )]
    NoUsableBand {
        /// The block.
        block: &'static str,
        /// Low search limit, Hz.
        low_hz: f64,
        /// High search limit, Hz.
        high_hz: f64,
        /// Best smoothed coherence found.
        best_coherence: f64,
        /// The coherence needed ([`band::MIN_COHERENCE`]).
        min: f64,
        /// Bins needed ([`band::MIN_BAND_BINS`]).
        bins: usize,
        /// Whether other blocks are identified beside this one (the advice to leave it out means
        /// nothing when it is the only block of the run, or the only one asked for;
        /// [`IdentError::alone`]).
        others: bool,
        /// Where in the record the outputs are coherent with the inputs all the same, s from the
        /// first sample analysed ([`coherent_spans`]; empty: nowhere, or not told).
        coherent_s: Vec<[f64; 2]>,
    },
    /// An input direction of a block carries (almost) no power in the band: a stand axis held
    /// still. Its response cannot be identified from this run.
    #[error(
        "{block} block: axis {axis} not excited between {low_hz} and {high_hz} Hz (weakest input \
         direction has {relative_power:.1e} of the strongest's power): {}{}",
        excitation::advice(axis),
        or_leave_out(*others, "identify from a run that does")
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
        /// Whether other blocks are identified beside this one ([`IdentError::alone`]).
        others: bool,
    },
    /// An output channel holds one value over every sample analysed: a dead or disconnected
    /// sensor axis ([`dead_output`]). Nothing of the block's response is in it.
    #[error(
        "{block} block: {} over the samples analysed (a dead or disconnected channel, a stuck \
         sensor axis or a column the logger never wrote): nothing of the block's response is in \
         it; check the sensor and the logger's channel map{}",
        dead_output::channel_words(channels),
        or_leave_out(*others, "record the run again")
    )]
    DeadOutput {
        /// The block.
        block: &'static str,
        /// Each flat channel (`gz`, ...) with the one value it holds.
        channels: Vec<(&'static str, f64)>,
        /// Whether other blocks are identified beside this one ([`IdentError::alone`]).
        others: bool,
    },
    /// A matrix that must be inverted is singular.
    #[error("{0} is singular")]
    Singular(&'static str),
}

/// What failed inside the factorisation stage (the leaf error, kept as it is).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FactorStageError {
    /// Wilson's factorisation or the factor's inverse.
    #[error(transparent)]
    Wilson(#[from] crate::spectral::factor::FactorError),
    /// The one-sided to two-sided grid.
    #[error(transparent)]
    Grid(#[from] crate::spectral::grid::GridError),
    /// The causal projection.
    #[error(transparent)]
    Causal(#[from] crate::spectral::causal::CausalError),
    /// The finer grid of the causal stage.
    #[error(transparent)]
    Refine(#[from] crate::spectral::refine::RefineError),
    /// The causal estimate was asked of a factorisation computed without its causal stage.
    #[error("the causal estimate needs the factorisation's causal stage, which was not computed")]
    NoCausalStage,
    /// The residual spectrum is not finite at a bin (spectra too large to multiply).
    #[error("the residual spectrum is not finite at bin {bin}")]
    NonFiniteResidual {
        /// The bin, on the one-sided grid.
        bin: usize,
    },
    /// The input spectrum is not finite at a bin (of the one-sided grid, or of the causal
    /// stage's finer two-sided grid).
    #[error("the input spectrum is not finite at bin {bin}")]
    NonFiniteInput {
        /// The bin, on the grid where it was met.
        bin: usize,
    },
}

/// The end of a refusal's advice: `, {alternative}, or leave this block out (settings "blocks")`
/// when the run has other blocks, else `, or {alternative}`.
/// The words of [`IdentError::NoUsableBand`]'s coherent spans (none when there are none).
fn coherent_words(spans: &[[f64; 2]]) -> String {
    if spans.is_empty() {
        return String::new();
    }
    let spans: Vec<String> = spans.iter().map(|[a, b]| format!("{a:.1}-{b:.1} s")).collect();
    format!(
        "; yet they are coherent over {} of the record (from its first sample analysed) and not \
         elsewhere: there the outputs are of another motion than the angles (a splice, samples \
         lost from one stream, a stalled logger); analyse the coherent part alone (span_s, in the \
         run's own time column)",
        spans.join(", ")
    )
}

fn or_leave_out(others: bool, alternative: &str) -> String {
    if others {
        format!(", {alternative}, or leave this block out (settings \"blocks\")")
    } else {
        format!(", or {alternative}")
    }
}

impl IdentError {
    /// The refusal of a block that is the only one its run has: its advice no longer offers to
    /// leave it out (nothing would be left).
    #[must_use]
    pub fn alone(mut self) -> Self {
        if let IdentError::NoUsableBand { others, .. }
        | IdentError::NotExcited { others, .. }
        | IdentError::DeadOutput { others, .. } = &mut self
        {
            *others = false;
        }
        self
    }

    /// Whether the error refuses one block for what its own data lack, leaving the run's other
    /// blocks to be identified: such a block goes to [`identify::RunIdentification::refused`]
    /// beside the others. A dead output channel of either block is ([`dead_output`]: the
    /// channel's own fault, and a gyro with one is not the angle noise's witness). Of the others
    /// only the accelerometer's are: no usable band (outputs not coherent with the inputs: a
    /// dead or disconnected block), or an input axis not excited (its inputs depend on its lever
    /// arm: a zero or undeclared arm leaves the vertical one flat while the motion is fine). The
    /// gyro's refuse the run: its inputs are the stand's
    /// angular motion itself (a stand axis held still takes every block's inputs with it; an
    /// accelerometer fitted beside it came out with gains 50 % off), and its outputs witness the
    /// stand's angle noise for every block (`Session::motion`; a dead gyro as witness left the
    /// accelerometer's band 1.5 Hz wide).
    #[must_use]
    pub fn is_refusal(&self) -> bool {
        match self {
            IdentError::NoUsableBand { block, .. } | IdentError::NotExcited { block, .. } => {
                *block != crate::block::Block::Gyro.name()
            }
            // The channel's own fault, whichever block: the stand's motion is untouched.
            IdentError::DeadOutput { .. } => true,
            _ => false,
        }
    }

    /// Whether the error is the user's input (the run, or settings that do not fit it): exit
    /// status 2 and an error panel, where anything else is our fault (exit status 1).
    #[must_use]
    pub fn is_input_error(&self) -> bool {
        use crate::spectral::SpectralError as S;
        use structural::StructuralError as F;
        match self {
            IdentError::Settings(_)
            | IdentError::MissingBlock(_)
            | IdentError::EmptyBand { .. }
            | IdentError::NotExcited { .. }
            | IdentError::NoUsableBand { .. }
            | IdentError::DeadOutput { .. }
            | IdentError::Observer(_) => true,
            IdentError::Singular(what) => *what == "weight_A" || *what == "auto-lambda system",
            IdentError::Spectra(e) => !matches!(e, S::Fft(_) | S::ShapeMismatch { .. } | S::BadParts { .. }),
            IdentError::Structural(e) => matches!(e, F::EmptyBand | F::TooFewBins { .. }),
            IdentError::Factor(_) => false,
        }
    }
}

#[cfg(test)]
#[path = "ident_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "edges_tests.rs"]
mod edges_tests;

#[cfg(test)]
#[path = "causal_grid_tests.rs"]
mod causal_grid_tests;

#[cfg(test)]
#[path = "finer_stretches_tests.rs"]
mod finer_stretches_tests;
