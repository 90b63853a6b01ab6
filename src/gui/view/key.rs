//! A plot's key drawn as a row under it instead of a legend inside it: a small plot (the stretches'
//! are 110 points high) has no corner to spare, and `egui_plot`'s legend sits over the data there
//! (it hid the last stretches' delays). Each entry is a swatch in the item's colour and style and
//! the item's name as a label, so the names stay readable (and queryable) as the legend's were.

use eframe::egui::{self, Color32, Stroke, pos2, vec2};

/// How an entry's swatch is drawn, as its item is in the plot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Swatch {
    /// A solid line.
    Line,
    /// A dashed line.
    Dashed,
    /// A dot with a vertical bar through it (a point with its error bar).
    DotWithBar,
}

/// Width of a swatch, points.
const SWATCH_WIDTH: f32 = 18.0;

/// Draws the entries `(colour, style, name)` in one wrapped row.
pub fn show(ui: &mut egui::Ui, entries: &[(Color32, Swatch, &str)]) {
    ui.horizontal_wrapped(|ui| {
        for &(colour, swatch, name) in entries {
            let height = ui.text_style_height(&egui::TextStyle::Body);
            let (rect, _) = ui.allocate_exact_size(vec2(SWATCH_WIDTH, height), egui::Sense::hover());
            let painter = ui.painter_at(rect);
            let stroke = Stroke::new(2.0, colour);
            let (y, left, right) = (rect.center().y, rect.left() + 1.0, rect.right() - 1.0);
            match swatch {
                Swatch::Line => {
                    painter.line_segment([pos2(left, y), pos2(right, y)], stroke);
                }
                Swatch::Dashed => {
                    let dash = (right - left) / 5.0;
                    for i in [0.0, 2.0, 4.0] {
                        let a = left + i * dash;
                        painter.line_segment([pos2(a, y), pos2(a + dash, y)], stroke);
                    }
                }
                Swatch::DotWithBar => {
                    let x = rect.center().x;
                    let half = 0.4 * height;
                    painter.line_segment([pos2(x, y - half), pos2(x, y + half)], stroke);
                    painter.circle_filled(rect.center(), 3.0, colour);
                }
            }
            ui.label(name);
            ui.add_space(8.0);
        }
    });
}
