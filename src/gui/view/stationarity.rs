//! The stationarity check in the results panel: the block identified on stretches of the record,
//! each stretch's delay (with ±2σ bars) and scale-factor errors against time, the whole record's
//! delay and the fitted trend. A clock that drifts shows as a sloping line of delays.

use eframe::egui;
use egui_plot::{HLine, Line, LineStyle, Plot, PlotPoints, Points};

use super::key::{self, Swatch};
use super::palette;
use crate::ident::stretches::Stationarity;
use crate::model::BlockModel;

/// The summary line, e.g. `gyro stretches: 12; delay trend +0.3 ± 0.8 ppm (no significant drift)`;
/// where the delay steps, the step and the slope its two sides share.
#[must_use]
pub fn stationarity_label(block: &str, st: &Stationarity) -> String {
    let (trend, trend_std) = st.drift();
    let step = st.delay_step.map_or_else(String::new, |s| {
        let back = s.back_between_s.map_or_else(String::new, |[a, b]| {
            format!(" and back between {a:.1} and {b:.1} s")
        });
        format!(
            "; the delay steps by {:+.2} sample periods between {:.1} and {:.1} s{back} (a stream slipped)",
            s.samples, s.between_s[0], s.between_s[1]
        )
    });
    let beside = if st.delay_step.is_some() {
        " beside the step"
    } else {
        ""
    };
    if !trend_std.is_finite() {
        let why = if st.delay_step.is_some_and(|s| s.back_between_s.is_some()) {
            "no drift is fitted beside a step that comes back"
        } else {
            "too few stretches beside the step to tell a drift"
        };
        return format!("{block} stretches: {}{step}; {why}", st.stretches.len());
    }
    format!(
        "{block} stretches: {}{}{step}; delay trend{beside} {:+.1} ± {:.1} ppm ({})",
        st.stretches.len(),
        st.segment_len
            .map(|l| format!(
                " (on segments of {l}: the record is too short for stretches at the settings' segment)"
            ))
            .unwrap_or_default(),
        trend * 1e6,
        trend_std * 1e6,
        if st.drifts() {
            "the delay drifts: the clocks of block and stand disagree"
        } else {
            "no significant drift"
        }
    )
}

/// Draws the delay and scale-factor plots of `m`'s stretches (nothing for a record too short to
/// cut).
pub fn show(ui: &mut egui::Ui, name: &str, m: &BlockModel) {
    let Some(st) = &m.stationarity else {
        ui.weak(format!(
            "{name}: record too short to cut into stretches (stationarity not checked)"
        ));
        return;
    };
    // The stretches are the identification's, without the effects accepted since.
    let extended = m.extended_by().is_some();
    let fitted_without = if extended {
        " (fitted without the accepted effects)"
    } else {
        ""
    };
    ui.label(format!("{}{fitted_without}", stationarity_label(name, st)));
    let mid = |s: &crate::ident::stretches::StretchFit| 0.5 * (s.span_s[0] + s.span_s[1]);
    let link = egui::Id::unique(("stretches", name));
    // The stretches are fitted at order 0: the whole record's delay beside them is its order-0
    // fit's. A richer model's delay leaves its poles' lag out (a 100 Hz filter's order-2 delay sat
    // 2.2 ms below every stretch, as if they all disagreed with it). So is an extended model's
    // (a gyro's mode accepted: 5.716 ms beside stretches of 5.85-5.90 fitted without it).
    let (whole_label, whole_tau_s) = match m.fit.candidates.first() {
        Some(zero) if m.order > 0 || extended => ("whole record, order 0", zero.tau_s),
        _ => ("whole record", m.tau_s),
    };
    let whole_colour = egui::Color32::GRAY;
    Plot::new(("stretch-delay", name))
        .x_grid_spacer(super::grid::nice_grid_spacer())
        .x_axis_formatter(super::grid::nice_label)
        .height(110.0)
        .link_axis(link, [true, false])
        .y_axis_label("τ, ms")
        .allow_scroll(false)
        .show(ui, |plot| {
            for s in &st.stretches {
                let (t, tau, sd) = (mid(s), s.tau_s * 1e3, 2.0 * s.tau_std_s * 1e3);
                plot.line(
                    Line::new("±2σ", PlotPoints::new(vec![[t, tau - sd], [t, tau + sd]])).color(palette(2)),
                );
            }
            let points: Vec<[f64; 2]> = st.stretches.iter().map(|s| [mid(s), s.tau_s * 1e3]).collect();
            plot.points(
                Points::new("stretch delay", PlotPoints::new(points))
                    .radius(3.0)
                    .color(palette(2)),
            );
            plot.hline(
                HLine::new(whole_label, whole_tau_s * 1e3)
                    .style(LineStyle::dashed_loose())
                    .color(whole_colour),
            );
            let n = st.stretches.len() as f64;
            let t_mean = st.stretches.iter().map(mid).sum::<f64>() / n;
            let tau_mean = st.stretches.iter().map(|s| s.tau_s).sum::<f64>() / n;
            let (Some(first), Some(last)) = (st.stretches.first(), st.stretches.last()) else {
                return;
            };
            // Where the delay steps, its two sides, each with the slope they share.
            if let Some(s) = st.delay_step {
                let slope = s.trend.map_or(0.0, |[t, _]| t);
                let side = |from: f64, to: f64, at: f64, level: f64| {
                    let y = |t: f64| [t, (level + slope * (t - at)) * 1e3];
                    PlotPoints::new(vec![y(from), y(to)])
                };
                let [a, b] = s.between_s;
                plot.line(
                    Line::new("before the step", side(first.span_s[0], a, a, s.before_s)).color(palette(3)),
                );
                // Where it comes back: the stepped delay up to there, then the first again.
                let [c, d] = s.back_between_s.unwrap_or([last.span_s[1]; 2]);
                plot.line(Line::new("after the step", side(b, c, a, s.after_s)).color(palette(4)));
                if s.back_between_s.is_some() {
                    plot.line(Line::new("back", side(d, last.span_s[1], a, s.before_s)).color(palette(3)));
                }
                return;
            }
            let line = |t: f64| [t, (tau_mean + st.tau_trend * (t - t_mean)) * 1e3];
            plot.line(
                Line::new(
                    "trend",
                    PlotPoints::new(vec![line(first.span_s[0]), line(last.span_s[1])]),
                )
                .color(palette(3)),
            );
        });
    let mut entries = vec![
        (palette(2), Swatch::DotWithBar, "stretch delay ±2σ"),
        (whole_colour, Swatch::Dashed, whole_label),
    ];
    match st.delay_step {
        Some(s) => {
            entries.push((palette(3), Swatch::Line, "before the step"));
            entries.push((palette(4), Swatch::Line, "after the step"));
            if s.back_between_s.is_some() {
                entries.push((palette(3), Swatch::Line, "back"));
            }
        }
        None => entries.push((palette(3), Swatch::Line, "trend")),
    }
    key::show(ui, &entries);
    Plot::new(("stretch-gain", name))
        .x_grid_spacer(super::grid::nice_grid_spacer())
        .x_axis_formatter(super::grid::nice_label)
        .height(110.0)
        .link_axis(link, [true, false])
        .y_axis_label("scale error, ppm")
        .x_axis_label("t, s")
        .allow_scroll(false)
        .show(ui, |plot| {
            for i in 0..3 {
                let points: Vec<[f64; 2]> = st
                    .stretches
                    .iter()
                    .map(|s| [mid(s), (s.k[i][i] - 1.0) * 1e6])
                    .collect();
                plot.line(Line::new(m.outputs[i].as_str(), PlotPoints::new(points)).color(palette(3 + i)));
            }
        });
    let outputs: Vec<_> = (0..3)
        .map(|i| (palette(3 + i), Swatch::Line, m.outputs[i].as_str()))
        .collect();
    key::show(ui, &outputs);
}
