//! Significant candidates the search does not name are said, with the reason
//! (`diagnose::not_named`). A true mount resonance on the gyro's roll axis (cruise, seed 21, 120 s,
//! 0.2 mrad coloured angle noise) pays the criterion by far (gain about 1000) and closes the
//! worst channel's gap by 0.8 dB, yet its refit opens another channel's by 0.013 dB, beyond the
//! rule's numerical tolerance: it is not a finding, and until 29 Nov the run read
//! `no_missing_effect` with nothing said. Now the block's report keeps the refusal and the words
//! are a warning. A lightly damped mode fitted at the band's edge beside weaker findings is a
//! warning that points to a wider band (where it is named); one damped beyond a peak, a note.
//! The diagnosis sees the loaded run only; the hidden mode's frequency is read by the test from
//! the simulator's truth.

use imu_attest::block::Block;
use imu_attest::diagnose::not_named::Reason;
use imu_attest::diagnose::{DiagnoseOptions, Verdict, diagnose_run};
use imu_attest::effect::Effect;
use imu_attest::ident::settings::Settings;
use imu_attest::run::Run;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::truth::EffectTruth;
use imu_attest::sim::{SimConfig, SimulatedRun};

use crate::common::sim as sim_common;

fn run_of(regime: Regime, seed: u64, coloured_rad: f64, effects: &[&str]) -> (SimulatedRun, Run) {
    let stand = StandImperfections {
        coloured_noise_rad: coloured_rad,
        coloured_corner_hz: StandImperfections::real().coloured_corner_hz,
        ..StandImperfections::default()
    };
    let mut config = SimConfig::new(regime);
    (config.seed, config.duration_s, config.rate_hz) = (seed, 120.0, 500.0);
    config.stand = stand;
    config.effects = effects.iter().map(|e| e.parse().expect("effect spec")).collect();
    sim_common::simulated_run(&config)
}

#[test]
fn a_significant_resonance_refused_by_the_gap_rule_is_said_as_a_warning() {
    let (_, run) = run_of(Regime::Cruise, 21, 2e-4, &["platform_resonance:gyro"]);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let gyro = &report.blocks["gyro"];
    // (Should a mend of the rule name the mode, this test is to change with it.)
    assert!(report.findings.is_empty(), "{:?}", report.findings);
    assert_eq!(report.verdict, Verdict::NoMissingEffect);
    let resonance = gyro
        .not_named
        .iter()
        .find(|r| r.effect == Effect::PlatformResonance)
        .unwrap_or_else(|| panic!("the resonance not said: {:?}", gyro.not_named));
    assert!(resonance.criterion_gain > 100.0, "{resonance:?}");
    let Reason::OpensGap {
        channel,
        before_db,
        after_db,
        worst_before_db,
        worst_after_db,
    } = &resonance.reason
    else {
        panic!("not named for another reason: {resonance:?}");
    };
    // A channel opened beyond the tolerance but by little, the worst closed by much.
    assert!(
        *after_db > before_db + 0.005 && *after_db < before_db + 0.1,
        "{resonance:?}"
    );
    assert!(*worst_after_db < worst_before_db - 0.3, "{resonance:?}");
    let (words, warning) = report.not_named_words("gyro").expect("words");
    eprintln!("{words}");
    assert!(warning, "said only as a note: {words}");
    assert!(
        words.contains("platform_resonance (gain") && words.contains(&format!("open {channel}'s gap")),
        "{words}"
    );
}

/// A true 30 Hz mount resonance (damping 0.05) on a turbulent cruise run with 0.1 mrad coloured
/// angle noise: the band found ends at about 28.6 Hz, the mode fits at that edge (out of reach)
/// and weaker effects are named in its place. Said as a warning that points to a wider band, and
/// with that band the mode is named near its true frequency.
#[test]
fn a_lightly_damped_mode_at_the_band_edge_is_said_and_a_wider_band_names_it() {
    let (sim, run) = run_of(Regime::TurbulentCruise, 21, 1e-4, &["platform_resonance:gyro"]);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let gyro = &report.blocks["gyro"];
    let (gain, hz, damping) = gyro
        .not_named
        .iter()
        .find_map(|r| match r.reason {
            Reason::OutOfReach {
                frequency_hz,
                damping,
            } if r.effect == Effect::PlatformResonance => Some((r.criterion_gain, frequency_hz, damping)),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no mode at the edge said: {:?}", gyro.not_named));
    assert!(
        damping <= 0.5 && hz > 0.97 * gyro.band_hz[1],
        "{hz} Hz, {damping}, band {:?}",
        gyro.band_hz
    );
    let gyro_findings: Vec<f64> = report
        .findings
        .iter()
        .filter(|f| f.block == Block::Gyro)
        .map(|f| f.criterion_gain)
        .collect();
    assert!(
        !gyro_findings.is_empty() && gyro_findings.iter().all(|&g| g < gain),
        "the mode ({gain}) beside findings {gyro_findings:?}"
    );
    let (words, warning) = report.not_named_words("gyro").expect("words");
    eprintln!("{words}");
    assert!(warning && words.contains("band_hz wider tests it"), "{words}");
    let wide = Settings {
        band_hz: imu_attest::ident::band::BandSetting::Fixed([0.1, 40.0]),
        ..Settings::default()
    };
    let widened = diagnose_run(&run, &wide, &DiagnoseOptions::default()).expect("diagnosed");
    let mode = widened
        .findings
        .iter()
        .find(|f| f.effect == Effect::PlatformResonance)
        .and_then(|f| f.parameters.get("frequency_hz")?.as_f64());
    // The hidden mode's frequency: the test's knowledge (the sidecar's truth), not the diagnosis's.
    let truth = sim.sidecar.truth.gyro.as_ref().and_then(|g| {
        g.effects.iter().find_map(|e| match e {
            EffectTruth::PlatformResonance { frequency_hz, .. } => Some(*frequency_hz),
            _ => None,
        })
    });
    let truth = truth.expect("the hidden mode");
    assert!(
        mode.is_some_and(|f| (f - truth).abs() < 0.01 * truth),
        "with band 0.1-40 Hz: {mode:?} against {truth}, findings {:?}",
        widened.findings.iter().map(|f| f.effect).collect::<Vec<_>>()
    );
}

/// A mode damped beyond a peak refused beside weaker findings is a note: on a cruise run with a
/// true skew of both blocks' channels, the accelerometer's "mode" at 32 Hz damped 0.67 (gain
/// 79.5) outweighs its skew (gain 53) and is no effect the band could show.
#[test]
fn an_over_damped_mode_refused_is_a_note() {
    let (_, run) = run_of(Regime::Cruise, 21, 1e-4, &["axis_time_skew"]);
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).expect("diagnosed");
    let accel = &report.blocks["accel"];
    let damped: Vec<_> = accel
        .not_named
        .iter()
        .filter(|r| matches!(r.reason, Reason::OutOfReach { damping, .. } if damping > 0.5))
        .collect();
    assert!(
        !damped.is_empty(),
        "no over-damped mode refused: {:?}",
        accel.not_named
    );
    let (words, warning) = report.not_named_words("accel").expect("words");
    eprintln!("{words}");
    assert!(!warning && words.contains("damped beyond a peak"), "{words}");
}
