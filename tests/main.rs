//! The integration tests, as one test binary.
//!
//! Every file beside this one is a module of it (one concept per file, as before); the helpers
//! are `common` (shared by many files) and `binary` (running the command line). One binary
//! instead of one per file: the ~80 files each linked the whole app (about 48 MB a binary), and
//! `cargo test` ran the binaries one after another, so a file of one long test kept one of the
//! CI machine's two cores idle. Here the harness spreads every test over the cores, and the
//! suite compiles and links once. Run one file's tests with its module name as the filter:
//! `cargo test --release --test integration identify_calibration::` (a substring: `span::` runs
//! `gui_app_span::` too; add `-- --skip gui_app_span` to leave it out).
//!
//! The app's tests (`gui_app*`, and `common::gui`) need the default feature `gui`.

mod binary;
mod common;

mod accept_effects;
mod accept_judged;
mod angle_noise_declared;
mod cli_bad_input;
mod cli_batch;
mod cli_bench;
mod cli_compare;
mod cli_discrepancy;
mod cli_identify;
mod cli_report;
mod cli_simulate;
mod coherent_spans;
mod dead_output;
mod delay_scatter;
mod delay_step;
mod diagnose_clock_std;
mod diagnose_effects;
mod diagnose_false_tones;
mod diagnose_gyro_drift;
mod diagnose_halves;
mod diagnose_input_limit;
mod diagnose_negative_delay;
mod diagnose_noisy_angles;
mod diagnose_not_named;
mod diagnose_real;
mod diagnose_real_skew;
mod diagnose_reference_band_limit;
mod diagnose_resonance_damping;
mod diagnose_sensor_filter;
mod diagnose_size_limit;
mod diagnose_stand;
mod diagnose_tone_limit;
mod diagnose_tone_sizes;
mod diagnose_tones;
mod diagnose_usable_band;
mod diagnose_white_angle_noise;
mod fuzz_parsers;
mod gain_amplitude;
#[cfg(feature = "gui")]
mod gui_app;
#[cfg(feature = "gui")]
mod gui_app_bode;
#[cfg(feature = "gui")]
mod gui_app_diagnosis;
#[cfg(feature = "gui")]
mod gui_app_dialog;
#[cfg(feature = "gui")]
mod gui_app_ident;
#[cfg(feature = "gui")]
mod gui_app_session;
#[cfg(feature = "gui")]
mod gui_app_span;
#[cfg(feature = "gui")]
mod gui_app_trust;
#[cfg(feature = "gui")]
mod gui_app_validation;
mod identify_accuracy;
mod identify_band_top;
mod identify_calibration;
mod identify_gain_pattern;
mod identify_gyro_mount_resonance;
mod identify_holdout;
mod identify_left_out_noise;
mod identify_real;
mod identify_real_fit;
mod identify_sensor_filters;
mod identify_sine_programme;
mod identify_sines;
mod identify_slower_reference;
mod identify_stationarity;
mod identify_suspected_effects;
mod identify_turned_gyro;
mod identify_unchanged;
mod noise_allantools;
mod noise_reference_share;
mod noise_terms;
mod numerical_edges;
mod real_latency_order;
mod recording_faults;
mod refused_blocks;
mod run_loader;
mod run_loader_damage;
mod run_loader_errors;
mod run_loader_sidecar;
mod span;
mod stream_alignment;
mod welch_oracle;
mod welch_properties;
mod welch_scipy;
mod witness_noise_shared;
mod wrapped_angles;

/// Every `.rs` file beside this one is a module of the binary: with `autotests = false` in
/// `Cargo.toml` a file left out of this list would never compile nor run, silently.
#[test]
fn every_test_file_is_a_module_of_the_suite() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let listed = include_str!("main.rs");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).expect("tests/ is readable") {
        let path = entry.expect("a directory entry").path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "rs") && stem != "main" {
            files += 1;
            assert!(
                listed.contains(&format!("\nmod {stem};\n")),
                "tests/{stem}.rs is not declared in tests/main.rs: its tests never run"
            );
        }
    }
    assert!(files > 50, "{files} test files found in {}", dir.display());
}
