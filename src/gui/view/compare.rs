//! The Compare tab: pick two or more runs; their K and tau side by side, the pairwise differences
//! with their combined standard deviation (significant when `|diff| > 3 std`, marked), and their
//! `W_u` overlaid on one Bode grid.

use eframe::egui;

use super::bode::{BodeEntry, grid};
use super::palette;
use crate::compare::{Comparison, Delta, SIGNIFICANCE_SIGMAS};
use crate::gui::app::{Command, RunEntry, ViewState};
use crate::gui::pipeline::RunId;

/// The note under the comparison when the runs' models of the block have different orders.
pub const ORDERS_DIFFER: &str = "the compared models have different orders: their K are static \
    gains of different structures (fix the order in the settings to compare like with like)";

/// Said when some compared runs' `K` are the gain at low frequency and others' the band's mean.
pub const GAINS_DIFFER_IN_KIND: &str = "some compared runs' K are the gain at low frequency (their \
    gain changes across the band with no phase; an even gain in the model) and others' the band's \
    mean gain: their differences hold that change too";

/// The line counting a block's significant differences, e.g. `gyro: 2 significant differences`,
/// or saying that no pair of runs both identified the block (one refused it).
#[must_use]
pub fn significance_label(comparison: &Comparison, block: &str) -> String {
    if !comparison.differences.iter().any(|d| d.block == block) {
        return format!("{block}: no pair of runs both identified it");
    }
    let n: usize = comparison
        .differences
        .iter()
        .filter(|d| d.block == block)
        .map(|d| {
            d.k.iter()
                .flatten()
                .chain([&d.tau_s])
                .filter(|x| x.significant == Some(true))
                .count()
        })
        .sum();
    format!("{block}: {n} significant differences")
}

fn delta_text(d: &Delta, scale: f64) -> String {
    let mark = if d.significant == Some(true) { " *" } else { "" };
    match d.std {
        Some(s) => format!("{:+.4} ± {:.4}{mark}", d.diff * scale, s * scale),
        None => format!("{:+.4}{mark}", d.diff * scale),
    }
}

/// Draws the tab.
pub fn show(
    ui: &mut egui::Ui,
    runs: &[RunEntry],
    compared: &[RunId],
    comparison: Option<&Comparison>,
    view: &mut ViewState,
    commands: &mut Vec<Command>,
) {
    ui.horizontal_wrapped(|ui| {
        ui.strong("compare:");
        for run in runs.iter().filter(|r| r.loaded()) {
            let mut on = compared.contains(&run.id);
            if ui.checkbox(&mut on, format!("compare {}", run.name())).changed() {
                commands.push(Command::ToggleCompare(run.id));
            }
        }
    });
    let Some(c) = comparison else {
        ui.weak("choose two or more identified runs");
        return;
    };
    // Every block any run identified (a block refused on one run is said below the buttons).
    let blocks: Vec<String> = c.runs.iter().flat_map(|r| r.blocks.keys().cloned()).collect();
    ui.horizontal(|ui| {
        for b in crate::block::Block::BOTH {
            if blocks.iter().any(|n| n == b.name()) {
                ui.selectable_value(&mut view.bode_block, b, b.name());
            }
        }
        ui.checkbox(&mut view.bode_deviation, "deviation from K");
        ui.separator();
        ui.label(format!(
            "differences are later run minus earlier; * marks |diff| > {SIGNIFICANCE_SIGMAS} combined std"
        ));
    });
    let block = view.bode_block.name();
    // Every run's refused blocks, whichever block is shown: a block missing from a pair is said.
    for r in &c.runs {
        for refused in r.refused_blocks.keys() {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!(
                    "{}: the {refused} block was not identified (its Results say why): no pair with this run compares it",
                    r.source.file
                ),
            );
        }
    }
    ui.label(significance_label(c, block));
    for line in c.mount_lines(block) {
        ui.label(line);
    }
    if c.orders_differ(block) {
        ui.colored_label(ui.visuals().warn_fg_color, ORDERS_DIFFER);
    }
    if c.gains_differ_in_kind(block) {
        ui.colored_label(ui.visuals().warn_fg_color, GAINS_DIFFER_IN_KIND);
    }
    egui::ScrollArea::vertical().show(ui, |ui| {
        // Wider than the tab with three or more runs: scrolled sideways, never under Results.
        egui::ScrollArea::horizontal()
            .id_salt("compare-table")
            .show(ui, |ui| figures(ui, c, block, view));
        ui.separator();
        findings(ui, c, view.bode_block);
        ui.separator();
        let entries: Vec<BodeEntry<'_>> = compared
            .iter()
            .filter_map(|id| runs.iter().find(|r| r.id == *id))
            .enumerate()
            .filter_map(|(k, r)| {
                let bode = r
                    .identification
                    .as_ref()?
                    .bode
                    .iter()
                    .find(|b| b.block == view.bode_block)?;
                Some(BodeEntry {
                    label: r.name(),
                    bode,
                    colour: palette(k),
                    details: false,
                })
            })
            .collect();
        grid(ui, &entries, "compare", view.bode_deviation);
    });
}

/// The table: each run's figures, then each pair's difference.
fn figures(ui: &mut egui::Ui, c: &Comparison, block: &str, view: &ViewState) {
    egui::Grid::new("compare-figures").striped(true).show(ui, |ui| {
        ui.strong("figure");
        for r in &c.runs {
            ui.strong(format!("{} ({})", r.source.file, r.source.regime));
        }
        for d in c.differences.iter().filter(|d| d.block == block) {
            ui.strong(c.difference_header(d));
        }
        ui.end_row();
        ui.label("τ, ms");
        for r in &c.runs {
            let f = r.blocks.get(block);
            ui.monospace(f.map_or_else(String::new, |f| format!("{:.3}", f.tau_s * 1e3)));
        }
        for d in c.differences.iter().filter(|d| d.block == block) {
            ui.monospace(delta_text(&d.tau_s, 1e3));
        }
        ui.end_row();
        ui.label("order");
        for r in &c.runs {
            let f = r.blocks.get(block);
            ui.monospace(f.map_or_else(String::new, |f| f.order.to_string()));
        }
        ui.end_row();
        let (inputs, outputs) = crate::ident::signals::channel_names(view.bode_block);
        for i in 0..3 {
            for j in 0..3 {
                ui.label(format!("K {}/{}", outputs[i], inputs[j]));
                for r in &c.runs {
                    let f = r.blocks.get(block);
                    ui.monospace(f.map_or_else(String::new, |f| format!("{:+.6}", f.k[i][j])));
                }
                for d in c.differences.iter().filter(|d| d.block == block) {
                    ui.monospace(delta_text(&d.k[i][j], 1.0));
                }
                ui.end_row();
            }
        }
    });
}

/// Said where the compared runs have not all been diagnosed.
pub const FINDINGS_NOT_COMPARED: &str = "findings: run Find missing effects on every compared run (Missing \
     effects tab), with the same settings, to compare them here";

/// The diagnosis's findings of `block` compared between each pair of runs, in words.
fn findings(ui: &mut egui::Ui, c: &Comparison, block: crate::block::Block) {
    let Some(all) = &c.findings else {
        ui.weak(FINDINGS_NOT_COMPARED);
        return;
    };
    let file = |i: usize| c.runs.get(i).map_or("?", |r| r.source.file.as_str());
    ui.strong(format!("findings of the {} block across runs", block.name()));
    let verdicts: Vec<String> = c
        .runs
        .iter()
        .map(|r| {
            let verdict = match r.verdict {
                Some(crate::diagnose::Verdict::EffectFound) => "effect found",
                Some(crate::diagnose::Verdict::NoMissingEffect) => "no missing effect",
                None => "not diagnosed",
            };
            format!("{}: {verdict}", r.source.file)
        })
        .collect();
    ui.label(verdicts.join("; "));
    let mut any = false;
    for d in all.iter().filter(|d| d.block == block) {
        any = true;
        let text = format!(
            "{} / {}: {}: {}",
            file(d.runs[0]),
            file(d.runs[1]),
            d.effect.name_on(d.block),
            d.words
        );
        if d.consistent == Some(false) {
            ui.colored_label(ui.visuals().warn_fg_color, text);
        } else {
            ui.label(text);
        }
    }
    if !any {
        let refused: Vec<&str> = c
            .runs
            .iter()
            .filter(|r| r.refused_blocks.contains_key(block.name()))
            .map(|r| r.source.file.as_str())
            .collect();
        if refused.is_empty() {
            ui.label("no finding on this block in any compared run");
        } else {
            ui.label(format!(
                "no finding on this block compared: {} did not identify it",
                refused.join(", ")
            ));
        }
    }
}
