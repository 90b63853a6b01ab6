//! The results panel: per block, the self-check's warnings in red, the band used, K with scale-factor errors (ppm) and misalignments (mrad), tau in
//! ms, the chosen order with every candidate's criterion (BIC) or the effects accepted into the
//! model with their sizes, and the fit's figures, each with
//! its standard deviation where the data determine it.

use eframe::egui;

use crate::block::Block;
use crate::diagnose::describe::describe_size;
use crate::gui::app::{Command, RunEntry};
use crate::ident::band::BandSetting;
use crate::ident::settings::{LambdaSetting, OrderSetting, Settings};
use crate::model::BlockModel;

/// `v ± std` with `decimals`, or with more where the deviation would round to zero (its first
/// significant digit shown, at most 9 decimals): a deviation of 7e-5 ms reads `± 0.00007`, not
/// `± 0.000`, which would read as exact.
fn pm(v: f64, std: Option<f64>, decimals: usize) -> String {
    match std {
        Some(s) => {
            let shown = if s > 0.0 && s < 0.5 * 10f64.powi(-(decimals as i32)) {
                ((-s.log10()).floor() as usize + 1).clamp(decimals, 9)
            } else {
                decimals
            };
            format!("{v:.shown$} ± {s:.shown$}")
        }
        None => format!("{v:.decimals$}"),
    }
}

/// The delay line, e.g. `gyro τ = 4.012 ± 0.010 ms`.
#[must_use]
pub fn tau_label(block: &str, m: &BlockModel) -> String {
    format!(
        "{block} τ = {} ms",
        pm(m.tau_s * 1e3, m.fit.tau_std_s.map(|s| s * 1e3), 3)
    )
}

/// The band line, e.g. `gyro band 0.14-14.58 Hz (auto: where the outputs are coherent with the
/// inputs and the model explains them)`.
#[must_use]
pub fn band_label(block: &str, m: &BlockModel, auto: bool) -> String {
    format!(
        "{block} band {:.2}-{:.2} Hz ({})",
        m.band_hz[0],
        m.band_hz[1],
        if auto {
            "auto: where the outputs are coherent with the inputs from the angles and the model explains them"
        } else {
            "as set"
        }
    )
}

/// Row `i` of K, e.g. `gyro K gx: +1.000012 -0.000340 +0.000101`.
#[must_use]
pub fn k_row_label(block: &str, m: &BlockModel, i: usize) -> String {
    let [a, b, c] = m.k[i];
    format!("{block} K {}: {a:+.6} {b:+.6} {c:+.6}", m.outputs[i])
}

/// The heading of the K rows: what K is, and with an even gain in the model (a gain that changes
/// across the band with no phase), that K is the gain at low frequency and how far `g` moves it
/// at the band's top.
#[must_use]
pub fn k_heading(m: &BlockModel) -> String {
    match &m.even_gain {
        Some(g) => format!(
            "K at low frequency (the model is g(f) K e^(-tau s), g {:+.2} % at {:.1} Hz against \
             low frequency: the gain changes across the band; rows: outputs; columns: inputs)",
            (g.at(m.band_hz[1]) - 1.0) * 100.0,
            m.band_hz[1]
        ),
        None => "K (rows: outputs; columns: inputs)".to_owned(),
    }
}

/// Draws the results of the selected run, with the model export button.
pub fn show(ui: &mut egui::Ui, run: Option<&RunEntry>, commands: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        ui.heading("Results");
        if let Some(run) = run
            && run.busy()
        {
            ui.spinner();
        }
    });
    let Some(run) = run else {
        ui.weak("no run selected");
        return;
    };
    let Some(id) = run.identification.as_ref() else {
        if let Some(e) = &run.identification.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        } else {
            ui.weak("identifying…");
        }
        return;
    };
    if let Some(e) = &run.identification.error {
        ui.colored_label(
            ui.visuals().error_fg_color,
            format!("current settings failed: {e}; showing the last good result"),
        );
    }
    if id.provisional() {
        ui.weak("refined from the previous fit; refitting from scratch when the settings rest");
    }
    if ui.button("Export model JSON…").clicked() {
        commands.push(Command::ExportModel(None));
    }
    // A block the run cannot identify is said first: the result holds the others only.
    let kept: Vec<&str> = id.model.blocks.keys().map(String::as_str).collect();
    for (name, refused) in &id.model.refused_blocks {
        ui.colored_label(
            ui.visuals().error_fg_color,
            format!("warning: {}", refused.words(name, &kept)),
        );
    }
    for (block, name, m) in id.blocks().iter().filter_map(|b| {
        let (name, m) = id.model.blocks.get_key_value(b.block.name())?;
        Some((b.block, name, m))
    }) {
        let auto_order = id.settings.order.of(block) == OrderSetting::Auto;
        ui.separator();
        ui.strong(format!(
            "{name}: {} to {}",
            m.inputs.join(" "),
            m.outputs.join(" ")
        ));
        for w in &m.fit.warnings {
            ui.colored_label(ui.visuals().error_fg_color, format!("warning: {w}"));
        }
        ui.label(band_label(name, m, id.settings.band_hz == BandSetting::Auto));
        if let Some([from, to]) = id.settings.span_s {
            ui.label(format!(
                "{name} analysed over t = {from:.2} to {to:.2} s of the record"
            ));
        }
        ui.label(tau_label(name, m));
        if m.extended_by().is_none() {
            ui.label(format!(
                "order {} ({}), {}",
                m.order,
                if auto_order {
                    "auto: lowest BIC among the admissible orders"
                } else {
                    "fixed"
                },
                if m.fit.stable { "stable" } else { "UNSTABLE" }
            ));
        }
        for line in effect_lines(name, m) {
            ui.label(line);
        }
        ui.label(k_heading(m));
        for i in 0..3 {
            ui.monospace(k_row_label(name, m, i));
        }
        for line in pole_lines(name, m) {
            ui.monospace(line);
        }
        figures(ui, name, m);
        super::stationarity::show(ui, name, m);
        candidates(ui, name, m);
        fit(ui, m, &id.settings);
    }
}

/// The accepted effects of a block's model in words: what the model is, each effect's size
/// with its standard deviation, what could not be added, and the fit with and without them.
/// Empty without accepted effects; when none could be added, only that and why.
#[must_use]
pub fn effect_lines(block: &str, m: &BlockModel) -> Vec<String> {
    let Some(e) = &m.effects else { return Vec::new() };
    let b = if block == "gyro" {
        Block::Gyro
    } else {
        Block::Accel
    };
    let not_added = e
        .not_added
        .iter()
        .map(|n| format!("not added: {} ({})", n.effect.name_on(b), n.reason));
    if !e.extends() {
        let mut out = vec![format!(
            "{block} model: as identified (no accepted effect could be added)"
        )];
        out.extend(not_added);
        return out;
    }
    let mut out = vec![format!(
        "{block} model: K e^(-tau s) with {} accepted effect{} (identified without them: order {}, tau {:.3} ms{})",
        e.accepted.len(),
        if e.accepted.len() == 1 { "" } else { "s" },
        e.identified.order,
        e.identified.tau_s * 1e3,
        e.identified.band_words(m.band_hz)
    )];
    for a in &e.accepted {
        out.push(format!("accepted: {}", a.name));
        out.extend(
            describe_size(b, a.effect, &a.parameters, &a.parameter_std)
                .into_iter()
                .map(|l| format!("  {l}")),
        );
    }
    out.extend(not_added);
    let worst = |g: &[f64; 3]| g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    out.push(format!(
        "whole-record fit {:.1}-{:.1} Hz: chi2/dof {:.2} -> {:.2}, worst-channel gap {:.2} -> {:.2} dB",
        e.band_hz[0],
        e.band_hz[1],
        e.chi2_per_dof[0],
        e.chi2_per_dof[1],
        worst(&e.gap_db[0]),
        worst(&e.gap_db[1])
    ));
    out
}

/// The lines of the model's poles (order 1 and above): each with its time constant, or natural
/// frequency and damping; none at order 0.
#[must_use]
pub fn pole_lines(block: &str, m: &BlockModel) -> Vec<String> {
    m.poles
        .iter()
        .enumerate()
        .map(|(k, p)| format!("{block} pole {}: {}", k + 1, crate::model::describe_pole(*p)))
        .collect()
}

fn figures(ui: &mut egui::Ui, name: &str, m: &BlockModel) {
    let f = &m.fit;
    ui.label("scale-factor errors, ppm");
    for i in 0..3 {
        ui.monospace(format!(
            "  {}: {}",
            m.outputs[i],
            pm(f.scale_factor_error_ppm[i], f.scale_factor_error_std_ppm[i], 1)
        ));
    }
    ui.label("misalignments, mrad (row: output, column: input)");
    egui::Grid::new(("misalignment", name))
        .striped(true)
        .show(ui, |ui| {
            ui.label("");
            for input in &m.inputs {
                ui.strong(input.as_str());
            }
            ui.end_row();
            for i in 0..3 {
                ui.monospace(m.outputs[i].as_str());
                for j in 0..3 {
                    if i == j {
                        ui.monospace("-");
                    } else {
                        ui.monospace(pm(f.misalignment_mrad[i][j], f.misalignment_std_mrad[i][j], 3));
                    }
                }
                ui.end_row();
            }
        });
}

fn candidates(ui: &mut egui::Ui, name: &str, m: &BlockModel) {
    ui.label("order candidates");
    // A wide table (a far pole's delay, a large chi2) scrolls instead of widening the panel over
    // the central view's controls.
    egui::ScrollArea::horizontal()
        .id_salt(("candidates-scroll", name))
        .show(ui, |ui| candidate_table(ui, name, m));
    // The reasons are sentences: wrapped under the table, so they do not widen the panel.
    for c in &m.fit.candidates {
        let rejected = c.rejected.as_ref().map(|reason| format!("no: {reason}"));
        let set_aside = c.unstable_set_aside.map(|aside| aside.to_string());
        for words in [rejected, set_aside].into_iter().flatten() {
            ui.horizontal_wrapped(|ui| {
                ui.monospace(format!("order {}:", c.order));
                ui.add(egui::Label::new(words).wrap());
            });
        }
    }
}

fn candidate_table(ui: &mut egui::Ui, name: &str, m: &BlockModel) {
    egui::Grid::new(("candidates", name))
        .striped(true)
        .show(ui, |ui| {
            for h in [
                "order",
                "params",
                "χ²",
                "BIC",
                "held-out χ²",
                "τ, ms",
                "admissible",
            ] {
                ui.strong(h);
            }
            ui.end_row();
            for c in &m.fit.candidates {
                // The identifier's choice (before any accepted effect made the model order 0).
                let identified = m.effects.as_ref().map_or(m.order, |e| e.identified.order);
                let chosen = if c.order == identified { " <" } else { "" };
                ui.monospace(format!("{}{chosen}", c.order));
                ui.monospace(c.parameters.to_string());
                ui.monospace(format!("{:.1}", c.chi2));
                ui.monospace(format!("{:.1}", c.criterion));
                // Fitted to each half of the record, predicting the other (admissibility rule 7).
                ui.monospace(
                    c.held_out_chi2
                        .map_or_else(|| "–".to_owned(), |h| format!("{h:.1}")),
                );
                ui.monospace(format!("{:.3}", c.tau_s * 1e3));
                ui.monospace(if c.rejected.is_some() { "no" } else { "yes" });
                ui.end_row();
            }
        });
}

fn fit(ui: &mut egui::Ui, m: &BlockModel, settings: &Settings) {
    let f = &m.fit;
    let lambda_auto = settings.lambda == LambdaSetting::Auto;
    // With accepted effects the model is the joint fit (its chi2/dof in the effect lines above);
    // these figures are the identification's, without them.
    let whose = if m.extended_by().is_some() {
        "identified without the accepted effects: "
    } else {
        ""
    };
    ui.label(format!(
        "{whose}χ² = {:.1} on {} degrees of freedom (χ²/dof {:.2}); σ widened by the bins' correlation ×{:.2}",
        f.chi2,
        f.dof,
        f.chi2_per_dof,
        f.bin_correlation.max(1.0).sqrt()
    ));
    ui.label(format!(
        "Λ = [{:.4}, {:.4}, {:.4}]{} on the {} estimate",
        f.lambda[0],
        f.lambda[1],
        f.lambda[2],
        if lambda_auto { " (auto)" } else { "" },
        settings.estimate
    ));
    ui.label(format!(
        "constraint residual {:.2e}; {:.1} equivalent averages",
        f.constraint_residual, f.equivalent_averages
    ));
    let error = |e: Option<f64>| e.map_or_else(|| "not recorded".to_owned(), |e| format!("{e:.1e}"));
    // Recorded only for a fit through the causal stage (the causal estimate).
    let causal_stage = f.causal_grid_refinement.map_or_else(
        || "the H1 fit does not go through the causal stage".to_owned(),
        |r| format!("causal stage on a grid {r}x finer than the spectra's"),
    );
    ui.label(format!(
        "factor errors: {}disturbance {}; {causal_stage}",
        f.input_factor_error
            .map_or_else(String::new, |e| format!("input {e:.1e}, ")),
        error(f.noise_factor_error)
    ))
    .on_hover_text(
        "the input's spectral factor must be causal for the causal Wiener estimate; a steep input \
         spectrum (slow manoeuvres) needs a finer grid for that (identifier, fourth numerical choice)",
    );
}

#[cfg(test)]
mod tests {
    use super::pm;

    #[test]
    fn a_deviation_too_small_for_the_decimals_gets_its_first_digit() {
        assert_eq!(pm(4.420_112, Some(7.1e-5), 3), "4.42011 ± 0.00007");
        assert_eq!(pm(4.417, Some(0.002), 3), "4.417 ± 0.002");
        assert_eq!(pm(443.8, Some(4.3), 1), "443.8 ± 4.3");
        assert_eq!(pm(1.0, Some(0.0), 3), "1.000 ± 0.000");
        assert_eq!(pm(1.0, Some(1e-15), 3), "1.000000000 ± 0.000000000");
        assert_eq!(pm(2.5, None, 2), "2.50");
    }
}
