//! Where the diagnosis's inputs are not the motion (`diagnose::input_limit`). On runs whose
//! angles come from a slower, noisier reference (120 Hz, linearly interpolated, coloured noise
//! of 0.2 mrad: the inputs computed from them are noise at the band's top, above all the
//! accelerometer's, whose specific force takes the angles' second derivatives), the auto band
//! ends where the usable band does, the report says so, and the paper's model the search starts
//! from is nearer the truth than over the whole band asked for (four cruise seeds, measured:
//! the accelerometer's `K_base` 0.48 / 0.92 / 0.56 / 1.08 % off, against 1.67 / 2.59 / 1.22 /
//! 1.83 % over 0.1-40 Hz; its band ends at 3.7-4.3 Hz). A band the
//! user gives is kept, with the same limit said as a warning. A true accelerometer lag on the
//! same reference keeps the whole band (the identifier gives it its pole): set aside where the
//! accelerometer's inputs are their noise, named with less noise. On seeds where the band is not
//! ended, no sensor effect is named either. On a
//! clean run nothing is said and the whole band is searched. The diagnosis sees the loaded run only; the truth is read
//! here, from the simulation.

#![expect(
    clippy::float_cmp,
    reason = "the bands are copied from the settings and the limit, not computed: equal exactly"
)]

use imu_attest::diagnose::{DiagnoseOptions, Report, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::band::BandSetting;
use imu_attest::ident::settings::Settings;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};

use crate::common::sim as sim_common;

const SEARCHED: [f64; 2] = [0.1, 40.0];

/// A 120 s cruise run at 500 Hz of `seed`, with `effects` hidden and the stand's angle
/// measurement as `stand` says.
fn cruise_run(
    seed: u64,
    effects: &[&str],
    stand: StandImperfections,
) -> (SimulatedRun, imu_attest::run::Run) {
    let mut config = SimConfig::new(Regime::Cruise);
    config.seed = seed;
    config.duration_s = 120.0;
    config.rate_hz = 500.0;
    config.effects = effects.iter().map(|e| e.parse().expect("effect spec")).collect();
    config.stand = stand;
    sim_common::simulated_run(&config)
}

/// A slower, noisier reference: 120 Hz linearly interpolated, 0.2 mrad of coloured noise.
fn slow_noisy() -> StandImperfections {
    StandImperfections {
        coloured_noise_rad: 2e-4,
        coloured_corner_hz: StandImperfections::real().coloured_corner_hz,
        reference_rate_hz: Some(120.0),
        ..StandImperfections::default()
    }
}

/// `||K_base - K_true||_F / ||K_true||_F` of `block` in `report`.
fn k_base_error(report: &Report, sim: &SimulatedRun, block: &str) -> f64 {
    let truth = &sim.sidecar.truth;
    let k_true = match block {
        "gyro" => truth.gyro.as_ref(),
        _ => truth.accel.as_ref(),
    }
    .expect("the block's truth")
    .k;
    let k = report.blocks[block].k_base;
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..3 {
        for j in 0..3 {
            num += (k[i][j] - k_true[i][j]).powi(2);
            den += k_true[i][j].powi(2);
        }
    }
    (num / den).sqrt()
}

#[test]
fn a_noisy_slower_reference_ends_the_band_and_the_base_model_is_nearer_the_truth() {
    let given = Settings {
        band_hz: BandSetting::Fixed(SEARCHED),
        ..Settings::default()
    };
    let (mut ended_sum, mut given_sum) = (0.0, 0.0);
    for seed in [5_u64, 6, 7, 8] {
        let (sim, run) = cruise_run(seed, &[], slow_noisy());
        let auto = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let whole = diagnose_run(&run, &given, &DiagnoseOptions::default()).expect("diagnosed");
        let accel = &auto.blocks["accel"];
        let limit = accel
            .input_limit
            .as_ref()
            .unwrap_or_else(|| panic!("seed {seed}: the accelerometer's noisy inputs not said"));
        assert!(limit.band_ended, "seed {seed}: the auto band not ended");
        assert_eq!(limit.searched_hz, SEARCHED, "seed {seed}");
        assert!(accel.band_hz[1] < SEARCHED[1], "seed {seed}: {:?}", accel.band_hz);
        assert!(
            limit.words("accel").contains("the diagnosis searched"),
            "seed {seed}"
        );
        // No sensor effect is named on the ended band (over the whole band the accelerometer
        // was given a lag on all four seeds, and a lever-arm error on three: measured 27 Nov).
        assert!(
            auto.findings
                .iter()
                .all(|f| f.effect.is_stand_side() || f.block.name() != "accel"),
            "seed {seed}: {:?}",
            auto.findings.iter().map(|f| f.effect).collect::<Vec<_>>()
        );
        // The user's band: kept, the same limit said as a warning.
        let kept = &whole.blocks["accel"];
        assert_eq!(kept.band_hz, SEARCHED, "seed {seed}: the given band not kept");
        let said = kept
            .input_limit
            .as_ref()
            .expect("the limit said on the given band");
        assert!(!said.band_ended && said.words("accel").contains("of the given band"));
        let (e_ended, e_whole) = (
            k_base_error(&auto, &sim, "accel"),
            k_base_error(&whole, &sim, "accel"),
        );
        eprintln!(
            "seed {seed}: accel searched {:?}; K_base off {:.3} % (ended) vs {:.3} % (whole band)",
            accel.band_hz,
            100.0 * e_ended,
            100.0 * e_whole
        );
        ended_sum += e_ended;
        given_sum += e_whole;
    }
    assert!(
        ended_sum < 0.8 * given_sum,
        "the ended band's K_base is not nearer the truth: {ended_sum} vs {given_sum} (sum over seeds)"
    );
}

/// A true accelerometer lag (3.5-4.7 ms) on the same slower, noisier reference: its gain droop
/// is an even gain at first order too, but the identifier (auto order) gives the block its pole,
/// so the band is not ended. (Without that test the band ended at 3.5 Hz and the lag was lost,
/// unsaid: `no_missing_effect`.) The search finds it over the band; the band below, where a
/// smooth finding must be confirmed, ends where the accelerometer's outputs stop being coherent
/// with its inputs (3.7-4.0 Hz), where its droop is within K's deviation: set aside, and said. On
/// the same reference with a quarter of the noise it is named.
#[test]
fn a_true_lag_keeps_the_whole_band_and_is_set_aside_or_named_as_the_noise_allows() {
    for seed in [3_u64, 5] {
        let (_, run) = cruise_run(seed, &["sensor_lag:accel"], slow_noisy());
        // With the order selection on (the default) and with the order fixed at 0 (the
        // identifier's order selection is still asked: without it the lag was lost).
        for settings in [r"{}", r#"{"order": 0}"#] {
            let settings: Settings = serde_json::from_str(settings).expect("settings");
            let report = diagnose_run(&run, &settings, &DiagnoseOptions::default()).expect("diagnosed");
            let accel = &report.blocks["accel"];
            assert_eq!(accel.band_hz, SEARCHED, "seed {seed}: {:?}", accel.input_limit);
            let noisy = accel.noisy_angles.as_ref().expect("the noisy range");
            let own = noisy.usable_top_hz.expect("the accelerometer's own range");
            assert!(
                noisy.angles.is_some_and(|a| own < a.from_hz) && noisy.below_top_hz() == Some(own),
                "{noisy:?}"
            );
            assert!(
                noisy.set_aside.contains(&Effect::SensorLag),
                "seed {seed}: {noisy:?}"
            );
            let words = noisy.words("accel").expect("said");
            assert!(
                words.contains("sensor_lag") && words.contains("not named"),
                "{words}"
            );
        }
        let quieter = StandImperfections {
            coloured_noise_rad: 5e-5,
            ..slow_noisy()
        };
        let (_, run) = cruise_run(seed, &["sensor_lag:accel"], quieter);
        named_on_whole_band(&run, &Settings::default(), "accel", Effect::SensorLag, seed);
    }
}

/// Clean runs on the slower, noisier reference of seeds the input limit was not measured on
/// (10-12): its band is not ended there (the gain's fall moves K less than its deviation), and
/// the search finds a lag and a lever-arm error over the band, where the accelerometer's inputs
/// are their noise from about 4 Hz. Confirmed below the angles' range alone (from 9.7-10.8 Hz),
/// both were named on all three; below where the accelerometer's own coherence ends, they are
/// set aside and said.
#[test]
fn on_unseen_seeds_no_sensor_effect_is_named_where_the_block_s_inputs_are_noise() {
    for seed in [10_u64, 11, 12] {
        let (_, run) = cruise_run(seed, &[], slow_noisy());
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
        assert!(
            report
                .findings
                .iter()
                .all(|f| f.effect.is_stand_side() || f.block.name() != "accel"),
            "seed {seed}: {named:?}"
        );
        let noisy = report.blocks["accel"]
            .noisy_angles
            .as_ref()
            .expect("the noisy range");
        assert!(
            noisy.usable_top_hz.is_some_and(|f| f < 5.0) && !noisy.set_aside.is_empty(),
            "seed {seed}: {noisy:?}"
        );
    }
}

/// A mount resonance just above the stand's 30 Hz band limit (`--stand real`): below it the
/// resonance raises the gyro's gain with little phase and the coherence falls above the band
/// limit, but a rising gain is not the inputs' noise: the band is kept and the resonance named.
/// (Before the sign was asked, seed 20's band ended at 28.4 Hz and a g-sensitivity was named
/// instead of the resonance at 31.2 Hz.)
#[test]
fn a_resonance_above_the_stand_s_band_limit_keeps_the_whole_band() {
    let (_, run) = cruise_run(20, &["platform_resonance:gyro"], StandImperfections::real());
    named_on_whole_band(&run, &Settings::default(), "gyro", Effect::PlatformResonance, 20);
}

fn named_on_whole_band(
    run: &imu_attest::run::Run,
    settings: &Settings,
    block: &str,
    effect: Effect,
    seed: u64,
) {
    let report = diagnose_run(run, settings, &DiagnoseOptions::default()).expect("diagnosed");
    let b = &report.blocks[block];
    assert_eq!(b.band_hz, SEARCHED, "seed {seed}: {:?}", b.input_limit);
    let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
    assert!(
        report
            .findings
            .iter()
            .any(|f| f.block.name() == block && f.effect == effect),
        "seed {seed}: {effect} not named: {named:?}"
    );
}

#[test]
fn a_clean_run_is_searched_over_the_whole_band_and_nothing_is_said() {
    for seed in [1_u64, 2] {
        let (_, run) = sim_common::simulated_run_of(120.0, Regime::ALL[seed as usize], seed, &[]);
        let report =
            diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
        for (name, b) in &report.blocks {
            assert!(
                b.input_limit.is_none(),
                "seed {seed}: {name}: {:?}",
                b.input_limit
            );
            assert_eq!(b.band_hz[0], SEARCHED[0], "seed {seed}: {name}");
            assert_eq!(b.band_hz[1], SEARCHED[1], "seed {seed}: {name}");
        }
    }
}

/// An accelerometer mount resonance at 23.6 Hz on a `--stand real` run (30 Hz band limit): the
/// accelerometer's band ends below the limit, the resonance inside it is named, and no line is
/// searched above the ended band, where the residual is the model driven by the angles' noise
/// (searched there, its roll-off passed for tones at 27-38 Hz).
#[test]
fn above_an_ended_band_no_tone_is_named() {
    let (_, run) = cruise_run(3, &["platform_resonance:accel"], StandImperfections::real());
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let accel = &report.blocks["accel"];
    assert!(
        accel.band_hz[1] < SEARCHED[1],
        "the band not ended: {:?}",
        accel.band_hz
    );
    let named: Vec<_> = report.findings.iter().map(|f| (f.block, f.effect)).collect();
    assert!(
        named
            .iter()
            .any(|&(b, e)| b.name() == "accel" && e == Effect::PlatformResonance),
        "{named:?}"
    );
    assert!(
        !named
            .iter()
            .any(|&(b, e)| b.name() == "accel" && e == Effect::VibrationTone),
        "{named:?}"
    );
}
