//! The held-out validation of the order choice through the whole pipeline (issue 13, item 4):
//! every candidate carries its held-out chi2 (fitted to one half of the record, predicting the
//! other) whenever the record can be halved, a real sensor lag is kept because it predicts the
//! other half, and a record too short to halve says nothing rather than something invented.
//! The closed-form and statistical checks of the figure itself are unit tests
//! (`src/ident/structural/tests_holdout.rs`).

use imu_attest::block::Block;
use imu_attest::ident::identify::{RunIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};
use imu_attest::spectral::WelchSettings;

fn identified(duration_s: f64, effects: &[&str], seed: u64) -> RunIdentification {
    identified_with(duration_s, effects, seed, &Settings::default())
}

fn identified_with(duration_s: f64, effects: &[&str], seed: u64, settings: &Settings) -> RunIdentification {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = duration_s;
    config.rate_hz = 500.0;
    config.seed = seed;
    config.effects = effects.iter().map(|e| e.parse().expect("effect")).collect();
    let path = dir.path().join("run.csv");
    write_run(&simulate(&config).expect("simulated"), &path).expect("written");
    identify_run(&load(&path, &LoadOptions::default()).expect("loads"), settings).expect("identified")
}

fn held_out(id: &RunIdentification, block: Block) -> Vec<Option<f64>> {
    let b = id.blocks.iter().find(|b| b.block == block).expect("block");
    b.structural.candidates.iter().map(|c| c.held_out_chi2).collect()
}

#[test]
fn a_sensor_lag_predicts_the_other_half_and_is_kept() {
    for seed in [3, 4] {
        let id = identified(120.0, &["sensor_lag:gyro"], seed);
        let gyro = id.blocks.iter().find(|b| b.block == Block::Gyro).expect("gyro");
        let h = held_out(&id, Block::Gyro);
        assert!(
            h.len() >= 2 && h.iter().all(Option::is_some),
            "seed {seed}: {h:?}"
        );
        assert_eq!(gyro.structural.order, 1, "seed {seed}: the lag is kept");
        // A real lag behind a positive delay: nothing stands in for anything.
        assert!(
            !gyro
                .warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::DelayAbsorbedByPoles { .. })),
            "seed {seed}: {:?}",
            gyro.warnings
        );
        let (h0, h1) = (h[0].unwrap_or(0.0), h[1].unwrap_or(f64::INFINITY));
        assert!(
            h1 < 0.5 * h0,
            "seed {seed}: order 1 predicts far better: {h1} vs {h0}"
        );
        // The accelerometer has no sensor dynamics: order 0, and its figures are there too.
        let accel = id.blocks.iter().find(|b| b.block == Block::Accel).expect("accel");
        assert_eq!(accel.structural.order, 0, "seed {seed}");
        assert!(held_out(&id, Block::Accel).iter().all(Option::is_some));
    }
}

#[test]
fn a_record_too_short_for_the_stationarity_check_is_still_halved() {
    // 60 s at 500 Hz: 13 Welch segments of 4096 with half overlap, too few for four stretches of
    // six, enough for two halves; the stationarity check is made on segments of 2048 (28 of them,
    // 4 stretches).
    let id = identified(60.0, &[], 5);
    for b in &id.blocks {
        let st = b.stationarity.as_ref().expect("checked on a shorter segment");
        assert_eq!(st.segment_len, Some(2048), "{}", b.block);
        assert_eq!(st.stretches.len(), 4, "{}", b.block);
        let h = held_out(&id, b.block);
        assert!(h.iter().all(Option::is_some), "{}: {h:?}", b.block);
    }
}

#[test]
fn a_record_too_short_to_halve_has_no_held_out_figures() {
    // 40 s with a given segment of 4096: 8 segments, not two halves of six (and said).
    let given = Settings {
        welch: WelchSettings {
            segment_len: 4096,
            segment_auto: false,
            ..WelchSettings::default()
        },
        ..Settings::default()
    };
    let id = identified_with(40.0, &[], 6, &given);
    for b in &id.blocks {
        assert_eq!(b.spectra.n_averages, 8);
        let h = held_out(&id, b.block);
        assert!(h.iter().all(Option::is_none), "{}: {h:?}", b.block);
        assert!(
            b.structural.candidates.iter().all(|c| !matches!(
                c.rejected,
                Some(imu_attest::ident::structural::admissible::Rejection::NotPredictive { .. })
            )),
            "{}: rule 7 is not applied without halves",
            b.block
        );
        assert!(
            b.warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::FewSegments { segments: 8, .. })),
            "{}: {:?}",
            b.block,
            b.warnings
        );
    }
    // The same record with the segment left to the program: 2048, 18 segments, halved.
    let id = identified(40.0, &[], 6);
    for b in &id.blocks {
        assert_eq!((b.spectra.segment_len, b.spectra.n_averages), (2048, 18));
        assert!(held_out(&id, b.block).iter().all(Option::is_some), "{}", b.block);
        assert!(
            !b.warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::FewSegments { .. }))
        );
    }
}

/// The control of the short-record changes: on 40 s (the program's segment: 2048, 18 segments)
/// a real sensor lag is still found and kept, with nothing to say; rule 4 (a negative delay the data
/// cannot tell from the poles' lag) does not touch it, nor the accelerometer's order 0.
#[test]
fn a_sensor_lag_on_a_short_record_is_kept() {
    for seed in [3, 4] {
        let id = identified(40.0, &["sensor_lag:gyro"], seed);
        let gyro = id.blocks.iter().find(|b| b.block == Block::Gyro).expect("gyro");
        assert_eq!(gyro.spectra.segment_len, 2048, "seed {seed}");
        assert_eq!(
            gyro.structural.order, 1,
            "seed {seed}: {:?}",
            gyro.structural.candidates
        );
        assert!(gyro.warnings.is_empty(), "seed {seed}: {:?}", gyro.warnings);
        let accel = id.blocks.iter().find(|b| b.block == Block::Accel).expect("accel");
        assert_eq!(accel.structural.order, 0, "seed {seed}");
    }
}
