//! The time-series tab: stacked plots with linked time axes and a shared cursor; each series is
//! drawn from its min/max pyramid at about two points per pixel. Shift+drag selects the stretch
//! of the record to analyse (`span_s`, sent as new settings); the analysed stretch is shaded.

use eframe::egui;
use egui_plot::{HLine, Line, LineStyle, Plot, PlotPoints, PlotUi, Span, VLine};

use super::palette;
use crate::faults::RecordingFault;
use crate::gui::app::{Command, RunEntry, ViewState};
use crate::gui::pipeline::{Measured, Motion, Series};
use crate::ident::settings::Settings;

/// One plot: a title and its series (`true` = plain differentiation, drawn dashed).
pub type Group<'a> = (&'static str, Vec<(&'a Series, bool)>);

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

/// Fewest samples of a stretch selected by dragging (a click with shift held selects nothing).
const MIN_SPAN_SAMPLES: f64 = 16.0;

/// The stretch a drag from `a` to `b` (s, either order) selects in a record from `start` to
/// `end` sampled every `dt`: clamped to the record, `None` when shorter than
/// [`MIN_SPAN_SAMPLES`] samples or not finite.
#[must_use]
pub fn dragged_span(a: f64, b: f64, start: f64, end: f64, dt: f64) -> Option<[f64; 2]> {
    let (lo, hi) = (a.min(b).max(start), a.max(b).min(end));
    (lo.is_finite() && hi.is_finite() && hi - lo >= MIN_SPAN_SAMPLES * dt).then_some([lo, hi])
}

/// What one plot saw of a selecting drag.
#[derive(Clone, Copy)]
enum DragEvent {
    Start(f64),
    Move(f64),
    Stop,
}

/// Draws the tab for `run`; a shift+drag over a plot sends the selected stretch as new
/// `settings` (`span_s`).
pub fn show(
    ui: &mut egui::Ui,
    run: &RunEntry,
    view: &mut ViewState,
    settings: &Settings,
    commands: &mut Vec<Command>,
) {
    let Some(measured) = run.measured() else {
        ui.label("loading…");
        return;
    };
    ui.horizontal(|ui| {
        ui.checkbox(
            &mut view.show_differentiated,
            "overlay plain numerical differentiation (dashed)",
        );
        if let Some(e) = &run.motion.error {
            ui.colored_label(ui.visuals().error_fg_color, format!("observer failed: {e}"));
        } else if run.motion.is_none() {
            ui.spinner();
            ui.label("observer running…");
        }
    });
    let groups = groups(
        measured,
        run.motion.as_ref().map(AsRef::as_ref),
        view.show_differentiated,
    );
    let faults: &[RecordingFault] = run.summary().map_or(&[], |s| &s.recording_faults);
    let [first, ..] = &measured.angles;
    let (t_start, t_end) = (first.t0, first.t_end().max(first.t0 + first.dt));
    // Per run: switching runs shows the new run's whole time span, not the last one's zoom.
    let link = egui::Id::unique(("time-series-link", run.id));
    let readout_height = 22.0;
    // Each plot's key is a row above it (a legend inside covered the traces' top right).
    let key_height = 18.0;
    let height =
        ((ui.available_height() - readout_height) / groups.len() as f32 - 4.0 - key_height).max(80.0);
    let mut cursor_t = None;
    let mut drag = None;
    // Shift held (or a selection under way): a drag selects a stretch instead of panning.
    let selecting = view.span_drag.is_some() || ui.input(|i| i.modifiers.shift);
    for (k, (title, series)) in groups.iter().enumerate() {
        let first_plot = k == 0;
        key(
            ui,
            series,
            faults,
            first_plot.then_some(settings.span_s).flatten(),
            view.reference_t.is_some() && first_plot,
        );
        let mut plot = Plot::new(("ts", *title, run.id))
            .height(height)
            .link_axis(link, [true, false])
            .link_cursor(link, [true, false])
            .default_x_bounds(t_start, t_end)
            // Time only: y stays fitted to the visible samples while panning and zooming.
            .allow_drag([!selecting, false])
            .allow_zoom([true, false])
            .allow_scroll(false)
            // Right-drag: zoom to a box (both axes; the time axis of every plot follows);
            // right-click alone sets cursor A. Dragging an axis zooms that axis.
            .allow_boxed_zoom(true)
            .y_axis_label(*title)
            .y_axis_min_width(64.0)
            .x_grid_spacer(super::grid::nice_grid_spacer())
            .y_grid_spacer(super::grid::nice_grid_spacer())
            .x_axis_formatter(super::grid::nice_label)
            .y_axis_formatter(super::grid::nice_label);
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
            mark_span(plot, settings.span_s, view.span_drag);
            if let Some(t) = view.reference_t {
                plot.vline(VLine::new("cursor A", t).color(egui::Color32::from_rgb(240, 200, 80)));
            }
            let pointer = plot.pointer_coordinate().map(|p| p.x);
            let cursor = plot.response().hovered().then_some(pointer).flatten();
            let r = plot.response();
            let event = match pointer {
                Some(t) if r.drag_started() && selecting => Some(DragEvent::Start(t)),
                Some(t) if r.dragged() && view.span_drag.is_some() => Some(DragEvent::Move(t)),
                _ if r.drag_stopped() && view.span_drag.is_some() => Some(DragEvent::Stop),
                _ => None,
            };
            let placed = r.secondary_clicked().then_some(pointer).flatten();
            (cursor, lo, hi, event, placed)
        });
        let (cursor, lo, hi, event, placed) = response.inner;
        drag = drag.or(event);
        if placed.is_some() {
            view.reference_t = placed;
        }
        // Pan and zoom move the bounds after the points were chosen: draw once more for them.
        let shown = response.transform.bounds();
        if k == 0 {
            view.time_series_bounds = Some([shown.min()[0], shown.max()[0], shown.min()[1], shown.max()[1]]);
        }
        if (shown.min()[0] - lo).abs() > 1e-9 * (hi - lo) || (shown.max()[0] - hi).abs() > 1e-9 * (hi - lo) {
            ui.ctx().request_repaint();
        }
        cursor_t = cursor_t.or(cursor);
    }
    match (drag, view.span_drag) {
        (Some(DragEvent::Start(t)), _) => view.span_drag = Some([t, t]),
        (Some(DragEvent::Move(t)), Some([from, _])) => view.span_drag = Some([from, t]),
        (Some(DragEvent::Stop), Some([from, to])) => {
            view.span_drag = None;
            if let Some(span) = dragged_span(from, to, t_start, t_end, first.dt) {
                commands.push(Command::SetSettings(Box::new(Settings {
                    span_s: Some(span),
                    ..settings.clone()
                })));
            }
        }
        _ => {}
    }
    if ui.input(|i| i.key_pressed(egui::Key::Escape)) {
        view.reference_t = None;
    }
    ui.label(readout(&groups, cursor_t, view.reference_t));
}

/// The analysed stretch's hue: its key in full, its shading faint.
const SPAN_HUE: egui::Color32 = egui::Color32::from_rgb(90, 140, 255);
const SPAN_FILL: egui::Color32 = egui::Color32::from_rgba_unmultiplied_const(90, 140, 255, 28);

/// Recording faults: magenta, apart from every trace colour of the palette (its first is a red).
const FAULT_COLOUR: egui::Color32 = egui::Color32::from_rgb(230, 40, 200);

/// The analysed stretch (`span_s`), shaded, and a selection under way.
fn mark_span(plot: &mut PlotUi<'_>, span: Option<[f64; 2]>, dragging: Option<[f64; 2]>) {
    if let Some([from, to]) = span {
        plot.span(
            Span::new("analysed stretch", from..=to)
                .fill(SPAN_FILL)
                .border_width(1.0),
        );
    }
    if let Some([a, b]) = dragging {
        plot.span(
            Span::new("selecting", a.min(b)..=a.max(b))
                .fill(egui::Color32::from_rgba_unmultiplied(255, 190, 60, 40))
                .border_style(LineStyle::dashed_loose()),
        );
    }
}

/// The recording faults that concern the plot's channels.
fn faults_of<'f>(
    series: &[(&Series, bool)],
    faults: &'f [RecordingFault],
) -> impl Iterator<Item = &'f RecordingFault> {
    faults.iter().filter(|fault| {
        let channel = fault.channel().name();
        series.iter().any(|(s, diff)| !diff && s.name == channel)
    })
}

/// A plot's key, one row above it: each trace in its colour (dashed ones said so), the recording
/// faults marked on it in magenta, and (on the first plot only) the analysed stretch's shading
/// and cursor A.
fn key(
    ui: &mut egui::Ui,
    series: &[(&Series, bool)],
    faults: &[RecordingFault],
    span: Option<[f64; 2]>,
    cursor_a: bool,
) {
    ui.horizontal(|ui| {
        for (n, (s, diff)) in series.iter().enumerate() {
            let text = if *diff {
                format!("- - {} (differentiated)", s.name)
            } else {
                format!("— {}", s.name)
            };
            ui.colored_label(palette(n % 3), text);
        }
        for fault in faults_of(series, faults) {
            ui.colored_label(FAULT_COLOUR, fault.short_label());
        }
        if let Some(span) = span {
            ui.colored_label(SPAN_HUE, span_key(span));
        }
        if cursor_a {
            ui.colored_label(egui::Color32::from_rgb(240, 200, 80), "| cursor A");
        }
    });
}

/// The key's words for the shaded stretch.
#[must_use]
pub fn span_key(span: [f64; 2]) -> String {
    format!("shaded: analysed stretch {:.2}-{:.2} s", span[0], span[1])
}

/// The recording faults of the plot's channels: a magenta line where each starts (named in the
/// key above the plot), and a clipping's level.
fn mark_faults(plot: &mut PlotUi<'_>, series: &[(&Series, bool)], faults: &[RecordingFault]) {
    let colour = FAULT_COLOUR;
    for fault in faults_of(series, faults) {
        plot.vline(
            VLine::new(fault.short_label(), fault.time_s())
                .color(colour)
                .style(LineStyle::dashed_loose()),
        );
        if let RecordingFault::Clipping { level, .. } = fault {
            plot.hline(HLine::new(fault.short_label(), *level).color(colour));
        }
    }
}

/// The read-out line: the values at the hovered time `t`, and with a reference cursor A the time
/// since it and each value's change from it.
#[must_use]
pub fn readout(groups: &[Group<'_>], t: Option<f64>, reference: Option<f64>) -> String {
    let series = || groups.iter().flat_map(|(_, series)| series.iter());
    match (t, reference) {
        (None, None) => {
            "hover a plot for a read-out; drag to pan, ctrl+scroll to zoom time, double-click to \
             reset; shift+drag to analyse only that stretch; right-click to set cursor A, right-drag to \
             zoom to a box, drag an axis to zoom it"
                .to_owned()
        }
        (None, Some(a)) => {
            let values: Vec<String> = series()
                .filter_map(|(s, _)| s.value_at(a).map(|v| format!("{} {v:+.4e}", s.name)))
                .collect();
            format!(
                "cursor A at t = {a:.4} s   {}   (hover for the differences; right-click moves A, Esc clears it)",
                values.join("   ")
            )
        }
        (Some(t), None) => {
            let values: Vec<String> = series()
                .filter_map(|(s, _)| s.value_at(t).map(|v| format!("{} {v:+.4e}", s.name)))
                .collect();
            format!("t = {t:.4} s   {}", values.join("   "))
        }
        (Some(t), Some(a)) => {
            let values: Vec<String> = series()
                .filter_map(|(s, _)| {
                    let (v, va) = (s.value_at(t)?, s.value_at(a)?);
                    Some(format!("{} {v:+.4e} (Δ {:+.4e})", s.name, v - va))
                })
                .collect();
            format!(
                "t = {t:.4} s, Δt from A = {:+.4} s   {}",
                t - a,
                values.join("   ")
            )
        }
    }
}
