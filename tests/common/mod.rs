//! Helpers shared by the integration tests: the spectral ones here, the others in their own
//! modules (`accept` models with accepted effects, `sim` simulated runs, `real` the real
//! recordings, `loader` CSV texts, `poles` a warning read, `gui` the app's harness).

pub mod accept;
#[cfg(feature = "gui")]
pub mod gui;
pub mod loader;
pub mod poles;
pub mod real;
pub mod sim;

use imu_attest::rng::Rng;
use imu_attest::spectral::{Detrend, WelchSettings, Window};

/// `n_channels` seeded, cross-correlated channels of `len` samples with offsets and trends:
/// channel 0 is white noise, channel `c` mixes channel `c - 1` (delayed by `c` samples) with fresh
/// noise, an offset `c` and a slope `0.001 c` per sample.
pub fn correlated_channels(seed: u64, n_channels: usize, len: usize) -> Vec<Vec<f64>> {
    let mut rng = Rng::new(seed);
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(n_channels);
    for c in 0..n_channels {
        let ch = (0..len)
            .map(|t| {
                let driven = match out.last() {
                    Some(prev) if t >= c => 0.7 * prev[t - c],
                    _ => 0.0,
                };
                driven + rng.normal() + c as f64 * (1.0 + 0.001 * t as f64)
            })
            .collect();
        out.push(ch);
    }
    out
}

/// Borrowed views of the channels, as `welch_matrix` takes them.
pub fn views(channels: &[Vec<f64>]) -> Vec<&[f64]> {
    channels.iter().map(Vec::as_slice).collect()
}

/// Settings from their four fields, in declaration order (the segment given).
pub fn settings(segment_len: usize, overlap: f64, window: Window, detrend: Detrend) -> WelchSettings {
    WelchSettings {
        segment_len,
        segment_auto: false,
        overlap,
        window,
        detrend,
        fft_len: None,
    }
}
