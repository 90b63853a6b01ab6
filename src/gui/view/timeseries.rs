//! The time-series tab: stacked plots with linked time axes and a shared cursor; each series is
//! drawn from its min/max pyramid at about two points per pixel.

use eframe::egui;
use egui_plot::{HLine, Legend, Line, LineStyle, Plot, PlotPoints, PlotUi, VLine};

use super::palette;
use crate::faults::RecordingFault;
use crate::gui::app::{RunEntry, ViewState};
use crate::gui::pipeline::{Measured, Motion, Series};

/// One plot: a title and its series (`true` = plain differentiation, drawn dashed).
type Group<'a> = (&'static str, Vec<(&'a Series, bool)>);

fn groups<'a>(measured: &'a Measured, motion: Option<&'a Motion>, with_diff: bool) -> Vec<Group<'a>> {
    let solid = |s: &'a [Series; 3]| s.iter().map(|s| (s, false)).collect::<Vec<_>>();
    let mut out: Vec<Group<'a>> = vec![("angles, rad", solid(&measured.angles))];
    if let Some(m) = motion {
        for (present, title, observer, diff) in [
            (
                measured.gyro.is_some(),
                "gyro input ω, rad/s",
                &m.body_rate,
                &m.body_rate_differentiated,
            ),
            (
                measured.accel.is_some(),
                "accel input f, m/s²",
                &m.specific_force,
                &m.specific_force_differentiated,
            ),
        ] {
            if present {
                let mut series = solid(observer);
                if with_diff {
                    series.extend(diff.iter().map(|s| (s, true)));
                }
                out.push((title, series));
            }
        }
    }
    if let Some(g) = &measured.gyro {
        out.push(("gyro outputs, rad/s", solid(g)));
    }
    if let Some(a) = &measured.accel {
        out.push(("accel outputs, m/s²", solid(a)));
    }
    out
}

/// Draws the tab for `run`.
pub fn show(ui: &mut egui::Ui, run: &RunEntry, view: &mut ViewState) {
    let Some(measured) = &run.measured else {
        ui.label("loading…");
        return;
    };
    ui.horizontal(|ui| {
        ui.checkbox(
            &mut view.show_differentiated,
            "overlay plain numerical differentiation (dashed)",
        );
        if run.motion.is_none() {
            ui.spinner();
            ui.label("observer running…");
        }
    });
    let groups = groups(measured, run.motion.as_deref(), view.show_differentiated);
    let faults: &[RecordingFault] = run.summary.as_ref().map_or(&[], |s| &s.recording_faults);
    let [first, ..] = &measured.angles;
    let (t_start, t_end) = (first.t0, first.t_end().max(first.t0 + first.dt));
    // Per run: switching runs shows the new run's whole time span, not the last one's zoom.
    let link = egui::Id::unique(("time-series-link", run.id));
    let readout_height = 22.0;
    let height = ((ui.available_height() - readout_height) / groups.len() as f32 - 4.0).max(80.0);
    let mut cursor_t = None;
    for (k, (title, series)) in groups.iter().enumerate() {
        let mut plot = Plot::new(("ts", *title, run.id))
            .height(height)
            .link_axis(link, [true, false])
            .link_cursor(link, [true, false])
            .default_x_bounds(t_start, t_end)
            // Time only: y stays fitted to the visible samples while panning and zooming.
            .allow_drag([true, false])
            .allow_zoom([true, false])
            .allow_scroll(false)
            .allow_boxed_zoom(false)
            .legend(Legend::default())
            .y_axis_label(*title)
            .y_axis_min_width(64.0);
        if k + 1 == groups.len() {
            plot = plot.x_axis_label("t, s");
        }
        let response = plot.show(ui, |plot| {
            let bounds = plot.plot_bounds();
            let (lo, hi) = (bounds.min()[0], bounds.max()[0]);
            let (lo, hi) = if lo.is_finite() && hi.is_finite() && hi > lo {
                (lo, hi)
            } else {
                (t_start, t_end)
            };
            let budget = (2.0 * plot.response().rect.width()).max(64.0) as usize;
            for (n, (s, diff)) in series.iter().enumerate() {
                let mut points = Vec::new();
                s.decimate(lo, hi, budget, &mut points);
                let style = if *diff {
                    LineStyle::dashed_dense()
                } else {
                    LineStyle::Solid
                };
                plot.line(
                    Line::new(s.name.as_str(), PlotPoints::Owned(points))
                        .color(palette(n % 3))
                        .style(style),
                );
            }
            mark_faults(plot, series, faults);
            let cursor = plot
                .response()
                .hovered()
                .then(|| plot.pointer_coordinate())
                .flatten();
            (cursor.map(|p| p.x), lo, hi)
        });
        let (cursor, lo, hi) = response.inner;
        // Pan and zoom move the bounds after the points were chosen: draw once more for them.
        let shown = response.transform.bounds();
        if (shown.min()[0] - lo).abs() > 1e-9 * (hi - lo) || (shown.max()[0] - hi).abs() > 1e-9 * (hi - lo) {
            ui.ctx().request_repaint();
        }
        cursor_t = cursor_t.or(cursor);
    }
    readout(ui, &groups, cursor_t);
}

/// The recording faults of the plot's channels: a red line where each starts (named in the
/// legend), and a clipping's level.
fn mark_faults(plot: &mut PlotUi<'_>, series: &[(&Series, bool)], faults: &[RecordingFault]) {
    let red = egui::Color32::from_rgb(220, 40, 40);
    for fault in faults {
        let channel = fault.channel().name();
        if !series.iter().any(|(s, diff)| !diff && s.name == channel) {
            continue;
        }
        plot.vline(
            VLine::new(fault.short_label(), fault.time_s())
                .color(red)
                .style(LineStyle::dashed_loose()),
        );
        if let RecordingFault::Clipping { level, .. } = fault {
            plot.hline(HLine::new(fault.short_label(), *level).color(red));
        }
    }
}

fn readout(ui: &mut egui::Ui, groups: &[Group<'_>], t: Option<f64>) {
    let Some(t) = t else {
        ui.weak("hover a plot for a read-out; drag to pan, ctrl+scroll to zoom time, double-click to reset");
        return;
    };
    let values: Vec<String> = groups
        .iter()
        .flat_map(|(_, series)| series.iter())
        .filter_map(|(s, _)| s.value_at(t).map(|v| format!("{} {v:+.4e}", s.name)))
        .collect();
    ui.label(format!("t = {t:.4} s   {}", values.join("   ")));
}
