//! Heatmaps drawn with egui's painter: the CSD matrix at one frequency, and frequency by channel
//! pair; each with a colour legend and hover values.

use eframe::egui::{
    self, Align2, Color32, FontId, Rect, Sense, Stroke, StrokeKind, TextureHandle, pos2, vec2,
};

use super::colormap::{color, log_bin, log_position, normalise, pair_values, value_range};
use crate::gui::app::HeatmapMode;
use crate::gui::pipeline::BlockSpectra;
use crate::gui::pipeline::decibels;

const CELL: f32 = 36.0;
const LABEL: f32 = 34.0;
const ROW: f32 = 14.0;

fn unit(mode: HeatmapMode) -> &'static str {
    match mode {
        HeatmapMode::Magnitude => "dB",
        HeatmapMode::Coherence => "",
    }
}

/// The value shown for `S_ij` at bin `f`: `10 log10 |S_ij|` or the coherence (1 on the diagonal).
#[must_use]
pub fn cell_value(block: &BlockSpectra, f: usize, i: usize, j: usize, mode: HeatmapMode) -> f64 {
    let s = |a, b| block.matrix.get(f, a, b).unwrap_or_default();
    match mode {
        HeatmapMode::Magnitude => decibels(s(i, j).norm()),
        HeatmapMode::Coherence => {
            let denom = s(i, i).re * s(j, j).re;
            if denom > 0.0 {
                (s(i, j).norm_sqr() / denom).min(1.0)
            } else {
                0.0
            }
        }
    }
}

/// A horizontal colour bar from `range.0` to `range.1`.
pub fn legend(ui: &mut egui::Ui, range: (f32, f32), mode: HeatmapMode) {
    ui.horizontal(|ui| {
        ui.label(format!("{:.1}", range.0));
        let (rect, _) = ui.allocate_exact_size(vec2(160.0, 12.0), Sense::hover());
        let steps = 40;
        for k in 0..steps {
            let x0 = rect.left() + rect.width() * k as f32 / steps as f32;
            let x1 = rect.left() + rect.width() * (k + 1) as f32 / steps as f32;
            let r = Rect::from_min_max(pos2(x0, rect.top()), pos2(x1 + 0.5, rect.bottom()));
            ui.painter()
                .rect_filled(r, 0.0, color(k as f32 / (steps - 1) as f32));
        }
        ui.label(format!("{:.1} {}", range.1, unit(mode)));
    });
}

/// The colour scale of the single-frequency matrix at bin `f`: its own cells' range in dB
/// (whole dB, at least 1 dB wide), or `[0, 1]` for the coherence. The whole spectrum's range put
/// every cell of one frequency in two or three shades of one colour.
#[must_use]
pub fn matrix_range(block: &BlockSpectra, f: usize, mode: HeatmapMode) -> (f32, f32) {
    if mode == HeatmapMode::Coherence {
        return (0.0, 1.0);
    }
    let n = block.channels.len();
    let values = (0..n * n)
        .map(|e| cell_value(block, f, e / n, e % n, mode) as f32)
        .filter(|v| v.is_finite());
    let (low, high) = values.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !(low.is_finite() && high.is_finite()) {
        return value_range(block, mode);
    }
    // `+ 0.0` turns a -0.0 (the ceiling of -0.3) into 0.0, which prints without a sign.
    let (low, high) = (low.floor() + 0.0, high.ceil() + 0.0);
    (low, high.max(low + 1.0))
}

/// Title of the single-frequency matrix at `f_hz`.
#[must_use]
pub fn matrix_title(mode: HeatmapMode, f_hz: f64) -> String {
    match mode {
        HeatmapMode::Magnitude => format!("|S_ij|, dB, at {f_hz:.3} Hz"),
        HeatmapMode::Coherence => format!("coherence |S_ij|² / (S_ii S_jj) at {f_hz:.3} Hz"),
    }
}

/// The 6x6 CSD matrix of `block` at bin `f`.
pub fn matrix(ui: &mut egui::Ui, block: &BlockSpectra, f: usize, mode: HeatmapMode) {
    let n = block.channels.len();
    let range = matrix_range(block, f, mode);
    let size = vec2(LABEL + CELL * n as f32, LABEL + CELL * n as f32);
    let (response, painter) = ui.allocate_painter(size, Sense::hover());
    let origin = response.rect.min + vec2(LABEL, LABEL);
    let text = ui.visuals().text_color();
    let font = FontId::proportional(12.0);
    for (k, name) in block.channels.iter().enumerate() {
        let c = k as f32 * CELL + CELL / 2.0;
        painter.text(
            origin + vec2(c, -LABEL / 2.0),
            Align2::CENTER_CENTER,
            name,
            font.clone(),
            text,
        );
        painter.text(
            origin + vec2(-LABEL / 2.0, c),
            Align2::CENTER_CENTER,
            name,
            font.clone(),
            text,
        );
    }
    for i in 0..n {
        for j in 0..n {
            let v = cell_value(block, f, i, j, mode) as f32;
            let r = Rect::from_min_size(origin + vec2(j as f32 * CELL, i as f32 * CELL), vec2(CELL, CELL));
            painter.rect_filled(r.shrink(1.0), 2.0, color(normalise(v, range)));
        }
    }
    let Some(pos) = response.hover_pos() else { return };
    let (j, i) = (
        ((pos.x - origin.x) / CELL).floor(),
        ((pos.y - origin.y) / CELL).floor(),
    );
    if (0.0..n as f32).contains(&i) && (0.0..n as f32).contains(&j) {
        let (i, j) = (i as usize, j as usize);
        let r = Rect::from_min_size(origin + vec2(j as f32 * CELL, i as f32 * CELL), vec2(CELL, CELL));
        painter.rect_stroke(r, 2.0, Stroke::new(2.0, Color32::WHITE), StrokeKind::Inside);
        let v = cell_value(block, f, i, j, mode);
        let hz = block.matrix.frequency_hz.get(f).copied().unwrap_or_default();
        response.on_hover_text_at_pointer(format!(
            "S[{}, {}] at {hz:.3} Hz: {v:.4} {}",
            block.channels[i],
            block.channels[j],
            unit(mode)
        ));
    }
}

/// Frequency (x, logarithmic from the first bin to Nyquist) by channel pair (rows), from a
/// prepared texture.
pub fn pair_grid(ui: &mut egui::Ui, block: &BlockSpectra, mode: HeatmapMode, texture: &TextureHandle) {
    let rows = block.pairs.len();
    let width = ui.available_width().max(200.0);
    let size = vec2(width, ROW * rows as f32 + 18.0);
    let (response, painter) = ui.allocate_painter(size, Sense::hover());
    let image = Rect::from_min_max(
        response.rect.min + vec2(LABEL + 16.0, 0.0),
        pos2(
            response.rect.right() - 8.0,
            response.rect.top() + ROW * rows as f32,
        ),
    );
    painter.image(
        texture.id(),
        image,
        Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
        Color32::WHITE,
    );
    let text = ui.visuals().text_color();
    let font = FontId::proportional(11.0);
    for (r, &(i, j)) in block.pairs.iter().enumerate() {
        let y = image.top() + (r as f32 + 0.5) * ROW;
        let name = format!("{}·{}", block.channels[i], block.channels[j]);
        painter.text(
            pos2(image.left() - 4.0, y),
            Align2::RIGHT_CENTER,
            name,
            font.clone(),
            text,
        );
    }
    let (df, n_bins) = (block.matrix.df_hz(), block.matrix.n_bins());
    let nyquist = block.matrix.frequency_hz.last().copied().unwrap_or_default();
    let mut decade = 10f64.powf(df.log10().ceil());
    while decade <= nyquist {
        let x = image.left() + image.width() * log_position(decade, df, n_bins) as f32;
        painter.vline(
            x,
            image.y_range(),
            Stroke::new(1.0, Color32::from_white_alpha(60)),
        );
        painter.text(
            pos2(x, image.bottom() + 2.0),
            Align2::CENTER_TOP,
            format!("{decade} Hz"),
            font.clone(),
            text,
        );
        decade *= 10.0;
    }
    let Some(pos) = response.hover_pos().filter(|p| image.contains(*p)) else {
        return;
    };
    let values = pair_values(block, mode);
    let bin = log_bin(f64::from((pos.x - image.left()) / image.width()), n_bins);
    let row = ((pos.y - image.top()) / ROW) as usize;
    if let (Some(&(i, j)), Some(v)) = (
        block.pairs.get(row),
        values.get(row * n_bins + bin.min(n_bins - 1)),
    ) {
        let hz = block.matrix.frequency_hz.get(bin).copied().unwrap_or_default();
        response.on_hover_text_at_pointer(format!(
            "{}·{} at {hz:.3} Hz: {v:.4} {}",
            block.channels[i],
            block.channels[j],
            unit(mode)
        ));
    }
}
