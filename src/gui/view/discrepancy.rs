//! The missing-effect view: run the diagnosis on demand (it takes seconds), then show the verdict,
//! the named effects with their sizes, evidence and gaps before and after (each to accept or
//! reject: a rejected effect is never offered again and the diagnosis reruns without it), the
//! disagreement map before and after (channel by octave band, coloured by significance, hover for
//! values), and the residual densities before and after against the expected one.

use eframe::egui::{self, Align2, Color32, FontId, Rect, Sense, Stroke, StrokeKind, pos2, vec2};
use egui_plot::{Legend, Line, Plot, PlotPoints};

use super::colormap::color;
use crate::diagnose::Verdict;
use crate::diagnose::map::DisagreementMap;
use crate::diagnose::report::BlockReport;
use crate::gui::app::{Command, RunEntry};
use crate::ident::signals::channel_names;
use crate::run::Block;

const CELL_W: f32 = 36.0;
const CELL_H: f32 = 20.0;
const LABEL_W: f32 = 34.0;
/// Significance at which a map cell is fully coloured.
const Z_FULL: f64 = 20.0;

/// Draws the view for the selected run.
pub fn show(ui: &mut egui::Ui, run: Option<&RunEntry>, commands: &mut Vec<Command>) {
    let Some(run) = run else {
        ui.weak("no run selected");
        return;
    };
    ui.horizontal(|ui| {
        ui.heading("Missing effects");
        if ui.button("Find missing effects").clicked() {
            commands.push(Command::Diagnose(run.id));
        }
        if run.diagnosis.running() {
            ui.spinner();
            ui.weak("diagnosing…");
        }
        if !run.rejected.is_empty() {
            let names: Vec<String> = run
                .rejected
                .iter()
                .map(|(b, e)| format!("{} {}", b.name(), e.id()))
                .collect();
            ui.weak(format!("rejected: {}", names.join(", ")));
            if ui.small_button("clear").clicked() {
                commands.push(Command::ClearRejected(run.id));
            }
        }
    });
    if let Some(e) = &run.diagnosis.error {
        ui.colored_label(ui.visuals().error_fg_color, e);
    }
    let Some(report) = run.diagnosis.as_ref() else {
        ui.weak("The diagnosis simulates each block with its identified model, examines the residual against the model's disturbance model, and names the catalogue effect that explains it.");
        return;
    };
    let verdict = match report.verdict {
        Verdict::EffectFound => "verdict: effect found",
        Verdict::NoMissingEffect => "verdict: no missing effect",
    };
    let ended = report.ended_bands();
    let verdict = if ended.is_empty() {
        verdict.to_owned()
    } else {
        format!("{verdict} ({ended}: the inputs above are not the motion)")
    };
    ui.label(egui::RichText::new(verdict).strong());
    for name in report.refused_blocks.keys() {
        ui.colored_label(
            ui.visuals().error_fg_color,
            format!("{name} block not diagnosed: the run cannot identify it (Results says why); the verdict is the other block's"),
        );
    }
    for words in report.unexplained() {
        ui.colored_label(ui.visuals().error_fg_color, words);
    }
    // A refusal that may hide the block's strongest effect is read with the verdict; a note
    // stays with its block's details below (the words made once per frame).
    let mut not_named: Vec<Option<(String, bool)>> = report
        .blocks
        .keys()
        .map(|name| report.not_named_words(name))
        .collect();
    for (words, _) in not_named.iter().flatten().filter(|(_, warning)| *warning) {
        ui.colored_label(ui.visuals().error_fg_color, words);
    }
    for f in &report.findings {
        ui.group(|ui| {
            ui.horizontal(|ui| {
                let accepted = run.accepted.iter().any(|&(b, e)| b == f.block && e == f.effect);
                if accepted {
                    ui.label("accepted");
                } else if ui.small_button("Accept").clicked() {
                    commands.push(Command::AcceptEffect(run.id, f.block, f.effect));
                }
                if ui.small_button("Reject").clicked() {
                    commands.push(Command::RejectEffect(run.id, f.block, f.effect));
                }
                ui.strong(&f.name);
                ui.label(format!(
                    "gap {:.2} dB -> {:.2} dB",
                    f.gap_before_db, f.gap_after_db
                ));
            });
            let lines = crate::diagnose::describe::describe(f);
            if lines.is_empty() {
                ui.label(format!("size: {}", f.parameters));
            }
            for line in lines {
                ui.label(line);
            }
            ui.weak(&f.evidence);
        });
    }
    for ((name, block), said) in report.blocks.iter().zip(&mut not_named) {
        ui.separator();
        block_details(ui, name, block, said.take());
    }
}

/// One block's search: band, gaps, the notes and warnings of the search's limits, `not_named` the
/// significant candidates not named when they are a note
/// ([`crate::diagnose::Report::not_named_words`]), the maps and the densities.
fn block_details(ui: &mut egui::Ui, name: &str, b: &BlockReport, not_named: Option<(String, bool)>) {
    ui.label(format!(
        "{name}: searched {:.2}-{:.2} Hz; worst-channel gap {:.2} dB -> {:.2} dB; chi2/dof {:.3} -> {:.3}",
        b.band_hz[0],
        b.band_hz[1],
        b.gap_db[0].iter().copied().fold(f64::NEG_INFINITY, f64::max),
        b.gap_db[1].iter().copied().fold(f64::NEG_INFINITY, f64::max),
        b.chi2_per_dof[0],
        b.chi2_per_dof[1],
    ));
    if let Some(limit) = &b.input_limit {
        let words = limit.words(name);
        if limit.is_warning() {
            ui.colored_label(ui.visuals().error_fg_color, words);
        } else {
            ui.label(words);
        }
    }
    if let Some(step) = &b.delay_step {
        ui.colored_label(ui.visuals().error_fg_color, step.diagnosis_words(name));
    }
    if let Some((noisy, words)) = b.noisy_angles.as_ref().and_then(|n| Some((n, n.words(name)?))) {
        if noisy.is_warning() {
            ui.colored_label(ui.visuals().error_fg_color, words);
        } else {
            ui.label(words);
        }
    }
    // A warning is shown with the verdict above.
    if let Some((words, false)) = not_named {
        ui.label(words);
    }
    if let (Some(block), Some(limit)) = (crate::block::Block::from_name(name), &b.tone_limit) {
        ui.label(limit.words(block));
    }
    ui.horizontal(|ui| {
        ui.vertical(|ui| {
            ui.weak("disagreement before");
            map(ui, name, &b.map[0]);
        });
        ui.vertical(|ui| {
            ui.weak("after");
            map(ui, name, &b.map[1]);
        });
    });
    psd_plot(ui, name, b);
}

/// Channel by octave band, coloured by the excess's significance z (0 to [`Z_FULL`]).
fn map(ui: &mut egui::Ui, name: &str, m: &DisagreementMap) {
    let bands = m.bands_hz.len();
    let size = vec2(LABEL_W + CELL_W * bands as f32, CELL_H * (m.z.len() + 1) as f32);
    let (rect, response) = ui.allocate_exact_size(size, Sense::hover());
    let painter = ui.painter_at(rect);
    let font = FontId::proportional(10.0);
    let text = ui.visuals().text_color();
    for (k, band) in m.bands_hz.iter().enumerate() {
        let x = rect.left() + LABEL_W + CELL_W * (k as f32 + 0.5);
        painter.text(
            pos2(x, rect.bottom() - CELL_H * 0.5),
            Align2::CENTER_CENTER,
            format!("{:.1}", band[0]),
            font.clone(),
            text,
        );
    }
    let mut hovered = None;
    for (i, row) in m.z.iter().enumerate() {
        let y = rect.top() + CELL_H * i as f32;
        painter.text(
            pos2(rect.left() + 2.0, y + CELL_H * 0.5),
            Align2::LEFT_CENTER,
            outputs(name)[i].to_owned(),
            font.clone(),
            text,
        );
        for (k, &z) in row.iter().enumerate() {
            let cell = Rect::from_min_size(
                pos2(rect.left() + LABEL_W + CELL_W * k as f32, y),
                vec2(CELL_W - 1.0, CELL_H - 1.0),
            );
            let t = (z.max(0.0) / Z_FULL).min(1.0) as f32;
            painter.rect_filled(cell, 0.0, if z < 3.0 { Color32::from_gray(60) } else { color(t) });
            if response.hover_pos().is_some_and(|p| cell.contains(p)) {
                painter.rect_stroke(cell, 0.0, Stroke::new(1.5, Color32::WHITE), StrokeKind::Inside);
                hovered = Some((i, k));
            }
        }
    }
    if let Some((i, k)) = hovered {
        response.on_hover_text(format!(
            "{}, {:.2}-{:.2} Hz: residual {:+.2} dB over expected, z = {:.1}",
            outputs(name)[i],
            m.bands_hz[k][0],
            m.bands_hz[k][1],
            m.ratio_db[i][k],
            m.z[i][k]
        ));
    }
}

fn psd_plot(ui: &mut egui::Ui, name: &str, b: &BlockReport) {
    Plot::new(format!("residual-psd-{name}"))
        .height(180.0)
        .legend(Legend::default())
        .x_axis_label("log10 f (Hz)")
        .y_axis_label("log10 PSD")
        .show(ui, |p| {
            let curve = |psd: &crate::diagnose::map::ResidualPsd, ch: usize| -> PlotPoints<'static> {
                psd.frequency_hz
                    .iter()
                    .zip(&psd.psd[ch])
                    .map(|(f, v)| [f.log10(), v.max(1e-300).log10()])
                    .collect()
            };
            for (ch, channel) in outputs(name).iter().enumerate() {
                p.line(Line::new(
                    format!("{channel} before"),
                    curve(&b.residual_psd[0], ch),
                ));
                p.line(Line::new(
                    format!("{channel} after"),
                    curve(&b.residual_psd[1], ch),
                ));
                p.line(
                    Line::new(format!("{channel} expected"), curve(&b.expected_psd, ch))
                        .style(egui_plot::LineStyle::dashed_dense()),
                );
            }
        });
}

/// The output channels of the block named `name` as the run format names them (`gx gy gz`,
/// `ax ay az`); `?` for a name that is not a block.
fn outputs(name: &str) -> [&'static str; 3] {
    Block::BOTH
        .into_iter()
        .find(|b| b.name() == name)
        .map_or(["?"; 3], |b| channel_names(b).1)
}
