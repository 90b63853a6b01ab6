//! The identifier: from a run's block inputs and outputs to the block's transfer matrix and the
//! spectral model of its disturbances (READING.md, "The identification problem").

pub mod settings;
pub mod structural;
