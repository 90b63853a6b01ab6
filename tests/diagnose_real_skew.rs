//! A real recording (BROAD, CC BY 4.0: `tests/data/real/README.md`) with one gyro channel
//! written 3 ms late (interpolated here, the recording otherwise as it is): the diagnosis names
//! the channel skew with each channel's delay where it is (the recording's own 4.2-4.5 ms, the
//! delayed channel 3 ms later), and no mount resonance. Before, "resonances" damped 0.57-0.60 at
//! 22-28 Hz were added after the skew, each taking 6.5-8.8 ms from its channel's delay: the skew
//! was reported with channels at -2.5 ms and -7.1 ms.

use std::path::Path;

use imu_attest::diagnose::{DiagnoseOptions, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::interp::lagrange;
use imu_attest::run::{LoadOptions, Run, load};

fn real(name: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    load(&path, &LoadOptions::default()).expect("the real run loads")
}

/// The channel delays the diagnosis reports for the skew (none without a skew finding), and
/// whether it named a resonance.
fn skew_of(run: &Run) -> (Option<[f64; 3]>, bool) {
    let report = diagnose_run(run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let skew = report
        .findings
        .iter()
        .find(|f| f.effect == Effect::AxisTimeSkew)
        .map(|f| {
            let d = &f.parameters["channel_delay_s"];
            [0, 1, 2].map(|i| d[i].as_f64().expect("a delay"))
        });
    let resonance = report
        .findings
        .iter()
        .any(|f| f.effect == Effect::PlatformResonance);
    (skew, resonance)
}

#[test]
fn a_real_gyro_channel_delayed_3_ms_is_a_skew_of_3_ms_and_no_resonance() {
    for (name, channel, delay) in [
        ("broad07_fast_rotation", 0, 3e-3),
        ("broad07_fast_rotation", 1, -3e-3),
        ("broad25_tapping", 1, -3e-3),
        ("broad25_tapping", 2, 3e-3),
    ] {
        let mut run = real(name);
        let rate = run.sample_rate_hz;
        let g = &mut run.gyro.as_mut().expect("a gyro")[channel];
        let original = g.clone();
        for (i, v) in g.iter_mut().enumerate() {
            *v = lagrange(&original, rate, i as f64 / rate - delay);
        }
        let (skew, resonance) = skew_of(&run);
        let d = skew.unwrap_or_else(|| panic!("{name}: no skew found"));
        eprintln!("{name}: gyro channel {channel} {delay} s -> channel delays {d:?}");
        assert!(!resonance, "{name}: a resonance named");
        // The recording's own delays (README there): 4.2 ms, the slow run's y channel 4.5 ms.
        for (i, di) in d.iter().enumerate() {
            let expected = if i == channel { 4.17e-3 + delay } else { 4.17e-3 };
            assert!(
                (di - expected).abs() < 0.1e-3,
                "{name}: channel {i} at {di} s, not {expected}"
            );
        }
    }
}
