//! Widgets: each draws from borrowed state and pushes [`Command`](crate::gui::app::Command)s.

pub mod bode;
pub mod colormap;
pub mod compare;
pub mod controls;
pub mod discrepancy;
pub mod disturbance;
pub mod errors;
pub mod grid;
pub mod heatmap;
pub mod key;
pub mod results;
pub mod runs;
pub mod spectra;
pub mod stationarity;
pub mod timeseries;
pub mod validation;

use eframe::egui::Color32;

/// Line colours: three axes of inputs, then three of outputs.
#[must_use]
pub fn palette(k: usize) -> Color32 {
    const COLOURS: [Color32; 6] = [
        Color32::from_rgb(230, 85, 80),
        Color32::from_rgb(90, 190, 90),
        Color32::from_rgb(80, 140, 240),
        Color32::from_rgb(240, 170, 60),
        Color32::from_rgb(170, 110, 230),
        Color32::from_rgb(70, 200, 210),
    ];
    COLOURS[k % COLOURS.len()]
}
