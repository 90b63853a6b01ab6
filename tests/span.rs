//! `span_s`: identify a stretch of the record. A run whose gyro logger started 30 s late (its
//! outputs zero until then) is refused as a whole (no coherent band for the gyro, which
//! witnesses every block's angle noise) or its gyro spoilt, and identified right over the span
//! after the start; a span outside the record is refused with the record's extent (exit status 2).

use std::path::Path;
use std::process::Command;

use imu_attest::block::Block;
use imu_attest::ident::IdentError;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::{Settings, SettingsError};
use imu_attest::ident::structural::StructuralFit;
use imu_attest::run::{LoadOptions, Run, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

fn gyro_fit(run: &Run, settings: &Settings) -> StructuralFit {
    let id = identify_run(run, settings).expect("identified");
    assert!(id.refused.is_empty(), "{:?}", id.refused);
    let gyro = id
        .blocks
        .into_iter()
        .find(|b| b.block == Block::Gyro)
        .expect("the gyro");
    (*gyro.structural).clone()
}

/// The clean run and a copy whose gyro outputs are zero for the first `dead_s` seconds.
fn runs(dir: &Path, dead_s: f64) -> (Run, Run) {
    let mut config = SimConfig::new(Regime::Approach);
    config.seed = 77;
    config.duration_s = 150.0;
    let mut sim = simulate(&config).expect("simulated");
    let clean_path = dir.join("clean.csv");
    write_run(&sim, &clean_path).expect("written");
    let dead = sim.time_s.iter().take_while(|&&t| t < dead_s).count();
    for c in sim.gyro.as_mut().expect("gyro") {
        c[..dead].fill(0.0);
    }
    let late_path = dir.join("late.csv");
    write_run(&sim, &late_path).expect("written");
    let options = LoadOptions::default();
    (
        load(&clean_path, &options).expect("loads"),
        load(&late_path, &options).expect("loads"),
    )
}

#[test]
fn a_span_after_a_late_start_gives_the_clean_run_s_gain() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (clean, late) = runs(dir.path(), 30.0);
    let reference = gyro_fit(&clean, &Settings::default());
    let spanned = Settings {
        span_s: Some([35.0, 149.0]),
        ..Settings::default()
    };
    let span = gyro_fit(&late, &spanned);
    let worst = |fit: &StructuralFit| {
        (0..9)
            .map(|e| {
                let (i, j) = (e / 3, e % 3);
                (fit.k[i][j] - reference.k[i][j]).abs() / span.k_std[i][j]
            })
            .fold(0.0, f64::max)
    };
    eprintln!(
        "span: worst |K - K_clean| {:.2} sigma; tau {:.4} vs {:.4} ms",
        worst(&span),
        span.tau_s * 1e3,
        reference.tau_s * 1e3
    );
    // As a whole, the dead start is refused (no band where the gyro's outputs are coherent with
    // the inputs: a gyro's refusal is the run's) or spoils the gyro's K.
    match identify_run(&late, &Settings::default()) {
        Err(e) => assert!(matches!(e, IdentError::NoUsableBand { block: "gyro", .. }), "{e}"),
        Ok(id) => {
            let gyro = id
                .blocks
                .iter()
                .find(|b| b.block == Block::Gyro)
                .expect("a gyro's refusal refuses the run");
            assert!(
                worst(&gyro.structural) > 10.0,
                "the dead start spoils the whole record's K"
            );
        }
    }
    // What lies outside the span hardly matters: the clean run over the same span gives the same
    // K and tau to a tenth of their standard deviations (the outputs differ only before the span;
    // the angles not at all; the observer's noise model, estimated from the gyro's outputs over
    // the whole record, is the median of five stretches and ignores the dead one).
    let clean_span = gyro_fit(&clean, &spanned);
    for i in 0..3 {
        for j in 0..3 {
            let sigma = span.k_std[i][j];
            assert!(
                (span.k[i][j] - clean_span.k[i][j]).abs() < 0.1 * sigma,
                "K[{i}][{j}]: {} vs {} (sigma {sigma:e})",
                span.k[i][j],
                clean_span.k[i][j]
            );
        }
    }
    assert!((span.tau_s - clean_span.tau_s).abs() < 0.1 * span.tau_std_s);
    // And it agrees with the whole clean record's within the span's own uncertainty (loosely:
    // the two share most of their data, and the gyro's sigma runs about 1.5x small, README).
    assert!(worst(&span) < 5.0, "span K off by {} sigma", worst(&span));
    assert!((span.tau_s - reference.tau_s).abs() < 5.0 * span.tau_std_s);
}

#[test]
fn a_span_outside_the_record_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (clean, _) = runs(dir.path(), 0.0);
    for span in [[-5.0, 10.0], [20.0, 10.0], [100.0, 400.0], [f64::NAN, 10.0]] {
        let settings = Settings {
            span_s: Some(span),
            ..Settings::default()
        };
        let err = identify_run(&clean, &settings).expect_err("refused");
        assert!(
            matches!(err, IdentError::Settings(SettingsError::Span { .. })),
            "{span:?}: {err}"
        );
    }
    // Through the binary: exit 2, one line naming the record's extent.
    let settings_path = dir.path().join("s.json");
    std::fs::write(&settings_path, r#"{"span_s": [100.0, 400.0]}"#).expect("written");
    let out = Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .arg("identify")
        .arg(dir.path().join("clean.csv"))
        .arg("--settings")
        .arg(&settings_path)
        .arg("--out")
        .arg(dir.path().join("m.json"))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("span_s [100, 400] s"), "{stderr}");
    assert!(!dir.path().join("m.json").exists());
}

/// The settings as used on a span are fitted to, and checked against, the span's samples, not the
/// whole record's: the program's segment shrinks with the span, a given one that the span cannot
/// average enough is refused, and the session refuses the same.
#[test]
fn settings_are_used_on_the_span_s_samples() {
    use imu_attest::ident::session::Session;
    let dir = tempfile::tempdir().expect("temp dir");
    let (clean, _) = runs(dir.path(), 0.0);
    let start = clean.time_s[0];
    let whole = Settings::default().used_on(&clean).expect("whole record");
    assert_eq!(whole.welch.segment_len, 4096, "150 s at 500 Hz keeps 4096");
    // 30 s = 15000 samples: 4096 leaves 6 segments, 2048 leaves 13 (the program's rule: 12).
    let short = Settings {
        span_s: Some([start + 20.0, start + 50.0]),
        ..Settings::default()
    };
    let used = short
        .used_on(&clean)
        .expect("the program's segment fits the span");
    assert_eq!(used.welch.segment_len, 2048);
    let mut given = short.clone();
    given.welch.segment_auto = false;
    given.welch.segment_len = 4096;
    let err = given.used_on(&clean).expect_err("6 segments of 4096");
    assert!(
        matches!(err, SettingsError::TooFewSegments { segments: 6, .. }),
        "{err}"
    );
    // The same 4096 over the whole record is fine.
    given.span_s = None;
    assert!(given.used_on(&clean).is_ok());
    // The session (the app's and the command line's pipeline) refuses exactly so.
    given.span_s = short.span_s;
    let mut session = Session::new(std::sync::Arc::new(clean.clone()));
    let refused = session.identify_aside(&given).expect_err("refused");
    assert!(
        matches!(
            refused,
            IdentError::Settings(SettingsError::TooFewSegments { segments: 6, .. })
        ),
        "{refused}"
    );
    let outside = Settings {
        span_s: Some([start - 5.0, start + 10.0]),
        ..Settings::default()
    };
    assert!(matches!(outside.used_on(&clean), Err(SettingsError::Span { .. })));
}
