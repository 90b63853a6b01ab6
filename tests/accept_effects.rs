//! Issue 15, "accept means accept": an effect accepted into a block's model is fitted with the
//! paper's model on the whole record, and the model file carries the extended model (its `K`,
//! delay and the effect's size, each with a standard deviation). Checked on simulated runs whose
//! truth only this test reads: the sizes are right and the standard deviations honest (the
//! normalised errors over several seeds and regimes have rms near 1), the extended model explains
//! more, and a block without accepted effects is exactly as identified. How the extended model
//! is judged on what it now is (deviations, warnings, band): `accept_judged`.

use crate::common::sim as sim_common;

use std::sync::Arc;

use crate::common::accept::{extend, gain_and_delay_z, identify, rms};
use imu_attest::block::Block;
use imu_attest::diagnose::extend::extended_model;
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
