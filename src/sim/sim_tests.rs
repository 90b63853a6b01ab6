use super::effect::{Block, Effect, EffectSpec};
use super::regime::Regime;
use super::truth::{BlockTruth, EffectTruth};
use super::*;
use crate::stand::inputs::{accel_input, gyro_input};

fn config(regime: Regime, seed: u64, duration_s: f64, effects: &[&str]) -> SimConfig {
    let mut c = SimConfig::new(regime);
    c.seed = seed;
    c.duration_s = duration_s;
    c.effects = effects.iter().map(|e| e.parse::<EffectSpec>().unwrap()).collect();
    c
}

use super::interp::lagrange;

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

fn cov(a: &[f64], b: &[f64]) -> f64 {
    let (ma, mb) = (mean(a), mean(b));
    a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum::<f64>() / a.len() as f64
}

/// Output minus `K u(t - tau) - bias`, away from the ends, with the input's derivative.
fn residual(
    out: &[Vec<f64>; 3],
    input: &[Vec<f64>; 3],
    truth: &BlockTruth,
    rate: f64,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let n = input[0].len();
    let range = 10..n - 10;
    let delayed: Vec<Vec<f64>> = input
        .iter()
        .map(|u| {
            range
                .clone()
                .map(|i| lagrange(u, rate, i as f64 / rate - truth.tau_s))
                .collect()
        })
        .collect();
    let r = (0..3)
        .map(|i| {
            range
                .clone()
                .enumerate()
                .map(|(m, n)| {
                    out[i][n] - truth.bias[i] - (0..3).map(|j| truth.k[i][j] * delayed[j][m]).sum::<f64>()
                })
                .collect()
        })
        .collect();
    let du = input
        .iter()
        .map(|u| {
            range
                .clone()
                .map(|i| (u[i + 1] - u[i - 1]) * rate / 2.0)
                .collect()
        })
        .collect();
    (r, du)
}

#[test]
fn same_seed_same_numbers_other_seed_other_numbers() {
    let a = simulate(&config(Regime::Approach, 9, 20.0, &["sensor_lag"])).unwrap();
    let b = simulate(&config(Regime::Approach, 9, 20.0, &["sensor_lag"])).unwrap();
    let c = simulate(&config(Regime::Approach, 10, 20.0, &["sensor_lag"])).unwrap();
    assert_eq!(a.angles, b.angles);
    assert_eq!(a.gyro, b.gyro);
    assert_eq!(a.accel, b.accel);
    assert_eq!(a.sidecar, b.sidecar);
    assert_ne!(a.angles, c.angles);
    assert_ne!(a.sidecar.truth.gyro, c.sidecar.truth.gyro);
}

#[test]
fn outputs_are_k_times_delayed_input_plus_the_declared_noise() {
    let rate = 500.0;
    let r = simulate(&config(Regime::TurbulentCruise, 4, 120.0, &[])).unwrap();
    let truth = &r.sidecar.truth;
    let blocks = [
        (
            r.gyro.as_ref().unwrap(),
            gyro_input(&r.true_motion),
            truth.gyro.as_ref().unwrap(),
        ),
        (
            r.accel.as_ref().unwrap(),
            accel_input(&r.true_motion, truth.accel_lever_arm_true_m, G_STANDARD),
            truth.accel.as_ref().unwrap(),
        ),
    ];
    for (out, input, bt) in blocks {
        let (res, du) = residual(out, &input, bt, rate);
        for i in 0..3 {
            // Residual power = integral of the disturbance PSD, in bands up to 100 Hz (above, the
            // 8-point Lagrange reference itself loses accuracy).
            for (lo, hi) in [(0.0, 1.0), (1.0, 10.0), (10.0, 40.0), (40.0, 100.0)] {
                let model: f64 = ((lo * 100.0) as usize + 1..(hi * 100.0) as usize)
                    .map(|k| bt.noise.psd(k as f64 * 0.01)[i][i] * 0.01)
                    .sum();
                let p = band_power(&res[i], rate, lo, hi);
                // Four standard errors of a sum of (hi - lo) * 120 s periodogram bins.
                let tolerance = 4.0 / ((hi - lo) * 120.0f64).sqrt();
                assert!(
                    (p / model - 1.0).abs() < tolerance,
                    "channel {i}, {lo}-{hi} Hz: residual {p:e}, noise model {model:e}"
                );
            }
            // A delay error d would leave -d K u' in the residual: regress on u'.
            for j in 0..3 {
                let b = band_regression(&res[i], &du[j], rate, 0.1, 40.0);
                assert!(
                    b.abs() < 5e-6,
                    "channel {i} on input {j}: delay-like term {b:e} s"
                );
            }
        }
        // Cross-correlation of the disturbance (0-100 Hz) matches its model's white+coloured mix.
        let model = |i: usize, j: usize| {
            (1..10_000)
                .map(|k| bt.noise.psd(f64::from(k) * 0.01)[i][j] * 0.01)
                .sum::<f64>()
        };
        let band =
            |a: &[f64], b: &[f64]| band_regression(a, b, rate, 0.0, 100.0) * band_power(b, rate, 0.0, 100.0);
        let c01 = band(&res[0], &res[1]) / (band(&res[0], &res[0]) * band(&res[1], &res[1])).sqrt();
        let expected = model(0, 1) / (model(0, 0) * model(1, 1)).sqrt();
        assert!((c01 - expected).abs() < 0.03, "correlation {c01} vs {expected}");
    }
}

#[test]
fn angle_sensors_add_declared_noise_and_quantise() {
    let r = simulate(&config(Regime::Cruise, 2, 60.0, &[])).unwrap();
    let q = r.sidecar.truth.angle_quantum_rad;
    for axis in 0..3 {
        let e: Vec<f64> = r.angles[axis]
            .iter()
            .zip(&r.true_motion.angle[axis])
            .map(|(m, t)| m - t)
            .collect();
        let sd = cov(&e, &e).sqrt();
        assert!(
            (sd / r.sidecar.angle_noise_rad - 1.0).abs() < 0.03,
            "axis {axis}: {sd:e}"
        );
        assert!(
            r.angles[axis]
                .iter()
                .all(|v| ((v / q).round() - v / q).abs() < 1e-6)
        );
    }
}

/// Least-squares coefficient of `y` on `x` using only their content between `lo` and `hi` Hz.
fn band_regression(y: &[f64], x: &[f64], rate: f64, lo: f64, hi: f64) -> f64 {
    let mut fft = crate::fourier::RecordFft::new(x.len(), rate);
    let (sy, sx) = (fft.forward(y), fft.forward(x));
    let band: Vec<usize> = (0..fft.n_bins())
        .filter(|&k| (lo..hi).contains(&fft.frequency_hz(k)))
        .collect();
    band.iter().map(|&k| (sy[k] * sx[k].conj()).re).sum::<f64>()
        / band.iter().map(|&k| sx[k].norm_sqr()).sum::<f64>()
}

/// Band power of `x` between `lo` and `hi` Hz.
fn band_power(x: &[f64], rate: f64, lo: f64, hi: f64) -> f64 {
    let mut fft = crate::fourier::RecordFft::new(x.len(), rate);
    let s = fft.forward(x);
    (0..fft.n_bins())
        .filter(|&k| (lo..hi).contains(&fft.frequency_hz(k)))
        .map(|k| s[k].norm_sqr())
        .sum::<f64>()
        * 2.0
        / (x.len() as f64).powi(2)
}

#[test]
fn regimes_move_every_axis_up_to_the_high_band_with_cross_coupling() {
    let rate = 500.0;
    let mut high_band = Vec::new();
    for regime in Regime::ALL {
        let r = simulate(&config(regime, 3, 120.0, &[])).unwrap();
        let w = gyro_input(&r.true_motion);
        let noise_asd = r.sidecar.truth.gyro.as_ref().unwrap().noise.white_asd;
        for axis in 0..3 {
            // Rate power between 10 and 20 Hz far above the gyro's own noise there.
            let p = band_power(&w[axis], rate, 10.0, 20.0);
            assert!(
                p > 100.0 * noise_asd[axis].powi(2) * 10.0,
                "{regime} axis {axis}: {p:e}"
            );
        }
        high_band.push(band_power(&w[0], rate, 5.0, 25.0));
        // Roll and yaw are coupled (Dutch roll): correlated, not independent.
        let c = cov(&r.true_motion.rate[0], &r.true_motion.rate[1]);
        let rho = c
            / (cov(&r.true_motion.rate[0], &r.true_motion.rate[0])
                * cov(&r.true_motion.rate[1], &r.true_motion.rate[1]))
            .sqrt();
        assert!(rho.abs() > 0.05, "{regime}: roll-yaw rate correlation {rho}");
    }
    assert!(
        high_band[1] > 4.0 * high_band[0],
        "turbulence must shake more than calm cruise: {high_band:?}"
    );
}

/// Runs the same seed with and without one effect; the difference of the outputs is the effect.
fn effect_difference(effect: &str, block: Block) -> (SimulatedRun, Vec<Vec<f64>>, EffectTruth) {
    let plain = simulate(&config(Regime::TurbulentCruise, 6, 60.0, &[])).unwrap();
    let with = simulate(&config(Regime::TurbulentCruise, 6, 60.0, &[effect])).unwrap();
    let pick = |r: &SimulatedRun| {
        if block == Block::Gyro {
            r.gyro.clone().unwrap()
        } else {
            r.accel.clone().unwrap()
        }
    };
    let (a, b) = (pick(&plain), pick(&with));
    let diff = (0..3)
        .map(|i| b[i].iter().zip(&a[i]).map(|(x, y)| x - y).collect())
        .collect();
    let bt = if block == Block::Gyro {
        with.sidecar.truth.gyro.clone()
    } else {
        with.sidecar.truth.accel.clone()
    };
    let e = bt.unwrap().effects.into_iter().next().unwrap();
    (with, diff, e)
}

#[test]
fn every_effect_is_recorded_in_the_truth_and_changes_only_its_block() {
    for effect in Effect::ALL {
        for &block in effect.blocks() {
            let spec = format!("{}:{}", effect.id(), block.name());
            let r = simulate(&config(Regime::Cruise, 8, 20.0, &[&spec])).unwrap();
            let plain = simulate(&config(Regime::Cruise, 8, 20.0, &[])).unwrap();
            let (bt, other, other_plain, own, own_plain) = match block {
                Block::Gyro => (
                    &r.sidecar.truth.gyro,
                    &r.accel,
                    &plain.accel,
                    &r.gyro,
                    &plain.gyro,
                ),
                Block::Accel => (
                    &r.sidecar.truth.accel,
                    &r.gyro,
                    &plain.gyro,
                    &r.accel,
                    &plain.accel,
                ),
            };
            let effects = &bt.as_ref().unwrap().effects;
            assert_eq!(effects.len(), 1, "{spec}");
            assert_eq!(effects[0].effect(), effect, "{spec}");
            assert_eq!(other, other_plain, "{spec} changed the other block");
            assert_ne!(own, own_plain, "{spec} changed nothing");
            assert_eq!(r.angles, plain.angles, "{spec} changed the angles");
        }
    }
}

#[test]
fn g_sensitivity_and_scale_nonlinearity_have_their_recorded_size() {
    let rate = 500.0;
    let (r, diff, e) = effect_difference("g_sensitivity", Block::Gyro);
    let EffectTruth::GSensitivity { g_matrix } = e else {
        panic!("{e:?}")
    };
    let tau = r.sidecar.truth.gyro.as_ref().unwrap().tau_s;
    let f = accel_input(&r.true_motion, r.sidecar.gyro_lever_arm_m, G_STANDARD);
    let n = f[0].len();
    let fd: Vec<Vec<f64>> = f
        .iter()
        .map(|c| {
            (10..n - 10)
                .map(|i| lagrange(c, rate, i as f64 / rate - tau))
                .collect()
        })
        .collect();
    for i in 0..3 {
        let d: Vec<f64> = diff[i][10..n - 10].to_vec();
        let predicted: Vec<f64> = (0..d.len())
            .map(|m| (0..3).map(|j| g_matrix[i][j] * fd[j][m]).sum())
            .collect();
        let err: f64 = d
            .iter()
            .zip(&predicted)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>();
        let size: f64 = d.iter().map(|a| a * a).sum();
        assert!(err < 1e-3 * size, "channel {i}: relative error {}", err / size);
    }
    let (r, diff, e) = effect_difference("scale_nonlinearity:accel", Block::Accel);
    let EffectTruth::ScaleNonlinearity { k2 } = e else {
        panic!("{e:?}")
    };
    let bt = r.sidecar.truth.accel.as_ref().unwrap();
    let u = accel_input(&r.true_motion, r.sidecar.truth.accel_lever_arm_true_m, G_STANDARD);
    for i in 0..3 {
        let ud: Vec<f64> = (10..n - 10)
            .map(|m| lagrange(&u[i], rate, m as f64 / rate - bt.tau_s))
            .collect();
        let q: Vec<f64> = ud.iter().map(|v| v * v.abs()).collect();
        let d = &diff[i][10..n - 10];
        let fit = d.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>() / q.iter().map(|b| b * b).sum::<f64>();
        assert!((fit / k2[i] - 1.0).abs() < 0.01, "k2[{i}] {fit:e} vs {:e}", k2[i]);
    }
}

#[test]
fn vibration_tone_lag_and_resonance_act_at_their_frequencies() {
    let rate = 500.0;
    let (_, diff, e) = effect_difference("vibration_tone:gyro", Block::Gyro);
    let EffectTruth::VibrationTone {
        frequency_hz,
        amplitude,
        phase_rad,
        ..
    } = e
    else {
        panic!("{e:?}")
    };
    for i in 0..3 {
        let n = diff[i].len();
        let w = 2.0 * std::f64::consts::PI * frequency_hz;
        let (s, c) = (0..n).fold((0.0, 0.0), |(s, c), k| {
            let t = k as f64 / rate;
            (s + diff[i][k] * (w * t).sin(), c + diff[i][k] * (w * t).cos())
        });
        let amp = 2.0 * (s * s + c * c).sqrt() / n as f64;
        assert!(
            (amp / amplitude[i] - 1.0).abs() < 0.01,
            "tone amplitude {amp} vs {}",
            amplitude[i]
        );
        assert!(
            ((c.atan2(s) - phase_rad[i] + 3.0 * std::f64::consts::PI) % (2.0 * std::f64::consts::PI)
                - std::f64::consts::PI)
                .abs()
                < 0.02
        );
    }
    // A lag leaves a difference that grows with frequency like |1/(1 + j w T) - 1|.
    let (r, diff, e) = effect_difference("sensor_lag:gyro", Block::Gyro);
    let EffectTruth::SensorLag { time_constant_s } = e else {
        panic!("{e:?}")
    };
    let out = r.gyro.as_ref().unwrap();
    for (lo, hi) in [(1.0, 2.0), (12.0, 18.0)] {
        let ratio = (band_power(&diff[0], rate, lo, hi) / band_power(&out[0], rate, lo, hi)).sqrt();
        let fm = 2.0 * std::f64::consts::PI * (lo + hi) / 2.0 * time_constant_s;
        let expected = fm / (1.0f64 + fm * fm).sqrt() * (1.0 + fm * fm).sqrt() / (1.0 + fm * fm).sqrt();
        assert!(
            (ratio / expected - 1.0).abs() < 0.25,
            "{lo}-{hi} Hz: {ratio} vs {expected}"
        );
    }
    let (_, diff, e) = effect_difference("platform_resonance:gyro", Block::Gyro);
    let EffectTruth::PlatformResonance { frequency_hz, .. } = e else {
        panic!("{e:?}")
    };
    let near = band_power(&diff[0], rate, frequency_hz - 1.0, frequency_hz + 1.0)
        + band_power(&diff[1], rate, frequency_hz - 1.0, frequency_hz + 1.0)
        + band_power(&diff[2], rate, frequency_hz - 1.0, frequency_hz + 1.0);
    let low = band_power(&diff[0], rate, 0.5, 3.0)
        + band_power(&diff[1], rate, 0.5, 3.0)
        + band_power(&diff[2], rate, 0.5, 3.0);
    assert!(
        near > 10.0 * low,
        "resonance difference concentrated near {frequency_hz} Hz: {near:e} vs {low:e}"
    );
}

#[test]
fn bad_configurations_are_refused() {
    let mut c = config(Regime::Cruise, 1, 10.0, &[]);
    c.duration_s = -1.0;
    assert!(matches!(simulate(&c), Err(SimError::BadDuration(_))));
    c.duration_s = 0.1;
    assert!(matches!(simulate(&c), Err(SimError::SampleCount { .. })));
    c.duration_s = 10.0;
    c.rate_hz = 100.0;
    assert!(matches!(simulate(&c), Err(SimError::RateTooLow(_))));
    c.rate_hz = f64::NAN;
    assert!(matches!(simulate(&c), Err(SimError::BadRate(_))));
    c.rate_hz = 500.0;
    c.blocks = vec![Block::Gyro];
    c.effects = vec!["lever_arm_error".parse().unwrap()];
    assert!(matches!(simulate(&c), Err(SimError::EffectWithoutBlock { .. })));
    c.blocks.clear();
    assert!(matches!(simulate(&c), Err(SimError::NoBlock)));
}

#[test]
fn stand_imperfections_do_what_they_say_and_default_to_none() {
    let base = config(Regime::Cruise, 21, 20.0, &[]);
    let clean = simulate(&base).unwrap();
    // Latency alone: the measured angle is the true angle `latency` late (an independent
    // interpolation of the true angle), up to the white noise and quantum (1e-5 rad).
    let latency = 0.004;
    let mut late = base.clone();
    late.stand.latency_s = latency;
    let run = simulate(&late).unwrap();
    let rate = base.rate_hz;
    let mut worst: f64 = 0.0;
    for i in 100..run.time_s.len() - 100 {
        let expected = lagrange(&clean.true_motion.angle[1], rate, run.time_s[i] - latency);
        worst = worst.max((run.angles[1][i] - expected).abs());
    }
    assert!(worst < 8e-5, "latency: worst deviation {worst:.2e} rad");
    assert!((run.sidecar.truth.stand.latency_s - latency).abs() < 1e-15);
    // The blocks are the same draws: the imperfections only touch the angles.
    assert_eq!(run.gyro, clean.gyro);
    // Band limit at 20 Hz: above 30 Hz the measured angles' second difference (a high-pass that
    // keeps the low-frequency motion from leaking) holds a small fraction of the clean run's.
    let mut limited = base.clone();
    limited.stand.band_limit_hz = Some(20.0);
    let band = simulate(&limited).unwrap();
    let power_above = |x: &[f64]| {
        let d2: Vec<f64> = x.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]).collect();
        let mut fft = crate::fourier::RecordFft::new(d2.len(), rate);
        let spec = fft.forward(&d2);
        (0..spec.len())
            .filter(|&k| fft.frequency_hz(k) > 30.0)
            .map(|k| spec[k].norm_sqr())
            .sum::<f64>()
    };
    // The band-limited minus the clean measurement (same noise draws) is the motion removed:
    // above 30 Hz all of the true motion there.
    let removed: Vec<f64> = band.angles[0]
        .iter()
        .zip(&clean.angles[0])
        .map(|(b, c)| b - c)
        .collect();
    let (removed_power, motion_power) = (power_above(&removed), power_above(&clean.true_motion.angle[0]));
    assert!(
        (0.7..1.3).contains(&(removed_power / motion_power)),
        "{removed_power:.3e} vs {motion_power:.3e}"
    );
    // Coloured noise: the angle error has the rms asked for, most of it below the corner.
    let mut coloured = base.clone();
    coloured.stand.coloured_noise_rad = 1e-4;
    coloured.stand.coloured_corner_hz = 2.0;
    let col = simulate(&coloured).unwrap();
    let err: Vec<f64> = (0..col.angles[2].len())
        .map(|i| col.angles[2][i] - clean.angles[2][i])
        .collect();
    let rms = (err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64).sqrt();
    assert!((0.6e-4..1.4e-4).contains(&rms), "coloured rms {rms:.2e}");
    // Default: none, and the sidecar says nothing of a stand.
    assert!(!base.stand.any());
    let text = serde_json::to_string(&clean.sidecar).unwrap();
    assert!(!text.contains("\"stand\""), "{text}");
}

/// A slower reference interpolated linearly weighs a sine by the triangle kernel's response,
/// `sinc^2(f / f_r)`, exactly at the sine's frequency (its images lie at `k f_r +- f`): a
/// least-squares fit of the sine's amplitude on the output, over whole periods, against the closed
/// form (the cubic read-off adds `(f / f_s)^4`).
#[test]
fn a_slower_reference_weighs_the_motion_by_the_triangle_kernel() {
    let (fs, fr) = (500.0, 120.0);
    let n = 50_000_u32;
    // At 2 Hz the weight is 0.99909: the tolerance (the read-off's own smoothing, 3.5e-4 at
    // 10 Hz) is about half its distance from 1.
    for f in [2.0, 10.0, 25.0] {
        let w = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..n).map(|i| (w * f64::from(i) / fs + 0.3).sin()).collect();
        let y = super::stand::through_slower_reference(&x, fs, fr);
        let (mut sc, mut cc) = (0.0, 0.0);
        for (i, v) in y.iter().enumerate() {
            let phase = w * i as f64 / fs + 0.3;
            sc += v * phase.sin();
            cc += v * phase.cos();
        }
        let (gain, quadrature) = (2.0 * sc / f64::from(n), 2.0 * cc / f64::from(n));
        let sinc = |u: f64| (std::f64::consts::PI * u).sin() / (std::f64::consts::PI * u);
        let expected = sinc(f / fr).powi(2);
        assert!(
            (gain - expected).abs() < 5e-4,
            "{f} Hz: {gain} against {expected}"
        );
        // Zero phase: no delay.
        assert!(quadrature.abs() < 5e-4, "{f} Hz: quadrature {quadrature}");
    }
    // A reference as fast as the run, or a bad rate, leaves the angles as they are.
    let x = [0.0, 1.0, -2.0, 0.5];
    assert_eq!(super::stand::through_slower_reference(&x, fs, fs), x.to_vec());
    assert_eq!(
        super::stand::through_slower_reference(&x, fs, f64::NAN),
        x.to_vec()
    );
}

/// The sidecar's fields beyond the run format's are exactly those the loader passes over
/// without a notice ([`EXTRA_SIDECAR_FIELDS`]).
#[test]
fn the_sidecar_s_extra_fields_are_declared() {
    let r = simulate(&config(Regime::Cruise, 2, 20.0, &[])).unwrap();
    let value = serde_json::to_value(&r.sidecar).unwrap();
    let format = crate::run::SIDECAR_FIELDS;
    let extra: Vec<&str> = value
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .filter(|k| !format.contains(k))
        .collect();
    assert_eq!(extra, EXTRA_SIDECAR_FIELDS);
}
