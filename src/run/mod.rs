//! Loading stand runs (contract section 2): a CSV file (plain or gzipped) plus an optional JSON
//! sidecar of the same stem.
//!
//! # Contracts
//! - **Units**: SI as written in the file: `t` in s, angles in rad, gyro outputs in rad/s,
//!   accelerometer outputs in m/s^2, lever arms in m. Nothing is rescaled; `t` keeps its origin.
//! - **NaN and infinities**: refused. Every value of a loaded [`Run`] is finite; a `nan`, `inf` or
//!   `-inf` cell is [`LoadError::NonFinite`] naming its line and column.
//! - **Empty input**: refused. A file without a header is [`LoadError::Empty`]; fewer than
//!   [`MIN_SAMPLES`] rows is [`LoadError::TooFewSamples`]. A loaded run is never empty.
//! - **Time**: strictly increasing and uniform within [`LoadOptions::sampling_tolerance`] (1 %) of
//!   the nominal step (median of the first steps).
//! - **Angles**: wrapped columns ((-π, π] or [0, 2π)) are unwrapped with a notice; a step over
//!   [`LoadOptions::max_angle_step_rad`] (1 rad) that is not a wrap is [`LoadError::AngleJump`]
//!   (`wrap`).
//! - **Errors**: the first problem in file order, as one [`LoadError`] naming file, line and column
//!   where they apply. Bad input never panics.
//!
//! # Reading
//! One pass over the file: a named reader thread reads 2 MiB blocks, hashes the bytes as stored
//! (SHA-256), gunzips when the file starts with the gzip magic bytes (`1f 8b`) and cuts the text at
//! the last newline; the calling thread parses each block's lines in parallel with rayon. The whole
//! text is never held in memory; columns are reserved from the first block's rows per byte.
//!
//! Accepted: a UTF-8 byte-order mark (removed, with a notice), CRLF line endings, a missing final
//! newline, blank trailing lines, exponents (`-8.5e-05`), a leading `+`, spaces around cells, any
//! column order, unknown columns (kept in [`Run::extra`] with a notice), names and cells in double
//! quotes (one pair around the field). Header names are case-sensitive; a missing one present in
//! another case is named in the error.

mod csv;
mod error;
mod header;
mod load;
mod number;
mod options;
mod piece;
mod sidecar;
mod stream;
mod timing;
mod wrap;

use std::path::PathBuf;

pub use crate::block::Block;
pub use error::LoadError;
pub use load::{load, load_bytes, load_with_progress};
pub use options::{LoadOptions, LoadProgress, MIN_SAMPLES};
pub use sidecar::{
    SIDECAR_FIELDS, SIDECAR_FORMAT, STANDARD_G_MPS2, Sidecar, parse_sidecar, run_stem, sidecar_path,
};
pub use timing::{NOMINAL_STEPS, nominal_step};

/// Where a run came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunSource {
    /// The path it was loaded from, as given.
    pub path: PathBuf,
    /// The file name (`cruise.csv.gz`).
    pub file_name: String,
    /// SHA-256 of the file's bytes as stored (compressed for gzip), lower-case hex.
    pub sha256: String,
    /// Size of the file as stored, bytes.
    pub size_bytes: u64,
}

/// A column the format does not know, kept as read.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraColumn {
    /// Its header name.
    pub name: String,
    /// Its values, one per row.
    pub values: Vec<f64>,
}

/// A loaded stand run: every column has [`Run::len`] finite values. Its `Debug` summarises the
/// columns (length, time span, which blocks) instead of printing every sample.
#[derive(Clone, PartialEq)]
pub struct Run {
    /// The file.
    pub source: RunSource,
    /// Column `t` as in the file (need not start at 0), s.
    pub time_s: Vec<f64>,
    /// `(n-1)/(t_last - t_first)`, Hz.
    pub sample_rate_hz: f64,
    /// `[roll, yaw, pitch]`: rotations about platform `[x, y, z]`, rad.
    pub angles: [Vec<f64>; 3],
    /// `[gx, gy, gz]`, rad/s, when the gyro block is present.
    pub gyro: Option<[Vec<f64>; 3]>,
    /// `[ax, ay, az]`, m/s^2, when the accelerometer block is present.
    pub accel: Option<[Vec<f64>; 3]>,
    /// Unknown columns, in file order: kept, and ignored by the identifier.
    pub extra: Vec<ExtraColumn>,
    /// The sidecar, or its defaults.
    pub sidecar: Sidecar,
    /// Things the user should know that are not errors (unknown columns, missing sidecar, BOM).
    pub notices: Vec<String>,
}

impl std::fmt::Debug for Run {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let extra: Vec<&str> = self.extra.iter().map(|c| c.name.as_str()).collect();
        f.debug_struct("Run")
            .field("source", &self.source)
            .field("samples", &self.len())
            .field("time_s", &(self.time_s.first(), self.time_s.last()))
            .field("sample_rate_hz", &self.sample_rate_hz)
            .field("gyro", &self.gyro.is_some())
            .field("accel", &self.accel.is_some())
            .field("extra", &extra)
            .field("sidecar", &self.sidecar)
            .field("notices", &self.notices)
            .finish_non_exhaustive()
    }
}

impl Run {
    /// Number of samples (rows).
    #[must_use]
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when there are no samples (never for a run returned by [`load()`]).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// `t_last - t_first`, s (0 for fewer than two samples).
    #[must_use]
    pub fn duration_s(&self) -> f64 {
        match (self.time_s.first(), self.time_s.last()) {
            (Some(first), Some(last)) => last - first,
            _ => 0.0,
        }
    }

    /// The mean sampling step `1 / sample_rate_hz`, s.
    #[must_use]
    pub fn dt_s(&self) -> f64 {
        1.0 / self.sample_rate_hz
    }

    /// The blocks present, gyro first.
    #[must_use]
    pub fn blocks(&self) -> Vec<Block> {
        let mut blocks = Vec::with_capacity(2);
        if self.gyro.is_some() {
            blocks.push(Block::Gyro);
        }
        if self.accel.is_some() {
            blocks.push(Block::Accel);
        }
        blocks
    }

    /// A block's three outputs (`[gx, gy, gz]` or `[ax, ay, az]`), `None` when it is absent.
    #[must_use]
    pub fn outputs(&self, block: Block) -> Option<&[Vec<f64>; 3]> {
        match block {
            Block::Gyro => self.gyro.as_ref(),
            Block::Accel => self.accel.as_ref(),
        }
    }
}
