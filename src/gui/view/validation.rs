//! The Validation tab: a model's predicted outputs over the measured ones in time, the residual
//! beneath, and the fit in percent per channel (`crate::model::validation`), for the selected run
//! with its own model or another loaded run's.

use eframe::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints};

use super::grid::{nice_grid_spacer, nice_label};
use super::palette;
use crate::block::Block;
use crate::gui::app::{RunEntry, ViewState};
use crate::gui::pipeline::Validated;

/// The line saying how well channel `i` is predicted, e.g.
/// `gx: fit 97.31 % (model of cruise.csv.gz)`.
#[must_use]
pub fn fit_label(v: &Validated, i: usize) -> String {
    let name = crate::ident::signals::channel_names(v.key.block).1[i];
    format!(
        "{name}: fit {:.2} % (model of {})",
        v.fit_percent[i], v.model_file
    )
}

/// Draws the tab for `run`, choosing among `runs` for the model.
pub fn show(ui: &mut egui::Ui, run: &RunEntry, runs: &[RunEntry], view: &mut ViewState) {
    let blocks = run.summary().map_or_else(Vec::new, |s| s.blocks.clone());
    if !blocks.contains(&view.bode_block)
        && let Some(&first) = blocks.first()
    {
        view.bode_block = first;
    }
    ui.horizontal(|ui| {
        for b in Block::BOTH {
            if blocks.contains(&b) {
                ui.selectable_value(&mut view.bode_block, b, b.name());
            }
        }
        ui.separator();
        let current = view.validation_model.unwrap_or(run.id);
        let name_of = |id| {
            runs.iter()
                .find(|r| r.id == id)
                .map_or_else(String::new, RunEntry::name)
        };
        egui::ComboBox::from_label("model from")
            .selected_text(format!("model of {}", name_of(current)))
            .show_ui(ui, |ui| {
                for r in runs.iter().filter(|r| r.identification.is_some()) {
                    let pick = if r.id == run.id { None } else { Some(r.id) };
                    ui.selectable_value(&mut view.validation_model, pick, format!("model of {}", r.name()));
                }
            });
        if run.validation.running() {
            ui.spinner();
        }
    });
    let model_run = runs
        .iter()
        .find(|r| r.id == view.validation_model.unwrap_or(run.id));
    if let Some(m) = model_run.and_then(|r| r.identification.as_ref())
        && m.block_model(view.bode_block).is_none()
    {
        let block = view.bode_block.name();
        let why = if m.model.refused_blocks.contains_key(block) {
            "its run could not identify it (Results says why)"
        } else {
            "its run has no such block"
        };
        ui.colored_label(
            ui.visuals().error_fg_color,
            format!("no model of the {block} block to predict with: {why}"),
        );
        return;
    }
    let Some(v) = run.validation.as_ref() else {
        ui.weak(if run.identification.is_none() {
            "waiting for the identification"
        } else {
            "predicting the outputs…"
        });
        return;
    };
    if v.key.block != view.bode_block {
        ui.weak("predicting the outputs…");
        return;
    }
    ui.label(format!(
        "the model driven by this run's inputs (from the angles) against the measured outputs; \
         both low-passed at the model's band top {:.2} Hz, means removed; fit = 100 (1 - |y - ŷ| / |y|)",
        v.band_hz[1]
    ));
    let link = egui::Id::unique(("validation-link", run.id));
    let height = ((ui.available_height() - 3.0 * 22.0) / 3.0 - 4.0).max(90.0);
    for (i, channel) in v.channels.iter().enumerate() {
        ui.strong(fit_label(v, i));
        let [measured, predicted, residual] = channel;
        Plot::new(("validation", run.id, i))
            .height(height)
            .link_axis(link, [true, false])
            .link_cursor(link, [true, false])
            .default_x_bounds(measured.t0, measured.t_end())
            .allow_drag([true, false])
            .allow_zoom([true, false])
            .allow_scroll(false)
            .x_grid_spacer(nice_grid_spacer())
            .y_grid_spacer(nice_grid_spacer())
            .x_axis_formatter(nice_label)
            .y_axis_formatter(nice_label)
            .legend(Legend::default())
            .show(ui, |plot| {
                let bounds = plot.plot_bounds();
                let (lo, hi) = (bounds.min()[0], bounds.max()[0]);
                let (lo, hi) = if lo.is_finite() && hi > lo {
                    (lo, hi)
                } else {
                    (measured.t0, measured.t_end())
                };
                let budget = (2.0 * plot.response().rect.width()).max(64.0) as usize;
                for (series, colour) in [
                    (measured, egui::Color32::from_gray(170)),
                    (predicted, palette(2)),
                    (residual, palette(0)),
                ] {
                    let mut points = Vec::new();
                    series.decimate(lo, hi, budget, &mut points);
                    plot.line(Line::new(series.name.as_str(), PlotPoints::Owned(points)).color(colour));
                }
            });
    }
}
