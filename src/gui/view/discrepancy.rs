//! The missing-effect view: run the diagnosis on demand (it takes seconds), then show the verdict,
//! the named effects with their sizes, evidence and gaps before and after (each to accept or
//! reject: a rejected effect is never offered again and the diagnosis reruns without it), the
//! limits of each block's search and the candidates it did not name (each to accept all the
//! same), the disagreement map before and after (channel by octave band, coloured by significance, hover for
//! values), and the residual densities before and after against the expected one.

use eframe::egui::{self, Align2, Color32, FontId, Rect, Sense, Stroke, StrokeKind, pos2, vec2};
use egui_plot::{Legend, Line, Plot, PlotPoints};

use super::colormap::color;
use crate::diagnose::map::DisagreementMap;
use crate::diagnose::report::BlockReport;
use crate::effect::Effect;
use crate::gui::app::{Command, RunEntry};
use crate::gui::pipeline::BlockWords;
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
    let Some(diagnosis) = run.diagnosis.as_ref() else {
        ui.weak("The diagnosis simulates each block with its identified model, examines the residual against the model's disturbance model, and names the catalogue effect that explains it.");
        return;
    };
    let report = &diagnosis.report;
    ui.label(egui::RichText::new(&diagnosis.verdict).strong());
    for words in &diagnosis.warnings {
        ui.colored_label(ui.visuals().error_fg_color, words);
    }
    for (f, sizes) in report.findings.iter().zip(&diagnosis.sizes) {
        ui.group(|ui| {
            ui.horizontal(|ui| {
                accept_button(ui, run, (f.block, f.effect), commands);
                if ui.small_button("Reject").clicked() {
                    commands.push(Command::RejectEffect(run.id, f.block, f.effect));
                }
                ui.strong(&f.name);
                ui.label(format!(
                    "gap {:.2} dB -> {:.2} dB",
                    f.gap_before_db, f.gap_after_db
                ));
            });
            if sizes.is_empty() {
                ui.label(format!("size: {}", f.parameters));
            }
            for line in sizes {
                ui.label(line);
            }
            ui.weak(&f.evidence);
        });
    }
    for words in &diagnosis.blocks {
        ui.separator();
        if let Some(b) = report.blocks.get(&words.name) {
            block_details(ui, run, words, b, commands);
        }
    }
}

/// "Accept" for an effect of the run (the identification then fits the model with it), or
/// "accepted" once it is.
fn accept_button(ui: &mut egui::Ui, run: &RunEntry, pair: (Block, Effect), commands: &mut Vec<Command>) {
    if run.accepted.contains(&pair) {
        accepted_label(ui, run, pair, "accepted");
    } else if ui.small_button("Accept").clicked() {
        commands.push(Command::AcceptEffect(run.id, pair.0, pair.1));
    }
}

/// `words` for an accepted effect, in red with the reason where the model could not add it
/// (`ModelEffects::not_added`: Results says the same).
fn accepted_label(ui: &mut egui::Ui, run: &RunEntry, (block, effect): (Block, Effect), words: &str) {
    let not_added = run
        .identification
        .as_ref()
        .and_then(|i| i.model.blocks.get(block.name()))
        .and_then(|m| m.effects.as_ref())
        .and_then(|e| e.not_added.iter().find(|n| n.effect == effect));
    match not_added {
        Some(n) => {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!("{words}, not added to the model: {}", n.reason),
            );
        }
        None => {
            ui.label(words);
        }
    }
}

/// One block's search: its header, the notes and warnings of the search's limits (a warning of
/// candidates not named is with the verdict), an "Accept" for each candidate not named (the user
/// may know better than the rule that set it aside), the maps and the densities.
fn block_details(
    ui: &mut egui::Ui,
    run: &RunEntry,
    words: &BlockWords,
    b: &BlockReport,
    commands: &mut Vec<Command>,
) {
    ui.label(&words.header);
    for limit in &words.limits {
        if limit.warning {
            ui.colored_label(ui.visuals().error_fg_color, &limit.words);
        } else {
            ui.label(&limit.words);
        }
    }
    for &(block, effect) in &words.not_named {
        let name = effect.name_on(block);
        if run.accepted.contains(&(block, effect)) {
            accepted_label(ui, run, (block, effect), &format!("not named: {name} (accepted)"));
        } else {
            ui.horizontal(|ui| {
                ui.label("not named:");
                if ui.small_button(format!("Accept {name}")).clicked() {
                    commands.push(Command::AcceptEffect(run.id, block, effect));
                }
            });
        }
    }
    let name = words.name.as_str();
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
