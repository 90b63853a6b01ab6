//! Exports: the selected run's model JSON (contract section 4) and the current view as PNG, both
//! written atomically and never over an input; failures go to the error panel.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};

use eframe::egui::{self, ColorImage};

use super::App;
use super::ErrorTopic;
use super::PathPurpose;
use crate::output::{OutputError, ensure_not_input, write_atomic};
use crate::run::sidecar_path;

/// Screenshot requests and the images egui hands back.
pub(super) struct Screenshots {
    /// Where the next screenshot goes (set by the command, sent to egui in `logic`).
    pub pending: Option<PathBuf>,
    tx: Sender<(PathBuf, Arc<ColorImage>)>,
    rx: Receiver<(PathBuf, Arc<ColorImage>)>,
}

impl Default for Screenshots {
    fn default() -> Self {
        let (tx, rx) = channel();
        Self {
            pending: None,
            tx,
            rx,
        }
    }
}

/// Writes `image` as an 8-bit RGBA PNG, atomically.
///
/// # Errors
/// [`OutputError`] when the file cannot be written (nothing is left under `path`).
pub fn write_png(path: &Path, image: &ColorImage) -> Result<(), OutputError> {
    write_atomic(path, |w| {
        let [width, height] = image.size;
        let mut encoder = png::Encoder::new(&mut *w, width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(image.as_raw())
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)?;
        w.flush()
    })
}

impl App {
    /// Every file the loaded runs were read from (runs and sidecars): no export goes over one.
    fn input_files(&self) -> Vec<PathBuf> {
        self.runs
            .iter()
            .flat_map(|r| [r.path.clone(), sidecar_path(&r.path)])
            .collect()
    }

    /// Opens the typed-path window for `purpose` (with `note` saying why, for a fallback).
    pub(super) fn prompt_path(&mut self, purpose: PathPurpose, note: Option<&str>) {
        self.prompt = Some(super::prompt::PathPrompt {
            purpose,
            text: String::new(),
            note: note.map(str::to_owned),
        });
    }

    /// Writes the selected run's model to `path`.
    pub(super) fn export_model(&mut self, path: &Path) {
        let outcome = self.try_export_model(path);
        match outcome {
            Ok(()) => self.status = Some(format!("writing the model to {}…", path.display())),
            Err(e) => self.errors.push(ErrorTopic::Export, format!("export: {e}")),
        }
    }

    /// Checks the export and sends it to the worker, which adds the noise terms (they need the
    /// whole record's residual) and writes the file as `identify` does.
    fn try_export_model(&mut self, path: &Path) -> Result<(), String> {
        let run = self.selected().ok_or("no run selected")?;
        let id = run
            .identification
            .as_ref()
            .ok_or_else(|| format!("{} is not identified yet", run.name()))?;
        id.model
            .check_finite()
            .map_err(|e| format!("model not written: {e}"))?;
        let run_id = run.id;
        ensure_not_input(path, &self.input_files()).map_err(|e| e.to_string())?;
        let generation = self.next_generation();
        self.worker.submit(crate::gui::pipeline::Job {
            run: run_id,
            generation,
            kind: crate::gui::pipeline::JobKind::ExportModel {
                path: path.to_path_buf(),
            },
        });
        Ok(())
    }

    /// Asks the worker for the results table of every loaded run (one row per run and block: K,
    /// sigmas, ppm, mrad, delay, noise terms, warnings), as `batch` writes it.
    pub(super) fn export_results(&mut self, path: PathBuf) {
        if let Err(e) = ensure_not_input(&path, &self.input_files()) {
            self.errors.push(ErrorTopic::Export, format!("export: {e}"));
            return;
        }
        let runs: Vec<_> = self.runs.iter().filter(|r| r.loaded()).map(|r| r.id).collect();
        let Some(&first) = runs.first() else {
            self.errors
                .push(ErrorTopic::Export, "export: no loaded run".to_owned());
            return;
        };
        let generation = self.next_generation();
        self.status = Some(format!("writing the results table to {}…", path.display()));
        self.worker.submit(crate::gui::pipeline::Job {
            run: first,
            generation,
            kind: crate::gui::pipeline::JobKind::ExportResults { runs, path },
        });
    }

    /// Asks the worker for the selected run's certificate at `path` (it identifies, computes the
    /// noise terms and diagnoses on its cached session: seconds on a long run).
    pub(super) fn export_report(&mut self, path: PathBuf) {
        if let Err(e) = ensure_not_input(&path, &self.input_files()) {
            self.errors.push(ErrorTopic::Export, format!("export: {e}"));
            return;
        }
        let Some(id) = self.selected().filter(|r| r.loaded()).map(|r| r.id) else {
            self.errors
                .push(ErrorTopic::Export, "export: no loaded run selected".to_owned());
            return;
        };
        let generation = self.next_generation();
        self.status = Some(format!("writing the report to {}…", path.display()));
        self.worker.submit(crate::gui::pipeline::Job {
            run: id,
            generation,
            kind: crate::gui::pipeline::JobKind::Report {
                settings: Box::new(self.prefs.settings.clone()),
                path,
            },
        });
    }

    /// Sends a pending screenshot request to egui and writes the images it has returned.
    pub(super) fn screenshot_pass(&mut self, ctx: &egui::Context) {
        if let Some(path) = self.screenshots.pending.take() {
            let tx = self.screenshots.tx.clone();
            let waker = ctx.clone();
            ctx.request_screenshot(move |image| {
                // The app is gone when this fails; nothing left to save.
                let _ = tx.send((path, image));
                waker.request_repaint();
            });
        }
        while let Ok((path, image)) = self.screenshots.rx.try_recv() {
            match ensure_not_input(&path, &self.input_files()).and_then(|()| write_png(&path, &image)) {
                Ok(()) => self.status = Some(format!("view written to {}", path.display())),
                Err(e) => self.errors.push(ErrorTopic::Export, format!("export: {e}")),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::write_png;
    use eframe::egui::{Color32, ColorImage};

    #[test]
    fn a_png_reads_back_with_its_size_and_pixels() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("view.png");
        let mut image = ColorImage::new([3, 2], vec![Color32::BLACK; 6]);
        image[(2, 1)] = Color32::from_rgb(200, 10, 30);
        write_png(&path, &image).expect("written");
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).expect("open")));
        let mut reader = decoder.read_info().expect("a PNG");
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut buf).expect("frame");
        assert_eq!((info.width, info.height), (3, 2));
        let last = &buf[(5 * 4)..(6 * 4)];
        assert_eq!(last, [200, 10, 30, 255]);
    }
}
