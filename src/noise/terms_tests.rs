//! Closed forms: white rate noise of known density and a rate random walk of known strength
//! give back their `N` and `K` within the stated intervals, over many seeds.

use super::*;
use crate::noise::allan::{averaging_factors, overlapping_avar, phase};
use crate::rng::Rng;

fn points_of(y: &[f64], fs: f64) -> Vec<AvarPoint> {
    let x = phase(y, fs);
    averaging_factors(y.len(), 2)
        .into_iter()
        .filter_map(|m| {
            overlapping_avar(&x, m, 1.0 / fs).map(|avar| AvarPoint {
                m,
                tau_s: m as f64 / fs,
                avar,
                reference: 0.0,
            })
        })
        .collect()
}

/// White rate noise of two-sided density `n` plus a rate random walk of strength `k`.
fn series(seed: u64, len: usize, fs: f64, n: f64, k: f64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let mut walk = 0.0;
    (0..len)
        .map(|_| {
            walk += k * (1.0 / fs).sqrt() * rng.normal();
            n * fs.sqrt() * rng.normal() + walk
        })
        .collect()
}

fn normalised_error(t: &TermFit, truth: f64) -> f64 {
    // One-sigma interval: the half-width on the side of the truth.
    if truth >= t.value {
        (truth - t.value) / (t.hi - t.value)
    } else {
        (t.value - truth) / (t.value - t.lo)
    }
}

#[test]
fn white_rate_noise_gives_its_random_walk_coefficient_within_its_interval() {
    let (fs, n) = (100.0_f64, 2e-3);
    let mut z = Vec::new();
    for seed in 0..16 {
        let y = series(seed, 60_000, fs, n, 0.0);
        let fit = fit_terms(&points_of(&y, fs), y.len() + 1, 0.0);
        let arw = fit
            .terms
            .iter()
            .find(|t| t.term == NoiseTerm::RandomWalk)
            .expect("white noise is found");
        assert!(arw.share > 0.9, "{arw:?}");
        assert!(
            (arw.value / n - 1.0).abs() < 0.05,
            "seed {seed}: {} vs {n}",
            arw.value
        );
        z.push(normalised_error(arw, n));
        // Nothing else is big: from the shortest tau to a fiftieth of the record the white term
        // explains most of the variance.
        for tau in [1.0 / fs, 1.0, 10.0] {
            assert_eq!(fit.dominant(tau), NoiseTerm::RandomWalk, "seed {seed} tau {tau}");
        }
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    assert!(
        rms < 1.4,
        "normalised ARW errors rms {rms}: intervals too narrow ({z:?})"
    );
    assert!(
        rms > 0.05,
        "normalised ARW errors rms {rms}: intervals meaninglessly wide"
    );
}

#[test]
fn a_rate_random_walk_gives_its_strength_within_its_interval() {
    let (fs, n, k) = (100.0_f64, 1e-3, 2e-4);
    let mut z = Vec::new();
    for seed in 0..16 {
        let y = series(100 + seed, 200_000, fs, n, k);
        let fit = fit_terms(&points_of(&y, fs), y.len() + 1, 0.0);
        let rrw = fit
            .terms
            .iter()
            .find(|t| t.term == NoiseTerm::RateRandomWalk)
            .expect("the walk is found");
        let arw = fit
            .terms
            .iter()
            .find(|t| t.term == NoiseTerm::RandomWalk)
            .expect("the white part is found");
        assert!((arw.value / n - 1.0).abs() < 0.05, "seed {seed}: N {}", arw.value);
        assert!(
            (rrw.value / k - 1.0).abs() < 0.6,
            "seed {seed}: K {} vs {k}",
            rrw.value
        );
        z.push(normalised_error(rrw, k));
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    assert!(rms < 1.4, "normalised RRW errors rms {rms} ({z:?})");
}

#[test]
fn each_term_alone_is_recovered_from_its_exact_curve() {
    // Exact variances (no estimation noise): the fit returns the coefficient it was given.
    for (k, term) in NoiseTerm::ALL.iter().take(5).enumerate() {
        let mut coefficients = [0.0; 6];
        coefficients[k] = 1e-6;
        let truth = PowerLawFit {
            coefficients,
            ..PowerLawFit::default()
        };
        let points: Vec<AvarPoint> = averaging_factors(1 << 20, 2)
            .into_iter()
            .map(|m| AvarPoint {
                m,
                tau_s: m as f64 * 0.01,
                avar: truth.avar(m as f64 * 0.01),
                reference: 0.0,
            })
            .collect();
        let fit = fit_terms(&points, (1 << 20) + 1, 0.0);
        for (j, c) in fit.coefficients.iter().enumerate() {
            let want = if j == k { 1e-6 } else { 0.0 };
            assert!((c - want).abs() < 1e-12, "{term:?}: c[{j}] = {c}");
        }
        assert_eq!(fit.terms.len(), 1);
        assert!((fit.terms[0].value - term.value_of(1e-6)).abs() < 1e-9);
    }
    // Too few points: nothing.
    assert!(fit_terms(&[], 10, 0.0).terms.is_empty());
}

#[test]
fn display_units_follow_ieee_usage() {
    // 1 deg/sqrt(h) = (pi/180)/60 rad/sqrt(s).
    let (unit, scale) = NoiseTerm::RandomWalk.unit_on(Block::Gyro);
    assert_eq!(unit, "deg/sqrt(h)");
    assert!((std::f64::consts::PI / 180.0 / 60.0 * scale - 1.0).abs() < 1e-12);
    // 1 deg/h = (pi/180)/3600 rad/s; 1 ug = 9.80665e-6 m/s^2.
    assert!(
        (std::f64::consts::PI / 180.0 / 3600.0 * NoiseTerm::BiasInstability.unit_on(Block::Gyro).1 - 1.0)
            .abs()
            < 1e-12
    );
    assert!((9.806_65e-6 * NoiseTerm::BiasInstability.unit_on(Block::Accel).1 - 1.0).abs() < 1e-12);
    assert_eq!(NoiseTerm::RandomWalk.id_on(Block::Accel), "velocity_random_walk");
    // Bias instability: the flat Allan deviation is 0.664 B.
    let c = (0.664_f64 * 2.0).powi(2);
    assert!((NoiseTerm::BiasInstability.value_of(c) / 2.0 - 1.0).abs() < 1e-3);
}

#[test]
fn correlated_noise_has_its_closed_form_limits() {
    // Well below T_c a rate random walk K^2 tau / 3 with K^2 = 2 sigma_c^2 / T_c; well above,
    // a white rate N^2 / tau with N^2 = 2 sigma_c^2 T_c.
    let tc = 2.0;
    let t = NoiseTerm::Correlated;
    for tau in [1e-5, 1e-3, 0.01] {
        let want = 2.0 / tc * tau / 3.0;
        assert!((t.shape(tau, tc) / want - 1.0).abs() < 0.01, "{tau}");
    }
    let far = 2000.0;
    assert!((t.shape(far, tc) / (2.0 * tc / far) - 1.0).abs() < 2e-3);
    // Continuous across the series switch.
    let (a, b) = (t.shape(0.999e-3 * tc, tc), t.shape(1.001e-3 * tc, tc));
    // Nearly linear there (g ~ 2x/3 (1 - 3x/4)): the ratio of the two sides is the ratio of x.
    assert!((a / b - 0.999 / 1.001).abs() < 1e-5, "{a} {b}");
    assert!(t.shape(1.0, 0.0).abs() < f64::MIN_POSITIVE);
}

#[test]
fn a_first_order_markov_process_is_found_with_its_correlation_time() {
    // sigma_c = 1e-3, T_c = 0.5 s, on white noise of density 1e-4, at 100 Hz for 2000 s.
    let (fs, sigma, tc, n) = (100.0_f64, 1e-3, 0.5, 1e-4);
    let a = (-1.0 / (fs * tc)).exp();
    for seed in 0..4 {
        let mut rng = Rng::new(300 + seed);
        let mut x = 0.0;
        let y: Vec<f64> = (0..200_000)
            .map(|_| {
                x = a * x + sigma * (1.0 - a * a).sqrt() * rng.normal();
                x + n * fs.sqrt() * rng.normal()
            })
            .collect();
        let fit = fit_terms(&points_of(&y, fs), y.len() + 1, 0.0);
        let c = fit
            .terms
            .iter()
            .find(|t| t.term == NoiseTerm::Correlated)
            .expect("the Markov process is found");
        assert!(
            (c.value / sigma - 1.0).abs() < 0.3,
            "seed {seed}: sigma {} vs {sigma}",
            c.value
        );
        assert!(
            (fit.correlation_time_s / tc).ln().abs() < 1.8_f64.ln(),
            "seed {seed}: T_c {}",
            fit.correlation_time_s
        );
    }
}
