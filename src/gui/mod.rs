//! The desktop app (eframe/egui). Only this module imports GUI crates; it draws, sends commands,
//! and runs the core's stages on a worker thread ([`pipeline`]).
//!
//! Layout: [`app`] (state, `logic`, `ui`, commands), [`view`] (one widget per file),
//! [`pipeline`] (worker, cached stages, decimation pyramid).

pub mod app;
pub mod pipeline;
mod sample;
pub mod view;

use std::path::PathBuf;

pub use app::{App, AppOptions, Command, PathPurpose};
pub use pipeline::WorkerMode;
pub use sample::sample_run_path;

/// Why the app could not run.
#[derive(Debug, thiserror::Error)]
pub enum GuiError {
    /// The bundled sample run could not be written to the temporary folder.
    #[error("cannot write the bundled sample run: {0}")]
    Sample(#[from] std::io::Error),
    /// The window or its graphics context could not be created.
    #[error("cannot open the window: {0}")]
    Window(String),
}

/// Opens the app with `paths` loaded, or the bundled sample run when `paths` is empty; returns
/// when the window is closed.
///
/// # Errors
/// [`GuiError`] if the sample run cannot be written or the window cannot be opened.
pub fn run_app(paths: Vec<PathBuf>) -> Result<(), GuiError> {
    let paths = if paths.is_empty() {
        vec![sample_run_path()?]
    } else {
        paths
    };
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_title("imu-attest")
            .with_inner_size([1500.0, 950.0])
            .with_drag_and_drop(true),
        ..eframe::NativeOptions::default()
    };
    eframe::run_native(
        "imu-attest",
        options,
        Box::new(move |cc| Ok(Box::new(App::new(cc, AppOptions::new(paths))))),
    )
    .map_err(|e| GuiError::Window(e.to_string()))
}
