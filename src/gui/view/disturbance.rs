//! The Bode tab's lower half: the multiple coherence of each output with the band used, and the
//! disturbance PSD matrix with what it is made of (the stand's white angle noise through the
//! model, dashed on the diagonal, and where it is half of the disturbance or more:
//! `crate::noise::share`).

use eframe::egui::{self, Color32};
use egui_plot::{HLine, Legend, Line, LineStyle, PlotPoints};

use super::bode::{mark_band, plot};
use super::palette;
use crate::gui::pipeline::BlockBode;

/// Multiple coherence of each output, and the disturbance PSD matrix `|S_psi,ij|` in dB.
pub fn coherence_and_noise(ui: &mut egui::Ui, bode: &BlockBode) {
    let width = ((ui.available_width() - 24.0) / 3.0).max(120.0);
    ui.strong(format!(
        "multiple coherence of each output with the three inputs; band used {:.2}-{:.2} Hz (dashed), 0.9 dotted",
        bode.band_hz[0], bode.band_hz[1]
    ));
    plot("coherence", 3.0 * width, 150.0, "bode")
        // Bottom left: where the coherence is high (the band), the lower half is empty.
        .legend(Legend::default().position(egui_plot::Corner::LeftBottom))
        .include_y(0.0)
        .include_y(1.0)
        .show(ui, |p| {
            mark_band(p, bode.band_hz);
            p.hline(
                HLine::new("usable (0.9)", crate::ident::band::MIN_COHERENCE)
                    .color(Color32::GRAY)
                    .style(LineStyle::dotted_dense()),
            );
            for (i, points) in bode.coherence.iter().enumerate() {
                p.line(
                    Line::new(bode.outputs[i].clone(), PlotPoints::Borrowed(points))
                        .color(palette(i + 3))
                        .width(1.4),
                );
            }
        });
    ui.strong("disturbance PSD matrix |S_ψ,ij|, dB re 1 unit²/Hz: what the model does not explain");
    ui.label(&bode.reference_explanation);
    egui::Grid::new("noise-psd").spacing([6.0, 6.0]).show(ui, |ui| {
        for i in 0..3 {
            for j in 0..3 {
                ui.vertical(|ui| {
                    ui.label(format!("{} × {}", bode.outputs[i], bode.outputs[j]));
                    plot(("noise", i, j), width, 90.0, "bode").show(ui, |p| {
                        p.line(
                            Line::new("S_ψ", PlotPoints::Borrowed(&bode.noise_psd_db[3 * i + j]))
                                .color(palette(3 + i.min(j)))
                                .width(1.2),
                        );
                        if i == j {
                            p.line(
                                Line::new(
                                    "reference's angle error",
                                    PlotPoints::Borrowed(&bode.reference_psd_db[i]),
                                )
                                .color(Color32::GRAY)
                                .style(LineStyle::dashed_dense())
                                .width(1.2),
                            );
                        }
                    });
                });
            }
            ui.end_row();
        }
    });
}
