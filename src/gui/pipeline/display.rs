//! What the spectra tab draws, derived once per Welch setting from the identifier's own spectra
//! ([`ident::spectra::BlockSpectra`](crate::ident::spectra::BlockSpectra), computed once and shared
//! with the identification stages): the 6x6 CSD matrix of `[u; x]` on the native Welch bins, log-log
//! PSD lines and the frequency-by-pair grids.

use std::sync::Arc;

use egui_plot::PlotPoint;
use num_complex::Complex64;

use crate::block::Block;
use crate::ident::spectra::BlockSpectra as CoreSpectra;
use crate::spectral::WelchSettings;

/// The 6x6 CSD matrix of `[u; x]` read from the identifier's zero-padded spectra at their native
/// bins (every `fft_len / segment_len`-th bin: exactly the un-padded Welch estimate).
#[derive(Debug)]
pub struct NativeCsd {
    /// The identifier's spectra.
    pub core: Arc<CoreSpectra>,
    /// Padded-grid index step between native bins.
    pub step: usize,
    /// Native bin frequencies, Hz.
    pub frequency_hz: Vec<f64>,
    /// Segments averaged.
    pub n_averages: usize,
}

impl NativeCsd {
    /// Wraps `core`.
    #[must_use]
    pub fn new(core: Arc<CoreSpectra>) -> Self {
        let step = core.native_step();
        let frequency_hz = core.frequency_hz.iter().step_by(step).copied().collect();
        Self {
            n_averages: core.n_averages,
            core,
            step,
            frequency_hz,
        }
    }

    /// Number of native bins.
    #[must_use]
    pub fn n_bins(&self) -> usize {
        self.frequency_hz.len()
    }

    /// Native bin spacing, Hz.
    #[must_use]
    pub fn df_hz(&self) -> f64 {
        self.frequency_hz.get(1).copied().unwrap_or(1.0)
    }

    /// `S[f][i][j]` of `[u; x]` (channels 0..6), or `None` out of range.
    #[must_use]
    pub fn get(&self, f: usize, i: usize, j: usize) -> Option<Complex64> {
        if f >= self.n_bins() || i >= 6 || j >= 6 {
            return None;
        }
        let k = f * self.step;
        let c = &self.core;
        Some(match (i < 3, j < 3) {
            (true, true) => c.s_uu[k][(i, j)],
            (false, true) => c.s_xu[k][(i - 3, j)],
            (true, false) => c.s_xu[k][(j - 3, i)].conj(),
            (false, false) => c.s_xx[k][(i - 3, j - 3)],
        })
    }

    fn power(&self, f: usize, i: usize) -> f64 {
        self.get(f, i, i).map_or(0.0, |s| s.re)
    }

    /// Magnitude-squared coherence of channels `i`, `j` per native bin; 0 where either is silent.
    #[must_use]
    pub fn coherence(&self, i: usize, j: usize) -> Vec<f64> {
        (0..self.n_bins())
            .map(|f| {
                let denom = self.power(f, i) * self.power(f, j);
                let s = self.get(f, i, j).unwrap_or_default();
                if denom > 0.0 {
                    (s.norm_sqr() / denom).min(1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// Spectra of one block: inputs then outputs, six channels.
#[derive(Debug)]
pub struct BlockSpectra {
    /// The block.
    pub block: Block,
    /// `[wx, wy, wz, gx, gy, gz]` or `[fx, fy, fz, ax, ay, az]`.
    pub channels: [&'static str; 6],
    /// One-sided CSD matrix on the native bins, units^2/Hz.
    pub matrix: NativeCsd,
    /// Per channel, `(log10 f, log10 PSD)` for the bins above DC with positive power.
    pub psd_log: Vec<Vec<PlotPoint>>,
    /// Channel pairs `(i, j)`, `i < j`, in the order of the pair grids' rows.
    pub pairs: Vec<(usize, usize)>,
    /// `10 log10 |S_ij|` per pair row and bin (`[pair][bin]`), dB re 1 unit^2/Hz.
    pub pair_magnitude_db: Vec<f32>,
    /// Magnitude-squared coherence per pair row and bin, `[0, 1]`.
    pub pair_coherence: Vec<f32>,
}

/// All blocks' spectra for one Welch setting.
#[derive(Debug)]
pub struct Spectra {
    /// The settings they were computed with (the stage's cache key).
    pub welch: WelchSettings,
    /// Blocks present in the run, gyro first.
    pub blocks: Vec<BlockSpectra>,
}

/// `10 log10 x`, with a floor for zero power.
#[must_use]
pub fn decibels(x: f64) -> f64 {
    10.0 * x.max(1e-300).log10()
}

/// The display data of one block's identifier spectra.
#[must_use]
pub fn block_spectra(block: Block, channels: [&'static str; 6], core: Arc<CoreSpectra>) -> BlockSpectra {
    let matrix = NativeCsd::new(core);
    let psd_log = (0..channels.len())
        .map(|i| {
            (1..matrix.n_bins())
                .map(|f| (matrix.frequency_hz[f], matrix.power(f, i)))
                .filter(|&(_, p)| p > 0.0)
                .map(|(f, p)| PlotPoint::new(f.log10(), p.log10()))
                .collect()
        })
        .collect();
    let pairs: Vec<(usize, usize)> = (0..channels.len())
        .flat_map(|i| (i + 1..channels.len()).map(move |j| (i, j)))
        .collect();
    let mut pair_magnitude_db = Vec::with_capacity(pairs.len() * matrix.n_bins());
    let mut pair_coherence = Vec::with_capacity(pairs.len() * matrix.n_bins());
    for &(i, j) in &pairs {
        for f in 0..matrix.n_bins() {
            let s = matrix.get(f, i, j).map_or(0.0, Complex64::norm);
            pair_magnitude_db.push(decibels(s) as f32);
        }
        pair_coherence.extend(matrix.coherence(i, j).iter().map(|&c| c as f32));
    }
    BlockSpectra {
        block,
        channels,
        matrix,
        psd_log,
        pairs,
        pair_magnitude_db,
        pair_coherence,
    }
}
