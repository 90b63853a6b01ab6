//! The identifier settings panel: edits a copy of [`Settings`] and sends it as a command when
//! anything changed; shows why settings are refused (A not SPD, Lambda singular, band, segment).

use crate::ident::band::{AUTO_LIMITS_HZ, BandSetting};
use crate::ident::settings::MAX_SHRINK;
use eframe::egui::{self, ComboBox, DragValue, Slider};

use crate::block::Block;
use crate::gui::app::Command;
use crate::gui::pipeline::RunSummary;
use crate::ident::settings::{Estimate, LambdaSetting, MAX_ORDER, OrderSetting, Settings};
use crate::spectral::{DEFAULT_SEGMENT_LEN, Detrend, Window};

const WINDOWS: [Window; 4] = [
    Window::Rectangular,
    Window::Hann,
    Window::Hamming,
    Window::BlackmanHarris,
];
const DETRENDS: [Detrend; 3] = [Detrend::None, Detrend::Mean, Detrend::Linear];

/// Beside a block's box when the run shown has no such block.
pub const NOT_IN_THIS_RUN: &str = "(not in this run)";

/// Draws the panel for `settings`, validated against `run` (its span's samples) when one is
/// selected.
pub fn show(ui: &mut egui::Ui, settings: &Settings, run: Option<&RunSummary>, commands: &mut Vec<Command>) {
    let mut s = settings.clone();
    ui.heading("Identifier settings");
    ui.weak(
        "A, Λ, estimate and order changes redo only the Wiener stage and the structural fit; Welch changes redo the spectra.",
    );
    welch(ui, &mut s);
    ui.separator();
    ui.horizontal(|ui| {
        let mut auto = s.band_hz == BandSetting::Auto;
        if ui
            .checkbox(&mut auto, "auto band")
            .on_hover_text(
                "Fit only where the outputs are coherent with the inputs computed from the angles \
                 (multiple coherence at least 0.9), found per block from the data, and ended \
                 below a stretch at the top that the model does not explain (a smoothed \
                 reference; a warning says so).",
            )
            .changed()
        {
            s.band_hz = if auto {
                BandSetting::Auto
            } else {
                BandSetting::Fixed(AUTO_LIMITS_HZ)
            };
        }
    });
    if let BandSetting::Fixed(band) = &mut s.band_hz {
        ui.horizontal(|ui| {
            let low = ui.label("band from");
            ui.add(
                DragValue::new(&mut band[0])
                    .speed(0.01)
                    .range(0.0..=f64::MAX)
                    .suffix(" Hz"),
            )
            .labelled_by(low.id);
            let high = ui.label("to");
            ui.add(
                DragValue::new(&mut band[1])
                    .speed(0.1)
                    .range(0.0..=f64::MAX)
                    .suffix(" Hz"),
            )
            .labelled_by(high.id);
        });
    }
    span(ui, &mut s, run);
    weight(ui, &mut s);
    lambda(ui, &mut s);
    ui.separator();
    orders(ui, &mut s);
    ui.horizontal(|ui| {
        ui.label("blocks");
        for block in Block::BOTH {
            // An empty list means every block the run has.
            let mut on = s.blocks.is_empty() || s.blocks.contains(&block);
            let checkbox = ui.checkbox(&mut on, block.name());
            // The settings are every run's: a block this run lacks stays asked for the others.
            if let Some(run) = run.filter(|r| !r.blocks.contains(&block)) {
                ui.weak(NOT_IN_THIS_RUN).on_hover_text(format!(
                    "{} has no {} columns: the setting applies to the runs that have them",
                    run.file_name,
                    block.name()
                ));
            }
            if checkbox.changed() {
                if s.blocks.is_empty() {
                    s.blocks = Block::BOTH.to_vec();
                }
                s.blocks.retain(|b| *b != block);
                // At least one block stays: an empty list would mean "all".
                if on || s.blocks.is_empty() {
                    s.blocks.push(block);
                    s.blocks.sort();
                }
            }
        }
    });
    if let Some(run) = run
        && let Err(e) = s.used_on(&run.run)
    {
        ui.colored_label(ui.visuals().error_fg_color, format!("for {}: {e}", run.file_name));
    }
    if s != *settings {
        commands.push(Command::SetSettings(Box::new(s)));
    }
}

fn welch(ui: &mut egui::Ui, s: &mut Settings) {
    ui.strong("Welch");
    ComboBox::from_label("window")
        .selected_text(s.welch.window.scipy_name())
        .show_ui(ui, |ui| {
            for w in WINDOWS {
                ui.selectable_value(&mut s.welch.window, w, w.scipy_name());
            }
        });
    // (left to the program, longest segment): "auto" is the default, shortened for a short
    // record; a number is the user's, kept as given.
    let mut segment = (s.welch.segment_auto, s.welch.segment_len);
    let shown = |(auto, n): (bool, usize)| {
        if auto {
            format!("auto (up to {n})")
        } else {
            n.to_string()
        }
    };
    ComboBox::from_label("segment length")
        .selected_text(shown(segment))
        .show_ui(ui, |ui| {
            let auto = (true, DEFAULT_SEGMENT_LEN);
            ui.selectable_value(&mut segment, auto, shown(auto))
                .on_hover_text(
                    "the program's choice: the default segment, halved for a record too short \
                     to hold 12 segments (the Spectra tab names the segment used)",
                );
            for k in 6..=16 {
                let n = 1usize << k;
                ui.selectable_value(&mut segment, (false, n), n.to_string());
            }
        });
    (s.welch.segment_auto, s.welch.segment_len) = segment;
    ui.add(Slider::new(&mut s.welch.overlap, 0.0..=0.9).text("overlap"));
    ComboBox::from_label("detrend")
        .selected_text(format!("{:?}", s.welch.detrend))
        .show_ui(ui, |ui| {
            for d in DETRENDS {
                ui.selectable_value(&mut s.welch.detrend, d, format!("{d:?}"));
            }
        });
}

fn weight(ui: &mut egui::Ui, s: &mut Settings) {
    ui.strong("weight A (symmetric positive definite)");
    egui::Grid::new("weight-a").show(ui, |ui| {
        for (i, row) in s.weight_a.iter_mut().enumerate() {
            let label = ui.label(format!("A row {}", i + 1));
            for v in row.iter_mut() {
                ui.add(DragValue::new(v).speed(0.01).max_decimals(4))
                    .labelled_by(label.id);
            }
            ui.end_row();
        }
    });
    if ui.small_button("make symmetric").clicked() {
        for i in 0..3 {
            for j in i + 1..3 {
                let m = 0.5 * (s.weight_a[i][j] + s.weight_a[j][i]);
                s.weight_a[i][j] = m;
                s.weight_a[j][i] = m;
            }
        }
    }
}

fn lambda(ui: &mut egui::Ui, s: &mut Settings) {
    ComboBox::from_label("estimate")
        .selected_text(s.estimate.to_string())
        .show_ui(ui, |ui| {
            for e in Estimate::ALL {
                ui.selectable_value(&mut s.estimate, e, e.to_string());
            }
        })
        .response
        .on_hover_text(
            "The frequency response Λ shrinks and the structural model is fitted to. H1 = S_xu S_uu^-1 \
             (default): each frequency from its own spectra, with the covariance the fit's weights \
             assume. The paper's causal Wiener W0 = [S_xu D_u^-H]_+ D_u^-1 mixes every frequency, so a \
             reference band-limited inside the grid moves it in the band (measured: the \
             accelerometer's K up to twice as far off at 1 kHz).",
        );
    ui.horizontal(|ui| {
        ui.strong("Λ per channel");
        let mut auto = s.lambda == LambdaSetting::Auto;
        if ui.checkbox(&mut auto, "auto").changed() {
            s.lambda = if auto {
                LambdaSetting::Auto
            } else {
                LambdaSetting::Values([0.0; 3])
            };
        }
    });
    if let LambdaSetting::Values(values) = &mut s.lambda {
        for (k, v) in values.iter_mut().enumerate() {
            ui.horizontal(|ui| {
                let label = ui.label(format!("λ{}", k + 1));
                ui.add(DragValue::new(v).speed(0.001).max_decimals(5))
                    .labelled_by(label.id);
                // The slider spans what validation accepts for A = I: 0 (no shrinking) to
                // MAX_SHRINK (the gain of that output halved); other values are refused with
                // the reason below.
                ui.add(
                    Slider::new(v, 0.0..=MAX_SHRINK)
                        .show_value(false)
                        .clamping(egui::SliderClamping::Never),
                )
                .labelled_by(label.id)
                .on_hover_text(
                    "Λ shrinks the estimate W (H1 or W0): W_u = (I - A^-1 Λ) W. With A = I, output k's gain is \
                     multiplied by 1 - λk (λ = 0.01 lowers that scale factor by 10 000 ppm). Allowed: \
                     λ ≥ 0 and A^-1 Λ at most 0.5.",
                );
            });
        }
    }
    if let Err(e) = s.validate_weight_and_lambda() {
        ui.colored_label(ui.visuals().error_fg_color, e.to_string());
    }
}

/// The structural order of each block: "auto" (lowest BIC among the admissible orders) or fixed.
fn orders(ui: &mut egui::Ui, s: &mut Settings) {
    ui.horizontal(|ui| {
        for block in Block::BOTH {
            let order = s.order.of_mut(block);
            ComboBox::from_label(format!("{block} order"))
                .selected_text(order.to_string())
                .show_ui(ui, |ui| {
                    ui.selectable_value(order, OrderSetting::Auto, format!("{block} auto"));
                    for n in 0..=MAX_ORDER {
                        ui.selectable_value(order, OrderSetting::Fixed(n), format!("{block} {n}"));
                    }
                })
                .response
                .on_hover_text(
                    "0: K e^(-tau s); 1-4: a rational transfer of that order with the delay; \
                     auto: the lowest BIC among the admissible orders (Results says why the \
                     others were rejected)",
                );
        }
    });
}

/// The stretch of the record to analyse (`span_s`): the whole record, or `from`..`to` in the
/// file's time (rests and spin-up transients left out). The observer still sees everything.
fn span(ui: &mut egui::Ui, s: &mut Settings, run: Option<&RunSummary>) {
    let (start, end) = run.map_or((0.0, f64::MAX), |r| (r.start_s, r.start_s + r.duration_s));
    ui.horizontal(|ui| {
        let mut whole = s.span_s.is_none();
        if ui
            .checkbox(&mut whole, "whole record")
            .on_hover_text(
                "Untick to identify and diagnose only a stretch of the record (the observer still \
                 runs over all of it, so the stretch has no edge effects).",
            )
            .changed()
        {
            s.span_s = if whole {
                None
            } else {
                Some([
                    start,
                    if end.is_finite() && end < f64::MAX {
                        end
                    } else {
                        start + 1.0
                    },
                ])
            };
        }
    });
    if let Some(span) = &mut s.span_s {
        ui.horizontal(|ui| {
            let from = ui.label("analyse from");
            ui.add(
                DragValue::new(&mut span[0])
                    .speed(0.1)
                    .range(start..=end)
                    .suffix(" s"),
            )
            .labelled_by(from.id);
            let to = ui.label("to");
            ui.add(
                DragValue::new(&mut span[1])
                    .speed(0.1)
                    .range(start..=end)
                    .suffix(" s"),
            )
            .labelled_by(to.id);
        });
    }
}
