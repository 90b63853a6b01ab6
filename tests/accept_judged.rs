//! Issue 15, an accepted effect's model judged on what it now is: a band limit at its bound or
//! beyond the band leaves `K`'s and the delay's deviations determined; a resonant gyro's warnings
//! are the extended model's own; an accepted mode or band limit takes back the band the identified
//! model's misfit cut; a band limit where there is none does not take the delay. Simulated runs
//! whose truth only these tests read.

use crate::common::accept::{extend, gain_and_delay_z, identify, rms};
use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::{prepare_for_effects, starts_match};
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::{BlockModel, Model};
use imu_attest::sim::regime::Regime;
use sim_common::simulated_run_of;

/// The run's model as identified and with the stand's band limit accepted on both blocks.
fn identified_and_band_limited(run: imu_attest::run::Run) -> (Model, Model) {
    let accepted = [
        (Block::Gyro, Effect::ReferenceBandLimit),
        (Block::Accel, Effect::ReferenceBandLimit),
    ];
    (identify(run.clone()), extend(run, &accepted))
}

/// Asserts that each of `m`'s nine gain deviations is determined and between `ratio[0]` and
/// `ratio[1]` times `reference`'s (`what` names the block in the message).
fn gains_deviations_within(m: &BlockModel, reference: &imu_attest::model::Fit, ratio: [f64; 2], what: &str) {
    for i in 0..3 {
        for j in 0..3 {
            let sd = m.fit.k_std[i][j].expect("K's deviation");
            let reference_sd = reference.k_std[i][j].expect("K's deviation");
            assert!(
                sd > ratio[0] * reference_sd && sd < ratio[1] * reference_sd,
                "{what} K[{i}][{j}] {sd} against {reference_sd}"
            );
        }
    }
}

/// A band limit accepted on a run without one may fit at its bound (`T = 0`, where its gain moves
/// as `T^(2n)`, no curvature, and a step below leaves its range): it is held there, and `K`'s
/// and the delay's deviations are those of the model given it. Before, that one parameter left
/// every deviation of both blocks `null` in the model file (cruise seed 11 here, both blocks;
/// seed 12 and approach seed 13 fit a small band limit, their deviations determined as before).
#[test]
fn a_band_limit_at_its_bound_leaves_the_other_deviations_determined() {
    let mut at_bound = 0;
    for (regime, seed) in [(Regime::Cruise, 11), (Regime::Cruise, 12), (Regime::Approach, 13)] {
        let (_, run) = simulated_run_of(120.0, regime, seed, &[]);
        let (bare, model) = identified_and_band_limited(run);
        for (name, b) in &model.blocks {
            let accepted = &b.effects.as_ref().expect("effects").accepted[0];
            let t = accepted.parameters["T_s"].as_f64().expect("T");
            let t_std = accepted.parameter_std["T_s"].as_f64();
            eprintln!("{regime:?} {seed} {name}: T {t:e} +- {t_std:?}");
            at_bound += usize::from(t_std.is_none());
            // Of the bare model's size (the extended fit's deviations are the diagnosis's
            // covariance, not the identifier's widenings: 0.50-1.90 of them measured).
            gains_deviations_within(b, &bare.blocks[name].fit, [0.3, 5.0], name);
            let tau_sd = b.fit.tau_std_s.expect("tau's deviation");
            assert!(tau_sd > 0.0 && tau_sd.is_finite());
        }
    }
    assert!(at_bound > 0, "no band limit at its bound: the test tests nothing");
}

/// A gyro on a resonant mount: identified at order 0 it does not explain the data (poor fit,
/// implausible elements, a gain change across the band, the noise terms' misfit); with the mode
/// the diagnosis names accepted, the model file's warnings are the extended model's own, and it
/// explains the data with a calibrated block's `K`: none of them is left (before, all stayed,
/// "chi2/dof 62, uncertainties widened by 7.9x" beside a joint fit of chi2/dof 0.92 and a `K`
/// within 0.1 % of the truth).
#[test]
fn a_resonant_gyro_with_its_mode_accepted_is_judged_on_the_extended_model() {
    use imu_attest::ident::warnings::IdentWarning;
    use imu_attest::noise::NoiseWarning;
    let (sim, run) = simulated_run_of(120.0, Regime::Approach, 1, &["platform_resonance:gyro"]);
    let truth = sim.sidecar.truth.gyro.expect("gyro truth");
    let judged = |m: &BlockModel| {
        m.fit
            .warnings
            .iter()
            .filter(|w| {
                matches!(
                    w,
                    IdentWarning::PoorFit { .. }
                        | IdentWarning::PoorFitWithEffects { .. }
                        | IdentWarning::ImplausibleGain { .. }
                        | IdentWarning::GainChangesAcrossBand { .. }
                )
            })
            .count()
    };
    let misfit = |m: &BlockModel| {
        m.noise.as_ref().is_some_and(|n| {
            n.warnings
                .iter()
                .any(|w| matches!(w, NoiseWarning::ModelMisfit { .. }))
        })
    };
    let identified = identify(run.clone());
    let gyro = &identified.blocks["gyro"];
    assert!(judged(gyro) >= 2 && misfit(gyro), "{:?}", gyro.fit.warnings);
    let model = extend(run, &[(Block::Gyro, Effect::PlatformResonance)]);
    let gyro = &model.blocks["gyro"];
    let effects = gyro.effects.as_ref().expect("extended");
    assert_eq!(effects.resonances.len(), 1, "{effects:?}");
    assert!(effects.chi2_per_dof[1] < 1.5, "{:?}", effects.chi2_per_dof);
    let (k, tau) = gain_and_delay_z(gyro, &truth);
    assert!(rms(&k) < 3.0 && tau.abs() < 4.0, "K z {k:?}, tau z {tau}");
    assert_eq!(judged(gyro), 0, "{:?}", gyro.fit.warnings);
    assert!(!misfit(gyro), "{:?}", gyro.noise);
}

/// The band an identified model's misfit cut (`band_top_misfit`: a gyro's 20.6 Hz mode, the band
/// ended at 23.6 Hz of a usable 39.9) is the mode's once it is accepted: the joint fit runs
/// through it, explains it, and the model's band is the uncut one, without the misfit's warning
/// (before, the extended model kept the cut band and the identified model's "misses the data by 3
/// times" above it).
#[test]
fn an_accepted_mode_takes_back_the_band_the_identified_model_s_misfit_cut() {
    use imu_attest::ident::warnings::IdentWarning;
    let (sim, run) = simulated_run_of(120.0, Regime::TurbulentCruise, 7, &["platform_resonance:gyro"]);
    let truth = sim.sidecar.truth.gyro.expect("gyro truth");
    let identified = identify(run.clone());
    let gyro = &identified.blocks["gyro"];
    let Some(cut) = gyro.fit.warnings.iter().find_map(|w| match w {
        IdentWarning::BandTopMisfit { band_hz, .. } => Some(*band_hz),
        _ => None,
    }) else {
        panic!("the identified band is cut: {:?}", gyro.fit.warnings)
    };
    assert!(gyro.band_hz[1] < cut[1], "{:?} {cut:?}", gyro.band_hz);
    let identified_band = gyro.band_hz;
    // Two starts, over the identified band and through the cut one; a model of another band
    // (a cache of them made for it) does not match them.
    let accepted = [(Block::Gyro, Effect::PlatformResonance)];
    let preps = prepare_for_effects(
        &mut Session::new(Arc::new(run.clone())),
        &Settings::default(),
        &identified,
        &accepted,
    )
    .expect("prepared");
    let tops: Vec<f64> = preps
        .iter()
        .flat_map(|p| &p.blocks)
        .map(|b| b.band_hz[1])
        .collect();
    assert_eq!(tops, vec![identified_band[1], cut[1]]);
    assert!(starts_match(&preps, &identified, &accepted));
    let mut other = identified.clone();
    other.blocks.get_mut("gyro").expect("gyro").band_hz[1] *= 0.9;
    assert!(!starts_match(&preps, &other, &accepted));
    let model = extend(run, &accepted);
    let gyro = &model.blocks["gyro"];
    let effects = gyro.effects.as_ref().expect("extended");
    assert_eq!(effects.resonances.len(), 1, "{effects:?}");
    assert!(
        (effects.band_hz[1] - cut[1]).abs() < 1e-9
            && (0..2).all(|i| (gyro.band_hz[i] - effects.band_hz[i]).abs() < 1e-12),
        "{:?} {:?} {cut:?}",
        gyro.band_hz,
        effects.band_hz
    );
    assert!(effects.chi2_per_dof[1] < 1.5, "{:?}", effects.chi2_per_dof);
    // The identified band is kept beside it, and said.
    assert_eq!(effects.identified.band_hz, Some(identified_band));
    assert!(
        effects
            .identified
            .band_words(gyro.band_hz)
            .starts_with(", band 0.12-23.")
    );
    assert!(
        !gyro
            .fit
            .warnings
            .iter()
            .any(|w| matches!(w, IdentWarning::BandTopMisfit { .. })),
        "{:?}",
        gyro.fit.warnings
    );
    let (k, tau) = gain_and_delay_z(gyro, &truth);
    assert!(rms(&k) < 2.0 && tau.abs() < 3.0, "K z {k:?}, tau z {tau}");
}

/// The stand's band limit (a zero-phase 30 Hz limit on the angles, `--stand real`'s) ends the
/// identified band early on both blocks (`band_top_misfit`, the model's gain short of the data's
/// rise towards the limit); once the band limit is accepted the joint fit runs through the band
/// that was cut, explains it, and the model's band is the uncut one without the misfit's
/// warning. Before, only an accepted mount resonance took the band back: with the band limit
/// accepted the model kept the cut band and "misses the data by 22 times" above it, on 37 of 48
/// blocks of a campaign of 24 `--stand real` runs.
#[test]
fn an_accepted_band_limit_takes_back_the_band_the_identified_model_s_misfit_cut() {
    use imu_attest::ident::warnings::IdentWarning;
    use imu_attest::sim::SimConfig;
    use imu_attest::sim::stand::StandImperfections;
    let cut_top = |m: &BlockModel| {
        m.fit.warnings.iter().find_map(|w| match w {
            IdentWarning::BandTopMisfit { band_hz, .. } => Some(band_hz[1]),
            _ => None,
        })
    };
    let mut taken_back = 0;
    for (regime, seed) in [(Regime::TurbulentCruise, 131), (Regime::Approach, 132)] {
        let mut config = SimConfig::new(regime);
        (config.seed, config.duration_s, config.rate_hz) = (seed, 120.0, 500.0);
        config.stand = StandImperfections {
            band_limit_hz: Some(30.0),
            ..StandImperfections::default()
        };
        let (sim, run) = sim_common::simulated_run(&config);
        let (identified, model) = identified_and_band_limited(run);
        for (name, truth) in [
            ("gyro", &sim.sidecar.truth.gyro),
            ("accel", &sim.sidecar.truth.accel),
        ] {
            let before = &identified.blocks[name];
            let Some(top) = cut_top(before) else {
                continue;
            };
            let after = &model.blocks[name];
            let effects = after.effects.as_ref().expect("extended");
            eprintln!(
                "{regime:?} {seed} {name}: band {:?} -> {:?} (cut from {top:.2}), chi2/dof {:?}",
                before.band_hz, after.band_hz, effects.chi2_per_dof
            );
            assert!(effects.reference_band_limit.is_some(), "{effects:?}");
            assert!((after.band_hz[1] - top).abs() < 1e-9, "{:?} {top}", after.band_hz);
            assert_eq!(effects.identified.band_hz, Some(before.band_hz));
            assert!(cut_top(after).is_none(), "{:?}", after.fit.warnings);
            assert!(effects.chi2_per_dof[1] < 1.3, "{:?}", effects.chi2_per_dof);
            let (k, tau) = gain_and_delay_z(after, truth.as_ref().expect("truth"));
            assert!(rms(&k) < 2.0 && tau.abs() < 3.0, "K z {k:?}, tau z {tau}");
            taken_back += 1;
        }
    }
    assert!(
        taken_back >= 3,
        "only {taken_back} blocks' bands were cut: the test tests little"
    );
}

/// A band limit accepted on a stand without one (coloured angle noise only) can fit with its
/// corner far above the band (the accelerometer's `T` 0.67 and 0.36 ms here, corners far above
/// band tops near 33 Hz: its gain there moves as `(f/f_c)^16`), where the data do not see it: its
/// own deviation is undetermined, and `K`'s and the delay's are those of the model given it, of
/// the identified model's size. Before, its curvature at rounding's level left every deviation of
/// the accelerometer's model `null` (8 of 72 blocks of a 300 s campaign). Seeds 141 and 146 until
/// 1 Dec: with the residual spectrum resolved at ill-conditioned bins (`ident::explained`) seed
/// 146's band limit fits at its bound (the case
/// `a_band_limit_at_its_bound_leaves_the_other_deviations_determined` tests); of seeds 141-154,
/// 141, 147, 150, 152 and 153 fit far above the band.
#[test]
fn a_band_limit_the_band_does_not_see_leaves_the_other_deviations_determined() {
    use imu_attest::sim::SimConfig;
    for seed in [150, 153] {
        let mut config = SimConfig::new(Regime::Approach);
        (config.seed, config.duration_s) = (seed, 120.0);
        config.stand.coloured_noise_rad = 3e-5;
        config.stand.coloured_corner_hz = 5.0;
        let (_, run) = sim_common::simulated_run(&config);
        let (identified, model) = identified_and_band_limited(run);
        let accel = &model.blocks["accel"];
        let band_limit = &accel.effects.as_ref().expect("effects").accepted[0];
        // Away from its bound (0): not the case held before.
        let t = band_limit.parameters["T_s"].as_f64().expect("T");
        assert!(t > 1e-4, "seed {seed}: T {t}");
        assert!(
            band_limit.parameter_std["T_s"].is_null(),
            "seed {seed}: {band_limit:?}"
        );
        for (name, b) in &model.blocks {
            let reference = &identified.blocks[name].fit;
            gains_deviations_within(b, reference, [0.5, 3.0], &format!("seed {seed} {name}"));
            let tau_sd = b.fit.tau_std_s.expect("tau's deviation");
            let identified_sd = reference.tau_std_s.expect("tau's deviation");
            assert!(
                tau_sd > 0.5 * identified_sd && tau_sd < 3.0 * identified_sd,
                "seed {seed} {name}: {tau_sd} against {identified_sd}"
            );
        }
    }
}

/// A band limit accepted by hand on a stand without one is not fitted as a causal filter far
/// above the band, whose group delay the block's delay then gives up: a causal shape is taken
/// only where it explains more than the shapes without phase by what a parameter must buy.
/// Before, these perfect-stand runs' gyros fitted it (corners near 150 Hz) and their delays
/// moved by 0.9-1.1 ms (a helper's campaign: 22 of 104 blocks off by more than 0.1 ms, 2 after).
/// A real causal filter on the angles (a tracker's own, 40 Hz) is still fitted as one, at its
/// corner, the delay against the motion.
#[test]
fn a_band_limit_accepted_where_there_is_none_does_not_take_the_delay() {
    use imu_attest::sim::SimConfig;
    let both = [
        (Block::Gyro, Effect::ReferenceBandLimit),
        (Block::Accel, Effect::ReferenceBandLimit),
    ];
    let causal_corner = |m: &BlockModel| {
        let p = &m.effects.as_ref().expect("effects").accepted[0].parameters;
        (p["causal"].as_bool() == Some(true)).then(|| p["corner_hz"].as_f64().expect("corner"))
    };
    for (regime, seed, filter_hz) in [
        (Regime::Cruise, 155, None),
        (Regime::Approach, 156, None),
        (Regime::TurbulentCruise, 161, Some(40.0)),
    ] {
        let mut config = SimConfig::new(regime);
        (config.seed, config.duration_s) = (seed, 120.0);
        config.stand.filter_hz = filter_hz;
        let (sim, run) = sim_common::simulated_run(&config);
        let model = extend(run, &both);
        for (name, truth) in [
            ("gyro", &sim.sidecar.truth.gyro),
            ("accel", &sim.sidecar.truth.accel),
        ] {
            let b = &model.blocks[name];
            let corner = causal_corner(b);
            let (_, tau_z) = gain_and_delay_z(b, truth.as_ref().expect("truth"));
            eprintln!("{regime:?} {seed} {name}: causal corner {corner:?}, tau z {tau_z:.2}");
            match filter_hz {
                None => assert_eq!(corner, None, "{regime:?} {seed} {name}"),
                Some(f) => {
                    let c = corner.expect("the causal shape");
                    assert!((c / f - 1.0).abs() < 0.05, "{name}: corner {c}");
                }
            }
            assert!(tau_z.abs() < 4.0, "{regime:?} {seed} {name}: tau z {tau_z}");
        }
    }
}
