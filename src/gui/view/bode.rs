//! The Bode tab: a 3x3 grid of `W_u` (magnitude in dB over phase in degrees, log frequency) with
//! confidence bands and the fitted structural model, then the multiple coherence and the
//! disturbance PSD matrix. The same grid overlays several runs on the Compare tab.

use eframe::egui::{self, Color32, Id};
use egui_plot::{FilledArea, GridMark, Line, LineStyle, Plot, PlotPoint, PlotPoints, PlotUi, VLine};

use super::palette;
use crate::gui::app::{RunEntry, ViewState};
use crate::gui::pipeline::BlockBode;

/// One run's curves on the grid.
pub struct BodeEntry<'a> {
    /// Legend name.
    pub label: String,
    /// The curves.
    pub bode: &'a BlockBode,
    /// Line colour.
    pub colour: Color32,
    /// Draw the confidence band and the fitted model.
    pub details: bool,
}

/// Axis labels of a `log10 f` axis, in Hz: plain numbers from 0.01 to 1e5 Hz, powers of ten
/// beyond (a plot panned or zoomed far out showed "0.00" or "inf"), nothing where `10^x` is not a
/// finite number.
#[must_use]
pub fn hz_label(mark: GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let v = 10f64.powf(mark.value);
    if !v.is_finite() || v <= 0.0 {
        String::new()
    } else if !(0.01..1e5).contains(&v) {
        format!("{v:.0e}")
    } else if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

pub(super) fn plot(id: impl egui::AsIdSalt, width: f32, height: f32, group: &str) -> Plot<'static> {
    Plot::new(id)
        .width(width)
        .height(height)
        .link_axis(Id::unique(group), [true, false])
        .link_cursor(Id::unique(group), [true, false])
        .x_axis_formatter(hz_label)
        .y_grid_spacer(super::grid::nice_grid_spacer())
        .y_axis_formatter(super::grid::nice_label)
        .allow_scroll(false)
}

/// Draws the 3x3 `W_u` grid for `entries` (all of the same block): magnitude in dB, or with
/// `deviation` the deviation from K (ppm on the diagonal, mrad off it), over the phase. Returns
/// the read-out of the first entry at the element and frequency under the pointer.
pub fn grid(ui: &mut egui::Ui, entries: &[BodeEntry<'_>], group: &str, deviation: bool) -> Option<String> {
    let first = entries.first()?;
    let width = ((ui.available_width() - 24.0) / 3.0).max(120.0);
    let height = (width * 0.42).clamp(80.0, 170.0);
    // The key above the grid, not inside a plot (a legend in a plot this small covers its data).
    ui.horizontal_wrapped(|ui| {
        for entry in entries {
            ui.colored_label(entry.colour, format!("— {}", entry.label));
        }
        ui.weak(if entries.iter().any(|e| e.details) {
            "white dashed: fitted model; shaded: ±2σ; grey dashed: band used"
        } else {
            "grey dashed: band used"
        });
    });
    let mut hovered = None;
    egui::Grid::new((group, "bode"))
        .spacing([6.0, 6.0])
        .show(ui, |ui| {
            for i in 0..3 {
                for j in 0..3 {
                    ui.vertical(|ui| {
                        ui.strong(format!("{} from {}", first.bode.outputs[i], first.bode.inputs[j]));
                        let e = 3 * i + j;
                        if let Some(x) = cell(ui, entries, e, [width, height], group, deviation) {
                            hovered = Some((e, x));
                        }
                    });
                }
                ui.end_row();
            }
        });
    let (e, x) = hovered?;
    readout(first.bode, e, x)
}

/// The read-out of element `e` of `bode` at the band bin nearest `log10 f = x`: the estimate's
/// gain, phase and deviation from K with its ±2σ, and the fitted model's.
#[must_use]
pub fn readout(bode: &BlockBode, e: usize, x: f64) -> Option<String> {
    let el = bode.elements.get(e)?;
    let k =
        (0..el.log_f.len()).min_by(|&a, &b| (el.log_f[a] - x).abs().total_cmp(&(el.log_f[b] - x).abs()))?;
    let (i, j) = (e / 3, e % 3);
    let unit = el.deviation_unit;
    let digits = if unit == "ppm" { 0 } else { 3 };
    let half = 0.5 * (el.deviation_band.1[k] - el.deviation_band.0[k]);
    Some(format!(
        "read-out: {} from {} at {:.3} Hz: {:+.3} dB, {:+.2}°, deviation from K {:+.digits$} ± {:.digits$} {unit} \
         (model {:+.3} dB, {:+.2}°, {:+.digits$} {unit})",
        bode.outputs[i],
        bode.inputs[j],
        10f64.powf(el.log_f[k]),
        el.magnitude_db[k].y,
        el.phase_deg[k].y,
        el.deviation[k].y,
        half,
        el.model_magnitude_db[k].y,
        el.model_phase_deg[k].y,
        el.model_deviation[k].y,
    ))
}

/// The curves of one quantity: the estimate, its band, the fitted model.
#[derive(Clone, Copy)]
struct Curves<'a> {
    estimate: &'a [PlotPoint],
    band: &'a (Vec<f64>, Vec<f64>),
    model: &'a [PlotPoint],
}

fn draw<'a>(p: &mut PlotUi<'a>, entry: &BodeEntry<'_>, log_f: &'a [f64], c: Curves<'a>) {
    if entry.details {
        p.add(
            FilledArea::new("±2σ", log_f, &c.band.0, &c.band.1).fill_color(entry.colour.gamma_multiply(0.25)),
        );
        p.line(
            Line::new("fitted model", PlotPoints::Borrowed(c.model))
                .color(Color32::WHITE)
                .style(LineStyle::dashed_dense())
                .width(1.2),
        );
    }
    p.line(
        Line::new(entry.label.clone(), PlotPoints::Borrowed(c.estimate))
            .color(entry.colour)
            .width(1.4),
    );
}

/// Dashed vertical lines at the band's edges (log10 frequency axis).
pub(super) fn mark_band(p: &mut PlotUi<'_>, band_hz: [f64; 2]) {
    for edge in band_hz {
        if edge > 0.0 {
            p.vline(
                VLine::new("band", edge.log10())
                    .color(Color32::from_gray(150))
                    .style(LineStyle::dashed_loose()),
            );
        }
    }
}

/// One element's magnitude (or deviation) and phase plots; the `log10 f` under the pointer.
fn cell(
    ui: &mut egui::Ui,
    entries: &[BodeEntry<'_>],
    e: usize,
    [width, height]: [f32; 2],
    group: &str,
    deviation: bool,
) -> Option<f64> {
    let unit = entries.first().map_or("dB", |f| {
        if deviation {
            f.bode.elements[e].deviation_unit
        } else {
            "dB"
        }
    });
    let mag = plot((group, "mag", e, deviation), width, height, group).y_axis_label(unit);
    let hovered_mag = mag
        .show(ui, |p| {
            if let Some(first) = entries.first() {
                mark_band(p, first.bode.band_hz);
            }
            for entry in entries {
                let el = &entry.bode.elements[e];
                let curves = if deviation {
                    Curves {
                        estimate: &el.deviation,
                        band: &el.deviation_band,
                        model: &el.model_deviation,
                    }
                } else {
                    Curves {
                        estimate: &el.magnitude_db,
                        band: &el.magnitude_band_db,
                        model: &el.model_magnitude_db,
                    }
                };
                draw(p, entry, &el.log_f, curves);
            }
            pointer_x(p)
        })
        .inner;
    let hovered_phase = plot((group, "phase", e), width, height * 0.6, group)
        .y_axis_label("deg")
        .show(ui, |p| {
            for entry in entries {
                let el = &entry.bode.elements[e];
                let curves = Curves {
                    estimate: &el.phase_deg,
                    band: &el.phase_band_deg,
                    model: &el.model_phase_deg,
                };
                draw(p, entry, &el.log_f, curves);
            }
            pointer_x(p)
        })
        .inner;
    hovered_mag.or(hovered_phase)
}

/// The `x` under the pointer when it hovers the plot.
fn pointer_x(p: &PlotUi<'_>) -> Option<f64> {
    p.response()
        .hovered()
        .then(|| p.pointer_coordinate())
        .flatten()
        .map(|c| c.x)
}

/// The Bode tab for `run`.
pub fn show(ui: &mut egui::Ui, run: &RunEntry, view: &mut ViewState) {
    let Some(id) = run.identification.as_ref() else {
        if let Some(e) = &run.identification.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        } else {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("identifying…");
            });
        }
        return;
    };
    ui.horizontal(|ui| {
        for b in &id.bode {
            ui.selectable_value(&mut view.bode_block, b.block, b.block.name());
        }
        ui.separator();
        ui.label("W_u: estimate (colour), ±2σ band (shaded), fitted structural model (dashed)");
        ui.checkbox(&mut view.bode_deviation, "deviation from K")
            .on_hover_text(
                "instead of the gain in dB: Re(W e^(jωτ)) - K, the in-phase part with the model's \
                 delay taken out, in ppm on the diagonal (scale factor) and mrad off it \
                 (misalignment), so that errors of a few hundred ppm show",
            );
        if run.busy() {
            ui.spinner();
            ui.label("recomputing…");
        }
    });
    // A block the run could not identify has no curves: said, not silently replaced.
    for name in id.model.refused_blocks.keys() {
        ui.colored_label(
            ui.visuals().error_fg_color,
            format!("{name} block not identified (Results says why): no W_u to draw"),
        );
    }
    let Some(bode) = id
        .bode
        .iter()
        .find(|b| b.block == view.bode_block)
        .or(id.bode.first())
    else {
        return;
    };
    // One line kept for the read-out, so the grid does not jump when it appears.
    ui.label(
        view.bode_readout
            .as_deref()
            .unwrap_or("read-out: hover a plot for the gain, phase and deviation from K at a frequency"),
    );
    egui::ScrollArea::vertical().show(ui, |ui| {
        let entry = BodeEntry {
            label: run.name(),
            bode,
            colour: palette(2),
            details: true,
        };
        // Per run: each run keeps its own zoom, and a run shown first starts from its own extent.
        let readout = grid(ui, &[entry], &format!("bode-{}", run.id), view.bode_deviation);
        if readout != view.bode_readout {
            view.bode_readout = readout;
            ui.ctx().request_repaint();
        }
        ui.separator();
        super::disturbance::coherence_and_noise(ui, bode);
    });
}

#[cfg(test)]
mod tests {
    use super::hz_label;
    use egui_plot::GridMark;

    #[test]
    fn frequency_labels_stay_readable_far_out() {
        let label = |value: f64| {
            hz_label(
                GridMark {
                    value,
                    step_size: 1.0,
                },
                &(0.0..=1.0),
            )
        };
        assert_eq!(label(0.0), "1.0");
        assert_eq!(label(2.0), "100");
        assert_eq!(label(-1.0), "0.10");
        assert_eq!(label(-5.0), "1e-5");
        assert_eq!(label(7.0), "1e7");
        assert_eq!(label(400.0), "", "10^400 is not a number to show");
    }
}
