//! Where model and measurement disagree: per output channel and octave band, the residual's power
//! relative to what the model's disturbance model expects, with a significance figure; and the
//! residual's spectral density on log-spaced cells for plotting.
//!
//! Under a correct model each band's whitened residual power is a sum of `n` independent
//! exponential variables of mean 1 (`n` = independent bins), so `ratio = mean` has standard
//! deviation `1/sqrt(n)` and `z = (ratio - 1) sqrt(n)` is approximately standard normal. A `z`
//! above about 5 marks disagreement that noise does not explain.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::design::Design;

/// The disagreement map of one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisagreementMap {
    /// Band edges `[low, high]`, Hz.
    pub bands_hz: Vec<[f64; 2]>,
    /// `ratio_db[channel][band]`: residual over expected power, dB.
    pub ratio_db: Vec<Vec<f64>>,
    /// `z[channel][band]`: significance of the excess, standard deviations.
    pub z: Vec<Vec<f64>>,
}

/// A residual spectral density for plotting.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualPsd {
    /// Cell centre frequencies (geometric), Hz.
    pub frequency_hz: Vec<f64>,
    /// `psd[channel][cell]`, one-sided, output units^2/Hz.
    pub psd: Vec<Vec<f64>>,
}

/// Octave bands from the band's low edge (the last one ends at the high edge).
fn octave_bands(design: &Design) -> Vec<std::ops::Range<usize>> {
    let f = &design.frequency_hz;
    let (lo, hi) = (f[0], f[f.len() - 1]);
    let mut edges = vec![lo];
    while edges[edges.len() - 1] * 2.0 < hi {
        let next = edges[edges.len() - 1] * 2.0;
        edges.push(next);
    }
    edges.push(hi * (1.0 + 1e-12));
    edges
        .windows(2)
        .map(|e| {
            let a = f.partition_point(|&x| x < e[0]);
            let b = f.partition_point(|&x| x < e[1]);
            a..b
        })
        .filter(|r| !r.is_empty())
        .collect()
}

/// The map of `residual` (band bins per channel).
#[must_use]
pub fn disagreement_map(design: &Design, residual: &[Vec<Complex64>; 3]) -> DisagreementMap {
    let bands = octave_bands(design);
    let independence = design.n_samples as f64 / design.fft_len as f64 / super::design::WINDOW_ENBW;
    let mut ratio_db = Vec::new();
    let mut z = Vec::new();
    for i in 0..3 {
        let (mut rd, mut zs) = (Vec::new(), Vec::new());
        for r in &bands {
            let m = r.len() as f64;
            let ratio = r
                .clone()
                .map(|k| residual[i][k].norm_sqr() / design.expected[i][k])
                .sum::<f64>()
                / m;
            rd.push(10.0 * ratio.max(1e-30).log10());
            zs.push((ratio - 1.0) * (m * independence).sqrt());
        }
        ratio_db.push(rd);
        z.push(zs);
    }
    DisagreementMap {
        bands_hz: bands
            .iter()
            .map(|r| [design.frequency_hz[r.start], design.frequency_hz[r.end - 1]])
            .collect(),
        ratio_db,
        z,
    }
}

/// Spectral density of `spectrum` (band bins per channel) averaged on `cells` log-spaced cells.
#[must_use]
pub fn psd_cells(design: &Design, spectrum: &[Vec<f64>; 3], cells: usize) -> ResidualPsd {
    let f = &design.frequency_hz;
    let (lo, hi) = (f[0], f[f.len() - 1] * (1.0 + 1e-12));
    let level = 0.375 * design.n_samples as f64 * design.sample_rate_hz / 2.0;
    let mut frequency_hz = Vec::new();
    let mut psd = vec![Vec::new(); 3];
    for c in 0..cells {
        let a = lo * (hi / lo).powf(c as f64 / cells as f64);
        let b = lo * (hi / lo).powf((c + 1) as f64 / cells as f64);
        let r = f.partition_point(|&x| x < a)..f.partition_point(|&x| x < b);
        if r.is_empty() {
            continue;
        }
        frequency_hz.push((a * b).sqrt());
        for (i, p) in psd.iter_mut().enumerate() {
            p.push(spectrum[i][r.clone()].iter().sum::<f64>() / (r.len() as f64 * level));
        }
    }
    ResidualPsd { frequency_hz, psd }
}

/// `|residual|^2` per channel and bin.
#[must_use]
pub fn power(residual: &[Vec<Complex64>; 3]) -> [Vec<f64>; 3] {
    residual
        .each_ref()
        .map(|r| r.iter().map(Complex64::norm_sqr).collect())
}
