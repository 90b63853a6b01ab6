use super::*;
use crate::fourier::RecordFft;
use crate::sim::regime::Regime;
use crate::sim::{SimConfig, SimulatedRun, simulate};
use crate::stand::inputs::{accel_input, differentiate, gyro_input};

fn run(regime: Regime, seed: u64, duration_s: f64) -> SimulatedRun {
    let mut c = SimConfig::new(regime);
    c.seed = seed;
    c.duration_s = duration_s;
    simulate(&c).unwrap()
}

fn angles(r: &SimulatedRun) -> [&[f64]; 3] {
    r.angles.each_ref().map(Vec::as_slice)
}

/// Power of `est - exact` between `lo` and `hi` Hz (sum over whole-record FFT bins), and power of
/// `exact` there.
fn band_error_power(est: &[f64], exact: &[f64], rate: f64, lo: f64, hi: f64) -> (f64, f64) {
    let mut fft = RecordFft::new(est.len(), rate);
    let e: Vec<f64> = est.iter().zip(exact).map(|(a, b)| a - b).collect();
    let (se, st) = (fft.forward(&e), fft.forward(exact));
    let band = (0..fft.n_bins()).filter(|&k| (lo..=hi).contains(&fft.frequency_hz(k)));
    band.fold((0.0, 0.0), |(pe, pt), k| {
        (pe + se[k].norm_sqr(), pt + st[k].norm_sqr())
    })
}

/// Delay of `est` relative to `exact` (positive = est lags), from the cross-spectrum's phase slope
/// weighted by its magnitude over `lo..hi` Hz.
fn delay_s(est: &[f64], exact: &[f64], rate: f64, lo: f64, hi: f64) -> f64 {
    let mut fft = RecordFft::new(est.len(), rate);
    let (a, b) = (fft.forward(est), fft.forward(exact));
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..fft.n_bins() {
        let f = fft.frequency_hz(k);
        if (lo..=hi).contains(&f) {
            let c = b[k] * a[k].conj(); // phase = +w tau for a lag tau
            let w = 2.0 * std::f64::consts::PI * f;
            num += c.norm() * c.arg() * w;
            den += c.norm() * w * w;
        }
    }
    num / den
}

#[test]
fn delay_estimator_recovers_a_known_shift() {
    let r = run(Regime::Cruise, 5, 60.0);
    let rate = 500.0;
    let exact = gyro_input(&r.true_motion);
    // A two-sample shift of the exact: 4 ms exactly.
    let shifted: Vec<f64> = (0..exact[0].len())
        .map(|i| exact[0][i.saturating_sub(2)])
        .collect();
    let d = delay_s(&shifted, &exact[0], rate, 0.1, 40.0);
    assert!((d - 0.004).abs() < 2e-5, "{d}");
}

/// Per regime: (whole-spectrum rate error ratio, whole-spectrum force error ratio) naive/observer,
/// in-band ratios, and delays. Measured on 120 s runs (seeds 11..13): rate 5.0-12.3x, force
/// 56-168x over 0.1-225 Hz; 1.0-1.3x inside 0.1-40 Hz, where the stand's motion dominates the angle
/// noise and no estimator can beat the noise floor (the Wiener error there is `N S/(S+N) ~ N`).
#[test]
fn observer_beats_differentiation_and_adds_no_delay() {
    for (regime, seed) in [
        (Regime::Cruise, 11),
        (Regime::TurbulentCruise, 12),
        (Regime::Approach, 13),
    ] {
        let r = run(regime, seed, 120.0);
        let rate = 500.0;
        let est = observe(angles(&r), rate, &ObserverSettings::default()).unwrap();
        let naive = differentiate(angles(&r), rate);
        let lever = r.sidecar.accel_lever_arm_m;
        let exact = (
            gyro_input(&r.true_motion),
            accel_input(&r.true_motion, lever, 9.80665),
        );
        let obs = (gyro_input(&est.euler), accel_input(&est.euler, lever, 9.80665));
        let nai = (gyro_input(&naive), accel_input(&naive, lever, 9.80665));
        for axis in 0..3 {
            let err = |e: &[f64], t: &[f64], lo, hi| band_error_power(e, t, rate, lo, hi).0;
            let whole_w =
                err(&nai.0[axis], &exact.0[axis], 0.1, 225.0) / err(&obs.0[axis], &exact.0[axis], 0.1, 225.0);
            let whole_f =
                err(&nai.1[axis], &exact.1[axis], 0.1, 225.0) / err(&obs.1[axis], &exact.1[axis], 0.1, 225.0);
            let band_w =
                err(&nai.0[axis], &exact.0[axis], 0.1, 40.0) / err(&obs.0[axis], &exact.0[axis], 0.1, 40.0);
            let band_f =
                err(&nai.1[axis], &exact.1[axis], 0.1, 40.0) / err(&obs.1[axis], &exact.1[axis], 0.1, 40.0);
            let ctx = format!(
                "{regime} axis {axis}: whole {whole_w:.1}/{whole_f:.1}, band {band_w:.2}/{band_f:.2}"
            );
            assert!(whole_w > 4.0 && whole_f > 40.0, "{ctx}");
            assert!(band_w > 0.98 && band_f > 0.98, "{ctx}");
            // Statistical: the estimate's noise gives its phase a random part.
            let d = delay_s(&obs.0[axis], &exact.0[axis], rate, 0.1, 40.0);
            assert!(d.abs() < 1e-5, "{ctx}: rate delay {d:e} s");
            let d = delay_s(&obs.1[axis], &exact.1[axis], rate, 0.1, 40.0);
            assert!(d.abs() < 2.5e-5, "{ctx}: force delay {d:e} s");
        }
        // The estimated noise is the angle sensor's (white 1e-5 rad with a 1.5e-6 rad quantum).
        assert_eq!(est.noise_source, NoiseSource::Estimated);
        for s in est.angle_noise_rad {
            assert!((s / r.sidecar.angle_noise_rad - 1.0).abs() < 0.05, "noise {s:e}");
        }
    }
}

/// The filter itself, without measurement noise to blur the phase: observing the true angles
/// (with a declared noise level, so the smoother still shrinks where the motion is weak) must not
/// move them in time.
#[test]
fn smoother_has_zero_phase_on_clean_angles() {
    let r = run(Regime::TurbulentCruise, 21, 60.0);
    let clean = r.true_motion.angle.each_ref().map(Vec::as_slice);
    let settings = ObserverSettings {
        angle_noise_rad: Some(1e-5),
        ..ObserverSettings::default()
    };
    let est = observe(clean, 500.0, &settings).unwrap();
    assert_eq!(est.noise_source, NoiseSource::Declared);
    let exact = gyro_input(&r.true_motion);
    let obs = gyro_input(&est.euler);
    for axis in 0..3 {
        let d = delay_s(&obs[axis], &exact[axis], 500.0, 0.1, 40.0);
        assert!(d.abs() < 1e-6, "axis {axis}: {d:e} s");
        let da = delay_s(&est.euler.angle[axis], clean[axis], 500.0, 0.1, 40.0);
        assert!(da.abs() < 1e-6, "angle axis {axis}: {da:e} s");
    }
}

#[test]
fn bad_input_is_refused_not_propagated() {
    let ok = vec![0.0; 100];
    let s = ObserverSettings::default();
    let short = vec![0.0; 10];
    assert!(matches!(
        observe([&short, &short, &short], 100.0, &s),
        Err(ObserverError::TooShort { n: 10, .. })
    ));
    assert!(matches!(
        observe([&ok, &short, &ok], 100.0, &s),
        Err(ObserverError::LengthMismatch { axis: 1, .. })
    ));
    let mut nan = ok.clone();
    nan[42] = f64::NAN;
    assert!(matches!(
        observe([&ok, &ok, &nan], 100.0, &s),
        Err(ObserverError::NonFinite { axis: 2, index: 42 })
    ));
    for bad_rate in [0.0, -1.0, f64::INFINITY, f64::NAN] {
        assert!(matches!(
            observe([&ok, &ok, &ok], bad_rate, &s),
            Err(ObserverError::BadSampleRate { .. })
        ));
    }
    let neg = ObserverSettings {
        angle_noise_rad: Some(-1.0),
        ..ObserverSettings::default()
    };
    assert!(matches!(
        observe([&ok, &ok, &ok], 100.0, &neg),
        Err(ObserverError::BadNoise { .. })
    ));
    // Constant angles and zero declared noise: finite output, zero rates.
    let zero = ObserverSettings {
        angle_noise_rad: Some(0.0),
        ..ObserverSettings::default()
    };
    let still = observe([&ok, &ok, &ok], 100.0, &zero).unwrap();
    assert!(still.euler.rate.iter().flatten().all(|v| v.abs() < 1e-12));
}

/// Exact angles (a few large slow sines and many small fast ones, in closed form) declared
/// noise-free (`angle_noise_rad: 0`, as a perfect simulator or a lab trusting its encoders would
/// declare), with a gyro witness whose three axes are unequally noisy: the angular accelerations
/// are the closed form's. Without the resolution floor, the white floor of 0 let the witness's
/// noise model give one axis a noise of zero beside another's of the gyro's level, and the
/// smoother's gain `N^1/2 G N^-1/2` then carried the quiet axis into the noisy one by their
/// ratio: a 100 Hz oscillation of 10^-3 rad in yaw, accelerations of 10^3 rad/s^2.
#[test]
fn exact_angles_declared_noise_free_give_the_exact_accelerations() {
    let rate = 500.0;
    let n = 60_000;
    let mut rng = crate::rng::Rng::new(5);
    // Per axis: (amplitude rad, frequency Hz, phase).
    let sines: Vec<Vec<(f64, f64, f64)>> = (0..3)
        .map(|_| {
            let mut s: Vec<(f64, f64, f64)> = (0..3)
                .map(|_| (0.06, 0.15 + 1.3 * rng.uniform(), 6.3 * rng.uniform()))
                .collect();
            s.extend((0..200).map(|_| (2e-4, 0.1 + 19.9 * rng.uniform(), 6.3 * rng.uniform())));
            s
        })
        .collect();
    let w = |f: f64| 2.0 * std::f64::consts::PI * f;
    let value = |axis: usize, i: usize, derivative: usize| -> f64 {
        let t = i as f64 / rate;
        sines[axis]
            .iter()
            .map(|&(a, f, p)| {
                let x = w(f) * t + p;
                [a * x.sin(), a * w(f) * x.cos(), -a * w(f) * w(f) * x.sin()][derivative]
            })
            .sum()
    };
    let series =
        |d: usize| -> [Vec<f64>; 3] { std::array::from_fn(|a| (0..n).map(|i| value(a, i, d)).collect()) };
    let exact = EulerSeries {
        angle: series(0),
        rate: series(1),
        accel: series(2),
    };
    // The gyro: body rates plus white noise of 3e-5, 8e-5 and 6e-5 rad/s/sqrt(Hz).
    let mut gyro = exact.body_rates();
    for (axis, asd) in [3e-5, 8e-5, 6e-5].into_iter().enumerate() {
        let sd = asd * (rate / 2.0_f64).sqrt();
        gyro[axis].iter_mut().for_each(|v| *v += sd * rng.normal());
    }
    let settings = ObserverSettings {
        angle_noise_rad: Some(0.0),
        ..ObserverSettings::default()
    };
    let angles = exact.angle.each_ref().map(Vec::as_slice);
    for witness in [None, Some(gyro.each_ref().map(Vec::as_slice))] {
        let est = observe_with_witness(angles, rate, &settings, witness).unwrap();
        for axis in 0..3 {
            let ctx = format!("witness {}, axis {axis}", witness.is_some());
            let (e, p) = band_error_power(&est.euler.accel[axis], &exact.accel[axis], rate, 0.0, rate / 2.0);
            assert!(
                e < 2e-4 * p,
                "{ctx}: acceleration error power {:e} of the motion's",
                e / p
            );
        }
    }
}
