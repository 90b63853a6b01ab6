//! Helpers shared by the app's kittest tests (AccessKit, no GPU): one way to build the app.

use std::path::PathBuf;

use egui_kittest::Harness;
use imu_attest::gui::{App, AppOptions, WorkerMode};

/// Options for `paths` with the worker in `mode`, without persisted settings.
pub fn options(paths: Vec<PathBuf>, mode: WorkerMode) -> AppOptions {
    AppOptions {
        mode,
        persist: false,
        ..AppOptions::new(paths)
    }
}

/// The app at 1500 x 950 with `options`, after `steps` frames.
pub fn app(options: AppOptions, steps: usize) -> Harness<'static, App> {
    let mut harness = Harness::builder()
        .with_size(eframe::egui::vec2(1500.0, 950.0))
        .build_eframe(|cc| App::new(cc, options));
    harness.run_steps(steps);
    harness
}
