//! The spectra tab: log-log PSD of every channel of a block, the CSD matrix at one frequency and
//! the frequency-by-pair grid, as magnitude or coherence.

use eframe::egui::{self, TextureHandle};
use egui_plot::{GridMark, Legend, Line, Plot, PlotPoints, VLine};

use super::heatmap;
use super::palette;
use crate::gui::app::{HeatmapMode, RunEntry, ViewState};
use crate::gui::pipeline::BlockSpectra;

/// Draws the tab for `run`; `texture` is the pair grid of the block shown, when ready.
pub fn show(ui: &mut egui::Ui, run: &RunEntry, view: &mut ViewState, texture: Option<&TextureHandle>) {
    let Some(spectra) = run.spectra.as_ref() else {
        if let Some(e) = &run.spectra.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        } else {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("computing observer and spectra…");
            });
        }
        return;
    };
    let block = spectra
        .blocks
        .iter()
        .find(|b| b.block == view.spectra_block)
        .or(spectra.blocks.first());
    let Some(block) = block else {
        ui.label("no block in this run");
        return;
    };
    controls(
        ui,
        run,
        view,
        spectra.blocks.iter().map(|b| b.block).collect(),
        block,
    );
    let df = block.matrix.df_hz();
    let bin = ((view.heatmap_frequency_hz / df).round() as usize).clamp(1, block.matrix.n_bins() - 1);
    let w = &spectra.welch;
    ui.label(format!(
        "Welch: {} segments of {} samples ({:.3} Hz resolution), overlap {:.0} %, {:?} window, detrend {:?}",
        block.matrix.n_averages,
        w.segment_len,
        df,
        w.overlap * 100.0,
        w.window,
        w.detrend
    ));
    let psd_height = (ui.available_height() * 0.45).max(160.0);
    let band_hz = run
        .identification
        .as_ref()
        .and_then(|id| id.model.blocks.get(block.block.name()))
        .map(|m| m.band_hz);
    psd_plot(
        ui,
        block,
        psd_height,
        block.matrix.frequency_hz[bin],
        band_hz,
        run.id,
    );
    ui.separator();
    let range = super::colormap::value_range(block, view.heatmap_mode);
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.strong(heatmap::matrix_title(
                view.heatmap_mode,
                block.matrix.frequency_hz[bin],
            ));
            heatmap::matrix(ui, block, bin, view.heatmap_mode);
            heatmap::legend(
                ui,
                heatmap::matrix_range(block, bin, view.heatmap_mode),
                view.heatmap_mode,
            );
        });
        ui.separator();
        ui.vertical(|ui| {
            ui.strong(match view.heatmap_mode {
                HeatmapMode::Magnitude => "frequency × channel pair: |S_ij|, dB",
                HeatmapMode::Coherence => "frequency × channel pair: coherence",
            });
            if let Some(texture) = texture {
                heatmap::pair_grid(ui, block, view.heatmap_mode, texture);
            }
            heatmap::legend(ui, range, view.heatmap_mode);
        });
    });
}

fn controls(
    ui: &mut egui::Ui,
    run: &RunEntry,
    view: &mut ViewState,
    blocks: Vec<crate::block::Block>,
    block: &BlockSpectra,
) {
    // Wrapped at the central view's width: a wide results panel must not hide these controls.
    ui.horizontal_wrapped(|ui| {
        for b in blocks {
            ui.selectable_value(&mut view.spectra_block, b, b.name());
        }
        ui.separator();
        ui.radio_value(
            &mut view.heatmap_mode,
            HeatmapMode::Magnitude,
            "magnitude |S| (dB)",
        );
        ui.radio_value(&mut view.heatmap_mode, HeatmapMode::Coherence, "coherence");
        ui.separator();
        let f = &block.matrix.frequency_hz;
        let (low, high) = (f.get(1).copied().unwrap_or(0.1), f.last().copied().unwrap_or(1.0));
        ui.add(
            egui::Slider::new(&mut view.heatmap_frequency_hz, low..=high)
                .logarithmic(true)
                .text("Hz"),
        );
        if run.busy() {
            ui.spinner();
            ui.label("recomputing…");
        }
        if let Some(e) = &run.spectra.error {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!("current settings: {e} (showing last good)"),
            );
        }
    });
}

fn log_label(mark: GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let v = 10f64.powf(mark.value);
    if (mark.value - mark.value.round()).abs() < 1e-9 {
        format!("{v:.0e}")
    } else {
        format!("{v:.2e}")
    }
}

fn psd_plot(
    ui: &mut egui::Ui,
    block: &BlockSpectra,
    height: f32,
    marker_hz: f64,
    band_hz: Option<[f64; 2]>,
    run: crate::gui::pipeline::RunId,
) {
    Plot::new(("psd", block.block, run))
        .height(height)
        .legend(Legend::default())
        .x_axis_label("frequency, Hz (log)")
        .y_axis_label("PSD, unit²/Hz (log)")
        .x_axis_formatter(log_label)
        .y_axis_formatter(log_label)
        .label_formatter(|hover| {
            let p = match hover {
                egui_plot::HoverPosition::NearDataPoint { position, .. }
                | egui_plot::HoverPosition::Elsewhere { position } => position,
            };
            Some(format!(
                "{:.3} Hz\n{:.3e} unit²/Hz",
                10f64.powf(p.x),
                10f64.powf(p.y)
            ))
        })
        .show(ui, |plot| {
            for (k, points) in block.psd_log.iter().enumerate() {
                let name = block.channels[k];
                plot.line(
                    Line::new(name, PlotPoints::Borrowed(points))
                        .color(palette(k))
                        .width(1.2),
                );
            }
            plot.add(VLine::new("heatmap frequency", marker_hz.log10()).color(egui::Color32::GRAY));
            // The identification's band, as on the Bode tab.
            for edge in band_hz.into_iter().flatten().filter(|f| *f > 0.0) {
                plot.vline(
                    VLine::new("band used", edge.log10())
                        .color(egui::Color32::from_gray(150))
                        .style(egui_plot::LineStyle::dashed_loose()),
                );
            }
        });
}
