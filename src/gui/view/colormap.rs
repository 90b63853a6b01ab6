//! Colour scale of the heatmaps (a viridis-like ramp) and the pair-grid image.

use eframe::egui::{Color32, ColorImage};

use crate::gui::app::HeatmapMode;
use crate::gui::pipeline::BlockSpectra;

/// Columns of the pair-grid texture, log-spaced in frequency from the first bin to Nyquist.
pub const COLUMNS: usize = 1024;
/// Dynamic range of the magnitude scale below its maximum, dB.
pub const MAGNITUDE_RANGE_DB: f32 = 100.0;

const STOPS: [[u8; 3]; 5] = [
    [68, 1, 84],
    [59, 82, 139],
    [33, 145, 140],
    [94, 201, 98],
    [253, 231, 37],
];

/// Colour of `t` in `[0, 1]` (clamped).
#[must_use]
pub fn color(t: f32) -> Color32 {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * (STOPS.len() - 1) as f32;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let u = x - k as f32;
    let mix = |c: usize| (f32::from(STOPS[k][c]) * (1.0 - u) + f32::from(STOPS[k + 1][c]) * u).round() as u8;
    Color32::from_rgb(mix(0), mix(1), mix(2))
}

/// The block's values for `mode`, `[pair][bin]`.
#[must_use]
pub fn pair_values(block: &BlockSpectra, mode: HeatmapMode) -> &[f32] {
    match mode {
        HeatmapMode::Magnitude => &block.pair_magnitude_db,
        HeatmapMode::Coherence => &block.pair_coherence,
    }
}

/// The colour scale's `(low, high)` for a block: coherence `0..1`; magnitude from the largest
/// value down [`MAGNITUDE_RANGE_DB`] (the diagonal PSDs included).
#[must_use]
pub fn value_range(block: &BlockSpectra, mode: HeatmapMode) -> (f32, f32) {
    match mode {
        HeatmapMode::Coherence => (0.0, 1.0),
        HeatmapMode::Magnitude => {
            let psd_max = block
                .psd_log
                .iter()
                .flatten()
                .map(|p| 10.0 * p.y as f32)
                .fold(f32::NEG_INFINITY, f32::max);
            let high = block.pair_magnitude_db.iter().copied().fold(psd_max, f32::max);
            let high = if high.is_finite() { high.ceil() } else { 0.0 };
            (high - MAGNITUDE_RANGE_DB, high)
        }
    }
}

/// Position of `value` on the scale `range`, `[0, 1]`.
#[must_use]
pub fn normalise(value: f32, (low, high): (f32, f32)) -> f32 {
    if high > low {
        (value - low) / (high - low)
    } else {
        0.0
    }
}

/// The bin at position `u` in `[0, 1]` of a log-frequency axis from bin 1 to bin `n_bins - 1`.
#[must_use]
pub fn log_bin(u: f64, n_bins: usize) -> usize {
    let top = n_bins.saturating_sub(1).max(1) as f64;
    (top.powf(u.clamp(0.0, 1.0)).round() as usize).clamp(1, n_bins.saturating_sub(1).max(1))
}

/// Position in `[0, 1]` of frequency `hz` on that axis (bin spacing `df_hz`).
#[must_use]
pub fn log_position(hz: f64, df_hz: f64, n_bins: usize) -> f64 {
    let top = n_bins.saturating_sub(1).max(2) as f64;
    (hz / df_hz).max(1.0).ln() / top.ln()
}

/// The frequency-by-pair grid as an image: one row per pair, [`COLUMNS`] columns log-spaced in
/// frequency (above DC); a column spanning several bins shows their largest value.
#[must_use]
pub fn pair_image(block: &BlockSpectra, mode: HeatmapMode) -> ColorImage {
    let values = pair_values(block, mode);
    let rows = block.pairs.len().max(1);
    let n_bins = values.len() / rows;
    if n_bins < 3 {
        return ColorImage::filled([1, 1], Color32::BLACK);
    }
    let range = value_range(block, mode);
    let edge = |c: usize| log_bin(c as f64 / COLUMNS as f64, n_bins);
    let mut pixels = Vec::with_capacity(COLUMNS * rows);
    for row in values.chunks(n_bins) {
        for c in 0..COLUMNS {
            let (a, b) = (edge(c), edge(c + 1).max(edge(c) + 1).min(n_bins));
            let v = row[a..b].iter().copied().fold(f32::NEG_INFINITY, f32::max);
            pixels.push(color(normalise(v, range)));
        }
    }
    ColorImage::new([COLUMNS, rows], pixels)
}

#[cfg(test)]
mod tests {
    use super::{color, log_bin, log_position, normalise};
    use eframe::egui::Color32;

    #[test]
    fn ramp_ends_and_clamping() {
        assert_eq!(color(0.0), Color32::from_rgb(68, 1, 84));
        assert_eq!(color(1.0), Color32::from_rgb(253, 231, 37));
        assert_eq!(color(7.0), color(1.0));
        assert_eq!(color(f32::NAN), color(0.0));
        assert!((normalise(-50.0, (-100.0, 0.0)) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn log_axis_round_trip() {
        let n_bins = 2049;
        assert_eq!(log_bin(0.0, n_bins), 1);
        assert_eq!(log_bin(1.0, n_bins), 2048);
        for bin in [1, 7, 100, 2048] {
            let u = log_position(bin as f64 * 0.25, 0.25, n_bins);
            assert_eq!(log_bin(u, n_bins), bin);
        }
    }
}
