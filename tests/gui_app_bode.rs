//! The Bode tab's read-out and deviation view (issue 16): hovering a plot names the element and
//! frequency with its gain, phase and deviation from K; "deviation from K" plots that deviation
//! in ppm (diagonal) and mrad (cross-axis) instead of dB. AccessKit (`egui_kittest`) with raw
//! pointer events, no GPU; the worker runs synchronously.

use eframe::egui::{self, Pos2};
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::view::bode::readout;
use imu_attest::gui::{WorkerMode, sample_run_path};

use crate::common::gui as gui_common;

#[test]
fn hovering_a_bode_plot_reads_out_gain_phase_and_deviation_from_k() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    harness.get_by_label("Bode").click();
    harness.run_steps(3);
    harness.get_by_label_contains("read-out: hover a plot");
    // The key is above the grid (a legend inside the small plots covered their data).
    harness.get_by_label("— cruise.csv.gz");
    harness.get_by_label("white dashed: fitted model; shaded: ±2σ; grey dashed: band used");
    // Into the gx-from-wx magnitude plot, just under its title.
    let title = harness.get_by_label("gx from wx").rect();
    let pos = Pos2::new(title.min.x + 120.0, title.max.y + 50.0);
    harness.input_mut().events.push(egui::Event::PointerMoved(pos));
    harness.run_steps(3);
    let shown = harness.state().view().bode_readout.clone().unwrap_or_default();
    assert!(shown.starts_with("read-out: gx from wx at"), "{shown}");
    harness.get_by_label(&shown);
    assert!(
        shown.contains(" ppm") && shown.contains("dB") && shown.contains('°'),
        "{shown}"
    );
    // The line is the identification's own numbers at that bin.
    let run = &harness.state().runs()[0];
    let id = run.identification.as_ref().expect("identified");
    let bode = id.bode.iter().find(|b| b.block.name() == "gyro").expect("gyro");
    let hz: f64 = shown
        .split(" at ")
        .nth(1)
        .and_then(|t| t.split(" Hz").next())
        .and_then(|t| t.parse().ok())
        .expect("a frequency");
    assert_eq!(readout(bode, 0, hz.log10()).as_deref(), Some(shown.as_str()));

    harness.get_by_label("deviation from K").click();
    harness.run_steps(2);
    assert!(harness.state().view().bode_deviation);
}

/// The disturbance PSD says what it is made of: the reference's angle error through the model
/// (dashed on each diagonal cell) and, in a sentence above the grid, where it is half of the
/// disturbance or more. On the sample run the gyro's disturbance at the top of the band is the
/// differentiated angle noise (`tests/noise_reference_share.rs` checks the line's level).
#[test]
fn the_disturbance_psd_names_where_it_is_the_references_angle_error() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    harness.get_by_label("Bode").click();
    harness.run_steps(3);
    for block in ["gyro", "accel"] {
        // The Bode tab's block selector (the side panels name the blocks too).
        harness
            .get_all_by_label(block)
            .find(|n| (340.0..1100.0).contains(&n.rect().center().x))
            .expect("the tab's block selector")
            .click();
        harness.run_steps(3);
        let bode = {
            let run = &harness.state().runs()[0];
            let id = run.identification.as_ref().expect("identified");
            let b = id.bode.iter().find(|b| b.block.name() == block).expect("block");
            assert!(b.reference_psd_db.iter().all(|line| line.len() > 10), "{block}");
            b.reference_explanation.clone()
        };
        // Exactly one such sentence, and it is this block's.
        harness.get_by_label_contains("Dashed on the diagonal");
        harness.get_by_label(&bode);
        let shown = bode;
        let how = if block == "gyro" {
            "differentiated into a rate error"
        } else {
            "as tilt against gravity and lever-arm acceleration"
        };
        assert!(shown.contains(how), "{shown}");
        if block == "gyro" {
            // White angle noise of 1e-5 rad at 500 Hz outgrows the gyro's noise at the band's top.
            assert!(shown.contains("not the sensor's noise: gx "), "{shown}");
            assert!(
                shown.contains("gy ") && shown.contains("gz ") && shown.contains(" Hz"),
                "{shown}"
            );
        }
    }
}
