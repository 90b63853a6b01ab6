//! The auto band's top on a stand whose angle measurement has a band limit (issue 13, item 1): the
//! limit is zero-phase, so the outputs stay coherent with the inputs beyond it while the estimate's
//! gain rises; the band is ended where the model stops explaining the data
//! (`ident::band_top`), and says so. Runs the identifier has not been tuned on: band limits of 22
//! and 30 Hz, seeds 41-46, two regimes; the truth is read here only.

use imu_attest::block::Block;
use imu_attest::ident::band::BandSetting;
use imu_attest::ident::identify::{BlockIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::sim::regime::Regime;
use imu_attest::sim::stand::StandImperfections;
use imu_attest::sim::{SimConfig, SimulatedRun};

use crate::common::sim as sim_common;

fn run(regime: Regime, seed: u64, stand: StandImperfections) -> (SimulatedRun, imu_attest::run::Run) {
    let mut config = SimConfig::new(regime);
    config.duration_s = 120.0;
    config.rate_hz = 500.0;
    config.seed = seed;
    config.stand = stand;
    sim_common::simulated_run(&config)
}

fn k_error(sim: &SimulatedRun, b: &BlockIdentification) -> f64 {
    let truth = match b.block {
        Block::Gyro => sim.sidecar.truth.gyro.as_ref(),
        Block::Accel => sim.sidecar.truth.accel.as_ref(),
    }
    .expect("truth");
    let (mut err, mut norm) = (0.0, 0.0);
    for i in 0..3 {
        for j in 0..3 {
            err += (b.structural.k[i][j] - truth.k[i][j]).powi(2);
            norm += truth.k[i][j].powi(2);
        }
    }
    (err / norm).sqrt()
}

fn trimmed(b: &BlockIdentification) -> Option<[f64; 2]> {
    b.warnings.iter().find_map(|w| match w {
        IdentWarning::BandTopMisfit { band_hz, .. } => Some(*band_hz),
        _ => None,
    })
}

#[test]
fn a_band_limited_reference_ends_the_band_below_its_limit_and_the_gain_is_closer() {
    let (mut with, mut without) = (0.0, 0.0);
    let mut cases = 0;
    for (limit, regime, seed) in [
        (22.0, Regime::TurbulentCruise, 41),
        (22.0, Regime::Approach, 42),
        (30.0, Regime::TurbulentCruise, 43),
        (30.0, Regime::TurbulentCruise, 44),
        (30.0, Regime::Approach, 45),
    ] {
        let stand = StandImperfections {
            band_limit_hz: Some(limit),
            ..StandImperfections::real()
        };
        let (sim, r) = run(regime, seed, stand);
        let id = identify_run(&r, &Settings::default()).expect("identified");
        let gyro = id.blocks.iter().find(|b| b.block == Block::Gyro).expect("gyro");
        let Some(left_out) = trimmed(gyro) else {
            // The coherence alone may have ended the band already; then it is below the limit.
            assert!(
                gyro.band_hz[1] < limit,
                "{limit} Hz, seed {seed}: band {:?}",
                gyro.band_hz
            );
            continue;
        };
        cases += 1;
        assert!(
            gyro.band_hz[1] < limit && gyro.band_hz[1] < left_out[0],
            "{limit} Hz, seed {seed}: band {:?}, left out {left_out:?}",
            gyro.band_hz
        );
        assert!(left_out[1] > gyro.band_hz[1]);
        // The same run fitted over the band the coherence found (what the fit did before).
        let found = Settings {
            band_hz: BandSetting::Fixed([gyro.band_hz[0], left_out[1]]),
            ..Settings::default()
        };
        let id_found = identify_run(&r, &found).expect("identified");
        let gyro_found = id_found
            .blocks
            .iter()
            .find(|b| b.block == Block::Gyro)
            .expect("gyro");
        eprintln!(
            "{limit} Hz, {regime:?}, seed {seed}: band {:?} (found to {:.1} Hz): K error {:.3} % \
             (over the found band {:.3} %), chi2/dof {:.2} ({:.2})",
            gyro.band_hz,
            left_out[1],
            100.0 * k_error(&sim, gyro),
            100.0 * k_error(&sim, gyro_found),
            gyro.structural.chi2 / gyro.structural.dof as f64,
            gyro_found.structural.chi2 / gyro_found.structural.dof as f64,
        );
        assert!(
            gyro.structural.chi2 / (gyro.structural.dof as f64)
                < gyro_found.structural.chi2 / gyro_found.structural.dof as f64,
            "the misfit left out"
        );
        with += k_error(&sim, gyro);
        without += k_error(&sim, gyro_found);
    }
    assert!(cases >= 3, "the band limit is seen on most runs: {cases} of 5");
    assert!(
        with < 0.7 * without,
        "the gain is closer without the band limit's stretch: {with} vs {without}"
    );
}

#[test]
fn a_stand_without_a_band_limit_keeps_the_band_the_coherence_found() {
    for (regime, seed) in [
        (Regime::TurbulentCruise, 46),
        (Regime::Cruise, 47),
        (Regime::Approach, 48),
    ] {
        let stand = StandImperfections {
            band_limit_hz: None,
            ..StandImperfections::real()
        };
        let (_, r) = run(regime, seed, stand);
        let id = identify_run(&r, &Settings::default()).expect("identified");
        for b in &id.blocks {
            assert_eq!(
                trimmed(b),
                None,
                "{regime:?} seed {seed} {:?}: {:?}",
                b.block,
                b.warnings
            );
        }
    }
}

#[test]
fn a_retune_on_a_trimmed_run_starts_each_fit_from_its_own_band_and_says_when_it_is_provisional() {
    use imu_attest::ident::identify::identify_run as cold;
    use imu_attest::ident::session::{Session, Start};
    use imu_attest::ident::settings::OrderSetting;
    use std::sync::Arc;

    let stand = StandImperfections {
        band_limit_hz: Some(30.0),
        ..StandImperfections::real()
    };
    let (_, r) = run(Regime::TurbulentCruise, 44, stand);
    let mut session = Session::new(Arc::new(r.clone()));
    let first = session
        .identify(&Settings::default(), Start::Cold, &mut |_| {})
        .expect("identified");
    let gyro = &first.blocks[0];
    assert!(trimmed(gyro).is_some(), "{:?}", gyro.warnings);
    let usable = gyro
        .usable_band_fit
        .as_ref()
        .expect("the usable band's fit is kept");
    assert!(usable.fitted.from_scratch());
    // Order changes, as the app's retune makes them: the fits start from the previous ones over
    // the same bands. Whatever comes out is either what the command line gives, or says it is
    // provisional (and is then redone cold).
    for order in [OrderSetting::Fixed(0), OrderSetting::Auto] {
        let settings = Settings {
            order: order.into(),
            ..Settings::default()
        };
        let warm = session
            .identify(&settings, Start::Warm, &mut |_| {})
            .expect("retuned");
        let reference = cold(&r, &settings).expect("identified");
        for (w, c) in warm.blocks.iter().zip(&reference.blocks) {
            if !warm.provisional() {
                assert_eq!(bits(w), bits(c), "{order:?} {:?}", w.block);
            }
        }
        let polished = session.polish().map_or(warm, |p| p.expect("polished"));
        for (p, c) in polished.blocks.iter().zip(&reference.blocks) {
            assert_eq!(bits(p), bits(c), "{order:?} {:?}", p.block);
        }
    }
}

/// The band, K and delay of a block's fit, bit for bit.
fn bits(b: &BlockIdentification) -> Vec<u64> {
    b.band_hz
        .iter()
        .chain(b.structural.k.iter().flatten())
        .chain([&b.structural.tau_s])
        .map(|v| v.to_bits())
        .collect()
}
