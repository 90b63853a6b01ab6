//! Issue 15, "accept means accept": an effect accepted into a block's model is fitted with the
//! paper's model on the whole record, and the model file carries the extended model (its `K`,
//! delay and the effect's size, each with a standard deviation). Checked on simulated runs whose
//! truth only this test reads: the sizes are right and the standard deviations honest (the
//! normalised errors over several seeds and regimes have rms near 1), the extended model explains
//! more, and a block without accepted effects is exactly as identified.

use crate::common::sim as sim_common;

use std::sync::Arc;

use imu_attest::block::Block;
use imu_attest::diagnose::extend::{extended_model, prepare_for_effects, starts_match};
use imu_attest::diagnose::identified::identified_model;
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::{BlockModel, Model};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::truth::{BlockTruth, EffectTruth};
use sim_common::simulated_run_of;

fn extended(regime: Regime, seed: u64, effect: &str, accepted: (Block, Effect)) -> (BlockTruth, Model) {
    let (sim, run) = simulated_run_of(120.0, regime, seed, &[effect]);
    let truth = if accepted.0 == Block::Gyro {
        sim.sidecar.truth.gyro
    } else {
        sim.sidecar.truth.accel
    }
    .expect("the block's truth");
    (truth, extend(run, &[accepted]))
}

/// The run's model with `accepted` effects, default settings.
fn extend(run: imu_attest::run::Run, accepted: &[(Block, Effect)]) -> Model {
    extended_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        accepted,
        &mut |_| {},
    )
    .expect("extended")
}

/// The run's model as identified, default settings (`identify` without effects).
fn identify(run: imu_attest::run::Run) -> Model {
    identified_model(
        &mut Session::new(Arc::new(run)),
        &Settings::default(),
        &mut |_| {},
    )
    .expect("identified")
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

/// The run's model as identified and with the stand's band limit accepted on both blocks.
fn identified_and_band_limited(run: imu_attest::run::Run) -> (Model, Model) {
    let accepted = [
        (Block::Gyro, Effect::ReferenceBandLimit),
        (Block::Accel, Effect::ReferenceBandLimit),
    ];
    (identify(run.clone()), extend(run, &accepted))
}

/// Normalised errors `(estimate - truth) / std` of K's nine elements and of tau.
fn gain_and_delay_z(m: &BlockModel, t: &BlockTruth) -> (Vec<f64>, f64) {
    let mut k = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let sd = m.fit.k_std[i][j].expect("K's deviation");
            k.push((m.k[i][j] - t.k[i][j]) / sd);
        }
    }
    (k, (m.tau_s - t.tau_s) / m.fit.tau_std_s.expect("tau's deviation"))
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

fn beyond_two(v: &[f64]) -> f64 {
    v.iter().filter(|x| x.abs() > 2.0).count() as f64 / v.len() as f64
}

fn sizes(m: &BlockModel, key: &str) -> (Vec<f64>, Vec<f64>) {
    let e = &m.effects.as_ref().expect("effects").accepted[0];
    let read = |v: &serde_json::Value| -> Vec<f64> {
        match v {
            serde_json::Value::Array(a) => a.iter().map(|x| x.as_f64().expect("number")).collect(),
            other => vec![other.as_f64().expect("number")],
        }
    };
    (read(&e.parameters[key]), read(&e.parameter_std[key]))
}

#[test]
fn accepted_effects_are_sized_with_honest_standard_deviations() {
    let regimes = [Regime::Cruise, Regime::Approach, Regime::TurbulentCruise];
    let (mut k_z, mut tau_z, mut size_z) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 1..=6_u64 {
        let regime = regimes[seed as usize % 3];
        // A gyro lag.
        let (truth, model) = extended(regime, seed, "sensor_lag:gyro", (Block::Gyro, Effect::SensorLag));
        let m = &model.blocks["gyro"];
        let (k, tau) = gain_and_delay_z(m, &truth);
        k_z.extend(k);
        tau_z.push(tau);
        let [EffectTruth::SensorLag { time_constant_s }] = truth.effects[..] else {
            panic!("{:?}", truth.effects)
        };
        let (t, sd) = sizes(m, "T_s");
        assert!(
            (t[0] - time_constant_s).abs() < 0.05 * time_constant_s,
            "T {} vs {time_constant_s}",
            t[0]
        );
        size_z.push((t[0] - time_constant_s) / sd[0]);
        // An accelerometer quadratic scale factor.
        let (truth, model) = extended(
            regime,
            100 + seed,
            "scale_nonlinearity:accel",
            (Block::Accel, Effect::ScaleNonlinearity),
        );
        let m = &model.blocks["accel"];
        let (k, tau) = gain_and_delay_z(m, &truth);
        k_z.extend(k);
        tau_z.push(tau);
        let [EffectTruth::ScaleNonlinearity { k2 }] = truth.effects[..] else {
            panic!("{:?}", truth.effects)
        };
        let (est, sd) = sizes(m, "k2");
        for i in 0..3 {
            size_z.push((est[i] - k2[i]) / sd[i]);
        }
    }
    let report = format!(
        "K: rms {:.2}, {:.0} % beyond 2 sigma; tau: rms {:.2}; sizes: rms {:.2}, {:.0} % beyond 2 sigma",
        rms(&k_z),
        100.0 * beyond_two(&k_z),
        rms(&tau_z),
        rms(&size_z),
        100.0 * beyond_two(&size_z)
    );
    eprintln!("{report}");
    for (what, z) in [("K", &k_z), ("tau", &tau_z), ("size", &size_z)] {
        assert!((0.6..=1.4).contains(&rms(z)), "{what}: {report}");
        assert!(beyond_two(z) <= 0.12, "{what}: {report}");
    }
}

#[test]
fn the_extended_model_explains_more_and_the_other_block_is_as_identified() {
    let (sim, run) = simulated_run_of(120.0, Regime::Approach, 3, &["sensor_lag:gyro"]);
    let run = Arc::new(run);
    let settings = Settings::default();
    let accepted = [(Block::Gyro, Effect::SensorLag)];
    let model =
        extended_model(&mut Session::new(run.clone()), &settings, &accepted, &mut |_| {}).expect("extended");
    let plain = identified_model(&mut Session::new(run.clone()), &settings, &mut |_| {}).expect("identified");
    let gyro = &model.blocks["gyro"];
    let e = gyro.effects.as_ref().expect("effects");
    assert!(e.chi2_per_dof[1] < e.chi2_per_dof[0], "{:?}", e.chi2_per_dof);
    let worst = |g: &[f64; 3]| g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(worst(&e.gap_db[1]) < worst(&e.gap_db[0]) - 1.0, "{:?}", e.gap_db);
    assert_eq!(e.identified.k, plain.blocks["gyro"].k);
    assert_eq!(e.identified.order, plain.blocks["gyro"].order);
    assert_eq!(gyro.order, 0);
    assert_eq!(gyro.poles, vec![[-1.0 / e.lag_s.expect("lag"), 0.0]]);
    // The response is K e^(-tau s) / (T s + 1), against the closed form.
    let t = e.lag_s.expect("lag");
    for f in [0.5, 10.0, 35.0] {
        let s = num_complex::Complex64::new(0.0, std::f64::consts::TAU * f);
        let want = (-s * gyro.tau_s).exp() / (1.0 + s * t) * gyro.k[1][2];
        assert!((gyro.response(f)[(1, 2)] - want).norm() < 1e-12, "{f}");
    }
    // The scale factors and misalignments follow the refitted K.
    assert!((gyro.fit.scale_factor_error_ppm[0] - (gyro.k[0][0] - 1.0) * 1e6).abs() < 1e-6);
    assert!((gyro.fit.misalignment_mrad[2][0] - gyro.k[2][0] * 1e3).abs() < 1e-9);
    // The noise residual is that of the extended model: the lag no longer leaks into it as it
    // does into the paper's model's (order 0; the identifier's own choice here, order 1, already
    // holds a lag).
    let order0 = Settings {
        order: imu_attest::ident::settings::OrderSetting::Fixed(0).into(),
        ..settings.clone()
    };
    let paper = identified_model(&mut Session::new(run.clone()), &order0, &mut |_| {}).expect("identified");
    let (with, without) = (
        gyro.noise.as_ref().expect("noise"),
        paper.blocks["gyro"].noise.as_ref().expect("noise"),
    );
    for (a, b) in with.channels.iter().zip(&without.channels) {
        assert!(
            a.residual_std < b.residual_std,
            "{} vs {}",
            a.residual_std,
            b.residual_std
        );
    }
    assert_eq!(
        model.blocks["accel"], plain.blocks["accel"],
        "nothing accepted on the accelerometer"
    );
    assert!(sim.sidecar.truth.gyro.is_some());
}

#[test]
fn an_effect_the_record_cannot_hold_is_listed_as_not_added() {
    let (_, run) = simulated_run_of(60.0, Regime::Cruise, 4, &[]);
    let accepted = [
        (Block::Accel, Effect::GSensitivity),
        (Block::Accel, Effect::SensorLag),
    ];
    let model = extend(run, &accepted);
    let e = model.blocks["accel"].effects.as_ref().expect("effects");
    assert_eq!(e.accepted.len(), 1);
    assert_eq!(e.accepted[0].effect, Effect::SensorLag);
    assert_eq!(e.not_added.len(), 1);
    assert_eq!(e.not_added[0].effect, Effect::GSensitivity);
    assert!(
        e.not_added[0].reason.contains("not an effect of the accel block"),
        "{}",
        e.not_added[0].reason
    );
}

/// A mode the diagnosis found beyond the band the block is identified over (a gyro resonance at
/// 30 Hz beside 0.2 mrad coloured angle noise, the usable band ending near 4 Hz) cannot be fitted
/// there: accepted, it is listed as not added with the reason (it was fitted at the band's edge
/// with K 3 % off and a negative delay, unsaid). With a band reaching the mode it is fitted near
/// the truth.
#[test]
fn a_mode_beyond_the_identified_band_is_not_added_and_a_band_reaching_it_fits_it() {
    let mut config = imu_attest::sim::SimConfig::new(Regime::Cruise);
    (config.seed, config.duration_s) = (21, 120.0);
    config.stand.coloured_noise_rad = 2e-4;
    config.stand.coloured_corner_hz = imu_attest::sim::stand::StandImperfections::real().coloured_corner_hz;
    config.effects = vec!["platform_resonance:gyro".parse().expect("effect")];
    let (sim, run) = sim_common::simulated_run(&config);
    let Some(EffectTruth::PlatformResonance { frequency_hz, .. }) = sim
        .sidecar
        .truth
        .gyro
        .as_ref()
        .and_then(|t| t.effects.first().cloned())
    else {
        panic!("the mode hidden")
    };
    let accepted = [(Block::Gyro, Effect::PlatformResonance)];
    let model = extend(run.clone(), &accepted);
    let gyro = &model.blocks["gyro"];
    assert!(
        gyro.band_hz[1] < 0.5 * frequency_hz,
        "the band {:?} ends below the mode",
        gyro.band_hz
    );
    let e = gyro.effects.as_ref().expect("effects");
    assert!(e.accepted.is_empty() && e.resonances.is_empty(), "{e:?}");
    assert_eq!(e.not_added[0].effect, Effect::PlatformResonance);
    assert!(
        e.not_added[0].reason.contains("does not reach the mode"),
        "{}",
        e.not_added[0].reason
    );
    // Nothing added: the block's model is the identified one, field for field, and only lists
    // the effect with the reason (it was the whole-record fit without effects, its K and delay
    // within their deviations of the identified ones; before the reach rule, the mode parked at
    // the edge had moved the delay to -2.8 ms and K's elements by up to 3 %).
    let identified = identify(run.clone());
    let mut as_identified = gyro.clone();
    as_identified.effects = None;
    assert_eq!(as_identified, identified.blocks["gyro"]);
    assert!(!e.extends());
    let wide = Settings {
        band_hz: imu_attest::ident::band::BandSetting::Fixed([0.1, 40.0]),
        ..Settings::default()
    };
    let model =
        extended_model(&mut Session::new(Arc::new(run)), &wide, &accepted, &mut |_| {}).expect("extended");
    let e = model.blocks["gyro"].effects.as_ref().expect("effects");
    assert_eq!(e.accepted.len(), 1, "{:?}", e.not_added);
    let found = e.resonances[0].frequency_hz;
    assert!(
        (found / frequency_hz - 1.0).abs() < 0.02,
        "{found} Hz against {frequency_hz}"
    );
}

#[test]
fn a_tones_frequency_deviation_is_honest() {
    // Ten gyro tones accepted (three regimes); the frequency's normalised errors.
    let regimes = [Regime::Cruise, Regime::Approach, Regime::TurbulentCruise];
    let mut z = Vec::new();
    for seed in 1..=10_u64 {
        let (truth, model) = extended(
            regimes[seed as usize % 3],
            seed,
            "vibration_tone:gyro",
            (Block::Gyro, Effect::VibrationTone),
        );
        let [EffectTruth::VibrationTone { frequency_hz, .. }] = truth.effects[..] else {
            panic!("{:?}", truth.effects)
        };
        let (f, sd) = sizes(&model.blocks["gyro"], "frequency_hz");
        assert!(
            (f[0] - frequency_hz).abs() < 1e-3 * frequency_hz,
            "{} vs {frequency_hz}",
            f[0]
        );
        z.push((f[0] - frequency_hz) / sd[0]);
    }
    eprintln!("tone frequency: rms {:.2}, {:?}", rms(&z), z);
    assert!((0.6..=1.5).contains(&rms(&z)), "{z:?}");
    assert!(beyond_two(&z) <= 0.2, "{z:?}");
}

/// An accepted effect refits the gyro's gains; where the gyro's own noise biases them
/// (`witness_noise_bias`), the refitted deviations keep that estimate, as the warning says.
#[test]
fn an_extended_gyro_keeps_the_witness_noise_estimate_in_its_deviations() {
    use imu_attest::ident::warnings::IdentWarning;
    use imu_attest::rng::Rng;
    let (_, mut run) = simulated_run_of(120.0, Regime::Cruise, 91, &["sensor_lag:gyro"]);
    let mut rng = Rng::new(92);
    for channel in run.gyro.as_mut().expect("gyro") {
        let rms = (channel.iter().map(|v| v * v).sum::<f64>() / channel.len() as f64).sqrt();
        for v in channel.iter_mut() {
            *v += rms / 3.0 * rng.normal();
        }
    }
    let accepted = [(Block::Gyro, Effect::SensorLag)];
    let model = extend(run, &accepted);
    let gyro = &model.blocks["gyro"];
    assert!(gyro.effects.is_some());
    let estimates = gyro
        .fit
        .warnings
        .iter()
        .find_map(|w| match w {
            IdentWarning::WitnessNoiseBias { estimates, .. } => Some(*estimates),
            _ => None,
        })
        .expect("the noisy gyro's estimate is said");
    for i in 0..3 {
        for j in 0..3 {
            let sd = gyro.fit.k_std[i][j].expect("a deviation");
            assert!(
                sd >= estimates[j] * gyro.k[i][j].abs() * (1.0 - 1e-12),
                "K[{i}][{j}] = {} +- {sd}, estimate {}",
                gyro.k[i][j],
                estimates[j]
            );
        }
    }
}

/// An accepted effect refits the gyro's gains; the angle noise the observer's model left out
/// (`ident::left_out_noise`, on a real stand's coloured noise) stays in the refitted deviations,
/// as the model file's shift says.
#[test]
fn an_extended_gyro_keeps_the_left_out_angle_noise_in_its_deviations() {
    use imu_attest::sim::SimConfig;
    use imu_attest::sim::stand::StandImperfections;
    let mut config = SimConfig::new(Regime::TurbulentCruise);
    config.duration_s = 120.0;
    config.rate_hz = 500.0;
    config.seed = 96;
    config.effects = vec!["sensor_lag:gyro".parse().expect("effect")];
    config.stand = StandImperfections::real();
    let (_, run) = sim_common::simulated_run(&config);
    let model = extend(run, &[(Block::Gyro, Effect::SensorLag)]);
    let gyro = &model.blocks["gyro"];
    assert!(gyro.extended_by().is_some());
    let shift = gyro
        .fit
        .k_shift_left_out_angle_noise
        .expect("the gyro witnessed the angle noise");
    assert!(shift.iter().flatten().any(|d| d.abs() > 0.0), "{shift:?}");
    for i in 0..3 {
        for j in 0..3 {
            let sd = gyro.fit.k_std[i][j].expect("a deviation");
            assert!(
                sd >= shift[i][j].abs() / 3.0_f64.sqrt() * (1.0 - 1e-12),
                "K[{i}][{j}] = {} +- {sd}, shift {}",
                gyro.k[i][j],
                shift[i][j]
            );
        }
    }
    // The accelerometer beside it takes the same noise through its own inputs.
    assert!(model.blocks["accel"].fit.k_shift_left_out_angle_noise.is_some());
}

/// A reference interpolated from 120 Hz: the delay-only model gives `K` at low frequency and
/// carries the even gain; the joint fit of an accepted effect (its own design and weights) gives
/// its gain as fitted, without the even gain, and the warning says `K` is not moved. (Seed 94
/// until 1 Dec: with the witness's own floor taken out of the angle-noise model its delay-only
/// model's order-2 rival no longer had a negative delay and took the even gain's place, said by
/// `poles_or_even_gain`; seeds 95-100 all carry the even gain.)
#[test]
fn an_extended_model_gives_its_own_gain_without_the_even_gain() {
    use imu_attest::ident::warnings::IdentWarning;
    use imu_attest::sim::SimConfig;
    use imu_attest::sim::stand::StandImperfections;
    let mut config = SimConfig::new(Regime::Cruise);
    config.duration_s = 120.0;
    config.rate_hz = 500.0;
    config.seed = 95;
    config.effects = vec!["scale_nonlinearity:gyro".parse().expect("effect")];
    config.stand = StandImperfections {
        reference_rate_hz: Some(120.0),
        ..StandImperfections::default()
    };
    let (_, run) = sim_common::simulated_run(&config);
    let low_frequency = |warnings: &[IdentWarning]| {
        warnings.iter().find_map(|w| match w {
            IdentWarning::GainChangesAcrossBand {
                k_at_low_frequency, ..
            } => Some(*k_at_low_frequency),
            _ => None,
        })
    };
    let identified =
        imu_attest::ident::identify::identify_run(&run, &Settings::default()).expect("identified");
    let gyro = identified
        .blocks
        .iter()
        .find(|b| b.block == Block::Gyro)
        .expect("gyro");
    assert!(gyro.structural.even_gain.is_some(), "{:?}", gyro.warnings);
    assert_eq!(low_frequency(&gyro.warnings), Some(true));
    let model = extend(run, &[(Block::Gyro, Effect::ScaleNonlinearity)]);
    let gyro = &model.blocks["gyro"];
    assert!(gyro.effects.is_some() && gyro.even_gain.is_none());
    assert_eq!(low_frequency(&gyro.fit.warnings), Some(false));
    // The response is the effects' alone.
    let e = gyro.effects.as_ref().expect("effects");
    let f = gyro.band_hz[1];
    assert_eq!(gyro.response(f), e.response(&gyro.k, gyro.tau_s, f));
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
