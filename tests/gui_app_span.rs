//! The stretch to analyse, selected as a lab engineer would: shift+drag over the Time series
//! (issue 16). A plain drag pans and selects nothing; a shift+drag sends `span_s` and the run is
//! identified over it. AccessKit (`egui_kittest`) with raw pointer events, no GPU; the worker runs
//! synchronously.

use eframe::egui::{self, Modifiers, PointerButton, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use imu_attest::gui::view::timeseries::dragged_span;
use imu_attest::gui::{App, WorkerMode, sample_run_path};

use crate::common::gui as gui_common;

/// Presses at `from`, moves to `to` in four steps and releases, with `modifiers` held.
fn drag(harness: &mut Harness<'_, App>, from: Pos2, to: Pos2, modifiers: Modifiers) {
    drag_with(harness, from, to, modifiers, PointerButton::Primary);
}

/// [`drag`] with `button`.
fn drag_with(
    harness: &mut Harness<'_, App>,
    from: Pos2,
    to: Pos2,
    modifiers: Modifiers,
    button: PointerButton,
) {
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button,
        pressed,
        modifiers,
    };
    let events = &mut harness.input_mut().events;
    events.push(egui::Event::ModifiersChanged(modifiers));
    events.push(egui::Event::PointerMoved(from));
    harness.run_steps(1);
    harness.input_mut().events.push(button(from, true));
    harness.run_steps(1);
    for step in 1..=4 {
        let pos = from + (to - from) * (step as f32 / 4.0);
        harness.input_mut().events.push(egui::Event::PointerMoved(pos));
        harness.run_steps(1);
    }
    harness.input_mut().events.push(button(to, false));
    harness.run_steps(1);
    let events = &mut harness.input_mut().events;
    events.push(egui::Event::ModifiersChanged(Modifiers::NONE));
    harness.run_steps(3);
}

#[test]
fn a_shift_drag_over_the_time_series_selects_the_stretch_the_run_is_identified_over() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    let summary = harness.state().runs()[0].summary().cloned().expect("loaded");
    let (start, end) = (summary.start_s, summary.start_s + summary.duration_s);
    // Over the first (angles) plot, in the central panel between the side panels.
    let (from, to) = (Pos2::new(520.0, 160.0), Pos2::new(860.0, 160.0));

    drag(&mut harness, from, to, Modifiers::SHIFT);
    let span = harness
        .state()
        .settings()
        .span_s
        .expect("a shift+drag selects a stretch");
    assert!(
        start <= span[0] && span[0] < span[1] && span[1] <= end,
        "{span:?} inside [{start}, {end}]"
    );
    // A third of the plot's width or so: neither a sliver nor the whole record.
    let share = (span[1] - span[0]) / (end - start);
    assert!(share > 0.05 && share < 0.9, "{span:?} is {share} of the record");
    let id = harness.state().runs()[0]
        .identification
        .value
        .clone()
        .expect("identified");
    assert_eq!(id.settings.span_s, Some(span), "identified over the stretch");
    harness.get_by_label(&format!(
        "gyro analysed over t = {:.2} to {:.2} s of the record",
        span[0], span[1]
    ));
    // The shading is named in the first plot's key, with its times.
    harness.get_by_label("Time series").click();
    harness.run_steps(2);
    harness.get_by_label(&imu_attest::gui::view::timeseries::span_key(span));

    // A plain drag pans the time axis and leaves the stretch as it is.
    drag(&mut harness, to, from, Modifiers::NONE);
    assert_eq!(harness.state().settings().span_s, Some(span), "a plain drag pans");
}

#[test]
fn a_dragged_span_is_clamped_to_the_record_and_refused_when_shorter_than_16_samples() {
    assert_eq!(dragged_span(5.0, 2.0, 0.0, 10.0, 0.01), Some([2.0, 5.0]));
    assert_eq!(dragged_span(-3.0, 20.0, 0.0, 10.0, 0.01), Some([0.0, 10.0]));
    assert_eq!(dragged_span(4.0, 4.1, 0.0, 10.0, 0.01), None);
    assert_eq!(dragged_span(4.0, 4.16, 0.0, 10.0, 0.01), Some([4.0, 4.16]));
    assert_eq!(dragged_span(f64::NAN, 4.0, 0.0, 10.0, 0.01), None);
    assert_eq!(
        dragged_span(11.0, 12.0, 0.0, 10.0, 0.01),
        None,
        "outside the record"
    );
}

/// The settings panel checks a stretch's samples, as the pipeline does: a given segment of 4096
/// is fine for the whole 120 s sample but refused, in the panel, for 30 s of it.
#[test]
fn the_settings_panel_checks_the_segment_against_the_stretch() {
    use imu_attest::gui::app::Command;
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    let start = harness.state().runs()[0].summary().expect("loaded").start_s;
    let mut settings = harness.state().settings().clone();
    settings.welch.segment_auto = false;
    settings.welch.segment_len = 4096;
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings.clone())));
    harness.run_steps(3);
    let refusal = "too few samples for the chosen spectral segment";
    assert!(
        harness.query_by_label_contains(refusal).is_none(),
        "the whole record holds 28 segments"
    );
    settings.span_s = Some([start + 20.0, start + 50.0]);
    harness
        .state_mut()
        .push_command(Command::SetSettings(Box::new(settings)));
    harness.run_steps(3);
    // 30 s at 500 Hz, both ends in: 15001 samples.
    harness.get_by_label_contains(&format!(
        "for cruise.csv.gz: welch: {refusal}: 15001 samples hold 6 segments of 4096"
    ));
}

/// The stretch belongs to the run it was chosen on: the preferences a new launch starts from
/// keep every other setting but not the span.
#[test]
fn a_stretch_is_not_carried_into_the_next_launch() {
    use imu_attest::gui::app::Prefs;
    use imu_attest::ident::settings::OrderSetting;
    let mut prefs = Prefs::default();
    prefs.settings.span_s = Some([60.0, 110.0]);
    prefs.settings.order = OrderSetting::Fixed(1).into();
    let json = serde_json::to_string(&prefs).expect("serialises");
    let back = Prefs::restored(&json).expect("reads back");
    assert_eq!(back.settings.span_s, None);
    assert_eq!(
        back.settings.order, prefs.settings.order,
        "the other settings are kept"
    );
    assert!(Prefs::restored("{not json").is_none());
}

/// Preferences written before the segment could be left to the program carried the default's
/// 4096 as a number: read back, it is the program's again, while a segment picked since (4096
/// included) stays the user's.
#[test]
fn the_segment_of_older_preferences_is_the_programs_and_a_picked_one_is_kept() {
    use imu_attest::gui::app::Prefs;
    let older = r#"{"settings": {"welch": {"segment_len": 4096, "overlap": 0.5}}, "recent": []}"#;
    let back = Prefs::restored(older).expect("reads");
    assert!(back.settings.welch.segment_auto);
    let older_picked = r#"{"settings": {"welch": {"segment_len": 1024}}}"#;
    let back = Prefs::restored(older_picked).expect("reads");
    assert!(!back.settings.welch.segment_auto && back.settings.welch.segment_len == 1024);
    let mut prefs = Prefs::default();
    assert!(prefs.settings.welch.segment_auto);
    prefs.settings.welch.segment_auto = false;
    let json = serde_json::to_string(&prefs).expect("serialises");
    let back = Prefs::restored(&json).expect("reads back");
    assert!(!back.settings.welch.segment_auto && back.settings.welch.segment_len == 4096);
    let auto = serde_json::to_string(&Prefs::default()).expect("serialises");
    assert!(Prefs::restored(&auto).expect("reads").settings.welch.segment_auto);
}

/// Right-click sets cursor A; hovering elsewhere reads the time since A and each value's change
/// from it; Esc clears A.
#[test]
fn a_right_click_sets_cursor_a_and_the_read_out_gives_the_differences() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    let (a, b) = (Pos2::new(560.0, 160.0), Pos2::new(820.0, 160.0));
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button: PointerButton::Secondary,
        pressed,
        modifiers: Modifiers::NONE,
    };
    harness.input_mut().events.push(egui::Event::PointerMoved(a));
    harness.run_steps(1);
    harness.input_mut().events.push(button(a, true));
    harness.input_mut().events.push(button(a, false));
    harness.run_steps(2);
    let t_a = harness.state().view().reference_t.expect("cursor A set");
    harness.input_mut().events.push(egui::Event::PointerMoved(b));
    harness.run_steps(2);
    harness.get_by_label_contains("Δt from A = +");
    harness.get_by_label_contains("(Δ ");
    // The pointer right of A: a positive interval; A inside the record.
    let summary = harness.state().runs()[0].summary().cloned().expect("loaded");
    assert!(t_a > summary.start_s && t_a < summary.start_s + summary.duration_s);
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert_eq!(harness.state().view().reference_t, None);
}

/// A right-drag over the angles plot zooms it to that box: its time range and its value range
/// both shrink to inside what was shown; a right-click alone still only sets cursor A.
#[test]
fn a_right_drag_zooms_the_time_series_to_a_box() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    let before = harness.state().view().time_series_bounds.expect("shown");
    let (from, to) = (Pos2::new(560.0, 100.0), Pos2::new(760.0, 170.0));
    drag_with(&mut harness, from, to, Modifiers::NONE, PointerButton::Secondary);
    let after = harness.state().view().time_series_bounds.expect("shown");
    let inside = |a: f64, b: f64, lo: f64, hi: f64| lo <= a && a < b && b <= hi;
    assert!(
        inside(after[0], after[1], before[0], before[1])
            && after[1] - after[0] < 0.5 * (before[1] - before[0]),
        "time {before:?} -> {after:?}"
    );
    assert!(
        inside(after[2], after[3], before[2], before[3])
            && after[3] - after[2] < 0.7 * (before[3] - before[2]),
        "values {before:?} -> {after:?}"
    );
    assert_eq!(harness.state().view().reference_t, None, "a drag is not a click");
}

/// Dragging the value axis of the angles plot zooms its values only: the time range stays.
#[test]
fn dragging_the_value_axis_zooms_the_values_only() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    let before = harness.state().view().time_series_bounds.expect("shown");
    // On the y axis, left of the plot frame (its tick labels), dragged up.
    drag(
        &mut harness,
        Pos2::new(420.0, 150.0),
        Pos2::new(420.0, 100.0),
        Modifiers::NONE,
    );
    let after = harness.state().view().time_series_bounds.expect("shown");
    assert!(
        (after[0] - before[0]).abs() < 1e-9 && (after[1] - before[1]).abs() < 1e-9,
        "{before:?} -> {after:?}"
    );
    let (span0, span1) = (before[3] - before[2], after[3] - after[2]);
    assert!(
        (span1 / span0 - 1.0).abs() > 0.05,
        "values zoomed: {before:?} -> {after:?}"
    );
}

/// Each Time series plot is keyed by a row above it, every trace in its colour: a legend inside
/// the plot covered the traces' top right (issue 16). The key of the angles sits above the key of
/// the gyro outputs, each above its own plot.
#[test]
fn the_time_series_key_sits_above_each_plot() {
    let mut harness = gui_common::app(
        gui_common::options(vec![sample_run_path().expect("sample")], WorkerMode::Synchronous),
        4,
    );
    harness.get_by_label("Time series").click();
    harness.run_steps(3);
    let roll = harness.get_by_label("— roll").rect();
    for name in ["yaw", "pitch", "wx", "wy", "wz", "gy", "gz", "fx", "ax", "az"] {
        harness.get_by_label(&format!("— {name}"));
    }
    let gx = harness.get_by_label("— gx").rect();
    let wx = harness.get_by_label("— wx").rect();
    assert!(
        roll.bottom() <= wx.top() && wx.bottom() <= gx.top(),
        "{roll:?} {wx:?} {gx:?}"
    );
    // Between two keys there is a whole plot, not just the next row.
    assert!(wx.top() - roll.bottom() > 60.0, "{roll:?} {wx:?}");
}
