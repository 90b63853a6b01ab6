//! A sensor's own filters above the band, and angles behind a causal filter. The identifier never
//! sees the truth; the test compares with what the simulator kept.
//!
//! - A first-order lag whose pole lies above the band (`sensor_lag@0.5`: time constants of
//!   1.6-2.5 ms, poles at 64-100 Hz, the band ending at 40 Hz) bends the gain by 5-10 % at the
//!   band's top *with* phase. It is the block's own dynamics: order 1 is chosen with its time
//!   constant and the delay without its lag, not a delay-only model over an even gain (which takes
//!   the gain's bend and leaves the phase to the delay: an independent simulator's 2 ms lag gave
//!   the delay 41 us off, 12.6 of its deviations, before the fit over the even gain had to beat
//!   the poles' on the information criterion; checked here: without that comparison the first
//!   block is order 0, its delay 1.83 ms long at a deviation of 3 us).
//! - Angles measured through a causal 20 Hz second-order filter (`simulate --angle-filter-hz`):
//!   the block's response to them leads, so a model with zeros fits, whose delay and poles are
//!   not the block's alone. Such a model says so (`zeros_lead`) with the lead, near the filter's
//!   group delay (11.25 ms); a block fitted at order 0 says its negative delay. Neither is silent.
//! - A sensor's anti-alias filter at 1 kHz (`simulate --sensor-filter-hz 100`: a second-order
//!   Butterworth on both blocks, the band ending at 40 Hz): order 2 for both blocks, the pair at
//!   the filter's corner, `K` within the 0.3 %. Checked with the binary before the
//!   eleventh session: seed 1's accelerometer order 3 with a pole at 2 Hz and `K` 2.1 % off, its
//!   gyro order 0; seed 3 order 0 for both (the order-2 fit's best was an unstable pair, and the
//!   accelerometer's weak input direction was compared at the bin centre). With the anti-alias
//!   starts tried only after an unstable best, seed 1's gyro was order 0 again (a stable pair at
//!   340 Hz found first, outside the band).
//! - A clean run forced to an order the rules reject says `inadmissible_order`, not `zeros_lead`
//!   (its zeros lead or lag at random). The other side, an admissible all-pole fit that does not
//!   say it, is the unit test `bic_finds_a_second_order_filter_above_the_band`.

use std::f64::consts::{PI, SQRT_2};

use imu_attest::block::Block;
use imu_attest::ident::band::BandSetting;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::{OrderSetting, Settings};
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::truth::EffectTruth;
use imu_attest::sim::{SimConfig, SimulatedRun};

use crate::common::sim as sim_common;

fn truth_of(sim: &SimulatedRun, block: Block) -> &imu_attest::sim::truth::BlockTruth {
    match block {
        Block::Gyro => sim.sidecar.truth.gyro.as_ref(),
        Block::Accel => sim.sidecar.truth.accel.as_ref(),
    }
    .expect("truth")
}

fn zeros_lead(warnings: &[IdentWarning]) -> Option<f64> {
    warnings.iter().find_map(|w| match w {
        IdentWarning::ZerosLead { lead_s, .. } => Some(*lead_s),
        _ => None,
    })
}

#[test]
fn a_lag_above_the_band_is_fitted_as_a_pole_not_an_even_gain() {
    for seed in 1..=3 {
        let (sim, run) = sim_common::simulated_run_of(120.0, Regime::Cruise, seed, &["sensor_lag@0.5"]);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            let truth = truth_of(&sim, b.block);
            let lag = truth
                .effects
                .iter()
                .find_map(|e| match e {
                    EffectTruth::SensorLag { time_constant_s } => Some(*time_constant_s),
                    _ => None,
                })
                .expect("the lag's truth");
            let s = &b.structural;
            let fitted = s.denominator.first().copied().unwrap_or(0.0);
            eprintln!(
                "seed {seed} {:?}: order {}, T {fitted:.6} (true {lag:.6}), tau {:.6} +- {:.6} (true {:.6})",
                b.block, s.order, s.tau_s, s.tau_std_s, truth.tau_s
            );
            assert_eq!(s.order, 1, "seed {seed} {:?}: {:?}", b.block, s.candidates);
            assert!(
                (fitted - lag).abs() < 0.1 * lag,
                "seed {seed} {:?}: T {fitted}",
                b.block
            );
            assert!(
                (s.tau_s - truth.tau_s).abs() < 4.0 * s.tau_std_s,
                "seed {seed} {:?}: tau {} against {}",
                b.block,
                s.tau_s,
                truth.tau_s
            );
            assert!(s.even_gain.is_none(), "seed {seed} {:?}", b.block);
            assert_eq!(zeros_lead(&b.warnings), None, "seed {seed} {:?}", b.block);
        }
    }
}

fn zeros_lag(warnings: &[IdentWarning]) -> Option<[f64; 2]> {
    warnings.iter().find_map(|w| match w {
        IdentWarning::ZerosLag { lag_s, lag_std_s, .. } => Some([*lag_s, *lag_std_s]),
        _ => None,
    })
}

/// A sensor's 25 Hz Butterworth filter (no zeros) at 1 kHz, found at order 2 with its poles,
/// whose delay came out 0.49 ms short (5.8 of its deviations) with the numerator lagging by as
/// much (a test campaign's case). The cause was the observer's: the gyro's own noise, added
/// behind its filter, left the witness more of the angles unexplained where the filter cut the
/// signal, and that was taken for angle noise, the inputs shrunk by it
/// (`stand::witness_floor`). Now the delay is the block's within three of its deviations and
/// nothing is split with zeros: the accelerometer (0.54 ms long before, its zeros leading by as
/// much) too.
#[test]
fn a_filtered_block_s_delay_is_not_split_with_zeros() {
    let mut config = SimConfig::new(Regime::Cruise);
    config.seed = 910;
    config.duration_s = 300.0;
    config.rate_hz = 1000.0;
    config.sensor_filter_hz = Some(25.0);
    let (sim, run) = sim_common::simulated_run(&config);
    let id = identify_run(&run, &Settings::default()).expect("identified");
    for b in &id.blocks {
        let (s, truth) = (&b.structural, truth_of(&sim, b.block));
        eprintln!(
            "{:?}: order {}, tau {:.6} +- {:.6} (true {:.6}), {:?}",
            b.block, s.order, s.tau_s, s.tau_std_s, truth.tau_s, b.warnings
        );
        assert_eq!(s.order, 2, "{:?}: {:?}", b.block, s.candidates);
        assert!(
            (s.tau_s - truth.tau_s).abs() < 3.0 * s.tau_std_s,
            "{:?}: tau {} +- {} against {}",
            b.block,
            s.tau_s,
            s.tau_std_s,
            truth.tau_s
        );
        assert_eq!(zeros_lag(&b.warnings), None, "{:?}", b.block);
        assert_eq!(zeros_lead(&b.warnings), None, "{:?}", b.block);
    }
}

/// Zeros that take part of a filtered block's delay are said, and the low-frequency delay the
/// words quote (delay plus the zeros' lag) is the block's: a 15 Hz Butterworth filter on a gyro
/// with white noise (cruise, seed 8406, found in a campaign of 12 such runs: the one whose fit
/// split its delay), the delay alone 0.41 ms short, more than three of its deviations.
#[test]
fn zeros_that_take_part_of_a_filtered_blocks_delay_are_said() {
    let mut config = SimConfig::new(Regime::Cruise);
    config.seed = 8406;
    config.sensor_filter_hz = Some(15.0);
    config.sensor_noise.white_only = true;
    let (sim, run) = sim_common::simulated_run(&config);
    let id = identify_run(&run, &Settings::default()).expect("identified");
    let gyro = id.blocks.iter().find(|b| b.block == Block::Gyro).expect("gyro");
    let (s, truth) = (&gyro.structural, truth_of(&sim, Block::Gyro));
    assert_eq!(s.order, 2, "{:?}", s.candidates);
    let [lag, lag_std] = zeros_lag(&gyro.warnings).unwrap_or_else(|| panic!("not said: {:?}", gyro.warnings));
    eprintln!(
        "tau {:.6} +- {:.6}, zeros' lag {lag:.6} +- {lag_std:.6}, true {:.6}",
        s.tau_s, s.tau_std_s, truth.tau_s
    );
    // The fitted delay alone misses by more than three of its deviations; with the zeros' lag
    // the delay beside the poles is right to a tenth of the miss.
    let (alone, beside) = ((s.tau_s - truth.tau_s).abs(), (s.tau_s + lag - truth.tau_s).abs());
    assert!(alone > 3.0 * s.tau_std_s, "{} against {}", s.tau_s, truth.tau_s);
    assert!(
        beside < 0.1 * alone,
        "{} + {lag} +- {lag_std} against {}",
        s.tau_s,
        truth.tau_s
    );
    let words = gyro
        .warnings
        .iter()
        .find(|w| matches!(w, IdentWarning::ZerosLag { .. }))
        .map(ToString::to_string)
        .unwrap_or_default();
    let quoted = format!(
        "quote {:.3} ms as the delay beside the poles",
        (s.tau_s + lag) * 1e3
    );
    assert!(words.contains(&quoted), "{quoted:?} not in {words}");
}

#[test]
fn angles_behind_a_causal_filter_are_said_never_silent() {
    let filter_hz = 20.0;
    let group_delay_s = SQRT_2 / (2.0 * PI * filter_hz);
    let settings = Settings {
        band_hz: BandSetting::Fixed([0.1, 35.0]),
        ..Settings::default()
    };
    let mut leads = 0;
    for seed in 1..=2 {
        let mut config = SimConfig::new(Regime::Cruise);
        config.seed = seed;
        config.duration_s = 120.0;
        config.stand = StandImperfections {
            filter_hz: Some(filter_hz),
            ..StandImperfections::default()
        };
        let (_, run) = sim_common::simulated_run(&config);
        let id = identify_run(&run, &settings).expect("identified");
        for b in &id.blocks {
            let s = &b.structural;
            let lead = zeros_lead(&b.warnings);
            let negative = b
                .warnings
                .iter()
                .any(|w| matches!(w, IdentWarning::NegativeDelay { .. }));
            eprintln!(
                "seed {seed} {:?}: order {}, tau {:.6}, lead {lead:?}, negative delay said {negative}",
                b.block, s.order, s.tau_s
            );
            if s.order >= 2 {
                let lead = lead.expect("a model with leading zeros says so");
                assert!(
                    (lead - group_delay_s).abs() < 0.1 * group_delay_s,
                    "seed {seed} {:?}: lead {lead} against the filter's {group_delay_s}",
                    b.block
                );
                leads += 1;
            } else {
                assert!(
                    negative,
                    "seed {seed} {:?}: order {} said nothing",
                    b.block, s.order
                );
            }
        }
    }
    // Measured: two of the four blocks at order 3, both saying it.
    assert!(
        leads >= 1,
        "no block was fitted with zeros: the test no longer tests the warning"
    );
}

/// A clean run forced to order 3: the fit has zeros that lead or lag at random, and the rules
/// reject the order; `inadmissible_order` is said, not `zeros_lead` (measured without the
/// admissibility condition: the gyro's zeros here lead by 3.12 of their deviations; over five
/// clean seeds forced to orders 3 and 4, seven blocks led by 2.0-3.1).
#[test]
fn a_forced_inadmissible_order_does_not_say_zeros_lead() {
    let (_, run) = sim_common::simulated_run_of(120.0, Regime::Approach, 6, &[]);
    let settings = Settings {
        order: OrderSetting::Fixed(3).into(),
        ..Settings::default()
    };
    let id = identify_run(&run, &settings).expect("identified");
    for b in &id.blocks {
        let inadmissible = b
            .warnings
            .iter()
            .any(|w| matches!(w, IdentWarning::InadmissibleOrder { .. }));
        assert!(inadmissible, "{:?}: {:?}", b.block, b.warnings);
        assert_eq!(zeros_lead(&b.warnings), None, "{:?}", b.block);
    }
}

#[test]
fn an_anti_alias_filter_at_1_khz_is_a_stable_pair_at_its_corner() {
    let corner_hz = 100.0;
    for seed in 1..=3 {
        let mut config = SimConfig::new(Regime::Cruise);
        config.seed = seed;
        config.duration_s = 300.0;
        config.rate_hz = 1000.0;
        config.sensor_filter_hz = Some(corner_hz);
        let (sim, run) = sim_common::simulated_run(&config);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        assert_eq!(id.blocks.len(), 2);
        for b in &id.blocks {
            let truth = truth_of(&sim, b.block);
            assert_eq!(
                truth.anti_alias_hz,
                Some(corner_hz),
                "the simulator kept its filter"
            );
            let s = &b.structural;
            let natural_hz: Vec<f64> = s.poles.iter().map(|p| p[0].hypot(p[1]) / (2.0 * PI)).collect();
            let k_error = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| (s.k[i][j] - truth.k[i][j]).powi(2))
                .sum::<f64>()
                .sqrt()
                / (0..3)
                    .map(|i| (0..3).map(|j| truth.k[i][j].powi(2)).sum::<f64>())
                    .sum::<f64>()
                    .sqrt();
            eprintln!(
                "seed {seed} {:?}: order {}, poles at {natural_hz:?} Hz, tau {:.6} (true {:.6}), K {:.4} %",
                b.block,
                s.order,
                s.tau_s,
                truth.tau_s,
                100.0 * k_error
            );
            assert_eq!(s.order, 2, "seed {seed} {:?}: {:?}", b.block, s.candidates);
            assert!(s.stable, "seed {seed} {:?}", b.block);
            for f in &natural_hz {
                assert!(
                    (f - corner_hz).abs() < 0.15 * corner_hz,
                    "seed {seed} {:?}: a pole at {f} Hz",
                    b.block
                );
            }
            // Damping of a Butterworth pair: -Re p / |p| = 1 / sqrt(2).
            let damping = -s.poles[0][0] / s.poles[0][0].hypot(s.poles[0][1]);
            assert!(
                (damping - 1.0 / SQRT_2).abs() < 0.1,
                "seed {seed} {:?}: damping {damping}",
                b.block
            );
            assert!(k_error < 0.003, "seed {seed} {:?}: K {k_error}", b.block);
            // Its delay is its own: no zeros take part of it.
            assert_eq!(zeros_lag(&b.warnings), None, "seed {seed} {:?}", b.block);
        }
    }
}

/// A sensor's 20 Hz Butterworth filter at 500 Hz (inside the band), on both blocks, the gyro's
/// noise behind it: before the witness's own floor was taken out (`stand::witness_floor`), the
/// observer took that noise for angle noise where the filter cut the signal, the gyro's response
/// estimate read 10 % high at 35-40 Hz, and on twelve such runs (seeds 8401-8406, cruise and
/// approach) every order-2 fit put zeros leading or lagging beside a delay 0.4-1.0 ms off (delay
/// z rms 8.8 gyro, 11.5 accelerometer); after, z rms 1.0 and 0.6, no zeros said. Four of them.
#[test]
fn a_filter_inside_the_band_keeps_the_observer_s_inputs_whole() {
    for (seed, regime) in [
        (8401, Regime::Approach),
        (8401, Regime::Cruise),
        (8403, Regime::Approach),
        (8403, Regime::Cruise),
    ] {
        let mut config = SimConfig::new(regime);
        config.seed = seed;
        config.sensor_filter_hz = Some(20.0);
        let (sim, run) = sim_common::simulated_run(&config);
        let id = identify_run(&run, &Settings::default()).expect("identified");
        for b in &id.blocks {
            let (s, truth) = (&b.structural, truth_of(&sim, b.block));
            eprintln!(
                "seed {seed} {regime:?} {:?}: order {}, tau {:.6} +- {:.6} (true {:.6})",
                b.block, s.order, s.tau_s, s.tau_std_s, truth.tau_s
            );
            assert_eq!(
                s.order, 2,
                "seed {seed} {regime:?} {:?}: {:?}",
                b.block, s.candidates
            );
            // Within three deviations, and within 0.35 ms (some order-2 fits put the delay's
            // deviation at 3 ms, where the zeros and the delay trade freely: honest, no test).
            assert!(
                (s.tau_s - truth.tau_s).abs() < (3.0 * s.tau_std_s).min(0.35e-3),
                "seed {seed} {regime:?} {:?}: tau {} +- {} against {}",
                b.block,
                s.tau_s,
                s.tau_std_s,
                truth.tau_s
            );
            assert_eq!(
                zeros_lead(&b.warnings),
                None,
                "seed {seed} {regime:?} {:?}",
                b.block
            );
            assert_eq!(
                zeros_lag(&b.warnings),
                None,
                "seed {seed} {regime:?} {:?}",
                b.block
            );
        }
    }
}
