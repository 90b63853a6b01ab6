//! The stationarity stretches' tests: a drift is told from delays near a line by chance, the
//! own-errors floor is the closed form, and a stretch whose best delay is the scan's end is named.

use super::*;

/// Four stretches of a clean 120 s run of an independent simulator (gyro, true delay
/// 0.71491 ms, no drift): their delays, ms, and own standard deviations, ms.
const CLEAN: [(f64, f64, f64, f64); 4] = [
    (0.0, 32.8, 0.71647, 0.00086),
    (28.7, 61.4, 0.71507, 0.00075),
    (57.3, 90.1, 0.71491, 0.00100),
    (86.0, 118.8, 0.71402, 0.00083),
];

fn stationarity_of(stretches: &[(f64, f64, f64, f64)]) -> Stationarity {
    let fits: Vec<StretchFit> = stretches
        .iter()
        .map(|&(a, b, tau_ms, std_ms)| StretchFit {
            span_s: [a, b],
            k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            tau_s: tau_ms * 1e-3,
            tau_std_s: std_ms * 1e-3,
        })
        .collect();
    let t: Vec<f64> = fits.iter().map(|s| 0.5 * (s.span_s[0] + s.span_s[1])).collect();
    let y: Vec<f64> = fits.iter().map(|s| s.tau_s).collect();
    let own: Vec<f64> = fits.iter().map(|s| s.tau_std_s).collect();
    let (tau_trend, tau_trend_std) = line_slope(&t, &y, &own);
    Stationarity {
        stretches: fits,
        k_spread_std: [[0.0; 3]; 3],
        tau_spread_std_s: 0.0,
        segment_len: None,
        tau_trend,
        tau_trend_std,
        no_delay_s: Vec::new(),
        delay_step: None,
    }
}

/// The clean run's delays lie close to a line by chance: the residuals alone put its slope
/// at 4.7 of their standard deviations (a false drift); the stretches' own errors do not.
#[test]
fn four_stretches_near_a_line_by_chance_do_not_drift() {
    let st = stationarity_of(&CLEAN);
    assert!(!st.drifts(), "{st:?}");
    let t: Vec<f64> = CLEAN.iter().map(|s| 0.5 * (s.0 + s.1)).collect();
    let y: Vec<f64> = CLEAN.iter().map(|s| s.2 * 1e-3).collect();
    let (slope, residual_only) = line_slope(&t, &y, &[0.0; 4]);
    assert!(slope.abs() > 4.0 * residual_only, "{slope} {residual_only}");
    assert!(
        slope.abs() < 2.5 * st.tau_trend_std,
        "{slope} {}",
        st.tau_trend_std
    );
}

/// A drift of 0.5 ppm (60 us over the run) on the same stretches is found, at its rate.
#[test]
fn a_drift_well_beyond_the_stretches_errors_is_found() {
    let drifting: Vec<(f64, f64, f64, f64)> = CLEAN
        .iter()
        .map(|&(a, b, _, s)| (a, b, 0.715 + 0.5e-6 * 0.5 * (a + b) * 1e3, s))
        .collect();
    let st = stationarity_of(&drifting);
    assert!(st.drifts(), "{st:?}");
    assert!((st.tau_trend / 0.5e-6 - 1.0).abs() < 1e-9, "{}", st.tau_trend);
}

/// Closed form: equal own deviations `s` and exact points give the slope's deviation
/// `s / sqrt(sum (t - t_mean)^2)`.
#[test]
fn the_own_errors_floor_is_the_closed_form() {
    let t = [0.0, 1.0, 2.0, 3.0, 4.0];
    let y: Vec<f64> = t.iter().map(|v| 2.0 + 0.5 * v).collect();
    let (slope, std) = line_slope(&t, &y, &[0.1; 5]);
    assert!((slope - 0.5).abs() < 1e-12);
    assert!((std - 0.1 / 10.0_f64.sqrt()).abs() < 1e-12, "{std}");
}

/// A stretch of exact data, the sum of `(gain, delay)` terms each `K gain e^(-delay s)` (`K` a
/// small misalignment), 0.1-40 Hz, with a white residual of `1e-4` of the gain per bin.
fn exact_stretch(terms: &[(f64, f64)]) -> (StretchSpectra, Vec<f64>) {
    let frequency_hz: Vec<f64> = (1..=400).map(|k| 0.1 * f64::from(k)).collect();
    let k = Matrix3::new(1.0, 2e-3, 0.0, -1e-3, 1.0, 1e-3, 0.0, 0.0, 1.0).map(Complex64::from);
    let mut s = StretchSpectra {
        span_s: [0.0, 30.0],
        s_uu: Vec::new(),
        s_xu: Vec::new(),
        s_xx: Vec::new(),
        equivalent_averages: 20.0,
        moments: None,
    };
    for f in &frequency_hz {
        let phase = |tau: f64| Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * tau);
        let w = k * terms.iter().map(|&(g, tau)| phase(tau) * g).sum::<Complex64>();
        s.s_uu.push(Matrix3::identity());
        s.s_xx
            .push(w * w.adjoint() + Matrix3::identity() * Complex64::from(1e-8));
        s.s_xu.push(w);
    }
    (s, frequency_hz)
}

/// A delay inside the scan is found to a microsecond; one just beyond either end leaves the
/// best of the range at that end, which is no measurement: the stretch is named, not fitted.
#[test]
fn a_stretch_whose_best_delay_is_the_scan_s_end_is_named_not_fitted() {
    for (tau, found) in [(0.003, true), (-0.25, true), (0.31, false), (-0.32, false)] {
        let (s, frequency_hz) = exact_stretch(&[(1.0, tau)]);
        let native: Vec<usize> = (0..frequency_hz.len()).collect();
        let at = At {
            frequency_hz: &frequency_hz,
            offset_hz: None,
            aligned_s: 0.0,
        };
        match fit_stretch(&s, &native, 1, at) {
            Outcome::Fitted(fit) => {
                assert!(found, "{tau}: fitted at {}", fit.tau_s);
                assert!((fit.tau_s - tau).abs() < 1e-6, "{tau}: {}", fit.tau_s);
            }
            Outcome::NoDelay(span) => {
                assert!(!found, "{tau}: named");
                assert_eq!(span.map(f64::to_bits), [0.0, 30.0].map(f64::to_bits));
            }
            Outcome::Failed => panic!("{tau}: failed"),
        }
    }
}

/// Four stretches fitted give a summary; three fitted beside one with no delay give one on
/// the three that names the fourth; three fitted beside a failed one, or two beside one with
/// no delay, give none.
#[test]
fn a_stretch_with_no_delay_is_named_and_the_others_summarised() {
    let fitted = |k: usize| {
        Outcome::Fitted(StretchFit {
            span_s: [30.0 * k as f64, 30.0 * (k + 1) as f64],
            k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            tau_s: 0.004 + 1e-6 * k as f64,
            tau_std_s: 1e-6,
        })
    };
    let all = summarise((0..4).map(fitted).collect(), None, 100.0).expect("four");
    assert!(all.no_delay_s.is_empty());
    let mut outcomes: Vec<Outcome> = (0..3).map(fitted).collect();
    outcomes.push(Outcome::NoDelay([90.0, 120.0]));
    let three = summarise(outcomes, None, 100.0).expect("three and one named");
    assert_eq!(three.stretches.len(), 3);
    assert_eq!(three.no_delay_s, vec![[90.0, 120.0]]);
    assert!(
        (three.tau_spread_std_s - 1e-6 / 3f64.sqrt()).abs() < 1e-12,
        "{}",
        three.tau_spread_std_s
    );
    let mut failed: Vec<Outcome> = (0..3).map(fitted).collect();
    failed.push(Outcome::Failed);
    assert!(summarise(failed, None, 100.0).is_none());
    let mut two: Vec<Outcome> = (0..2).map(fitted).collect();
    two.extend([Outcome::NoDelay([60.0, 90.0]), Outcome::NoDelay([90.0, 120.0])]);
    assert!(summarise(two, None, 100.0).is_none());
}

/// The warning names each stretch left out and what the check rests on.
#[test]
fn the_warning_names_the_stretches_without_a_delay() {
    let one = super::super::warnings::IdentWarning::StretchesWithoutDelay {
        spans_s: vec![[57.344, 90.112]],
        fitted: 3,
    }
    .to_string();
    assert!(one.contains("a stretch of the record (57.3-90.1 s)"), "{one}");
    assert!(one.contains("rest on the other 3 stretches"), "{one}");
    let two = super::super::warnings::IdentWarning::StretchesWithoutDelay {
        spans_s: vec![[0.0, 30.0], [60.0, 90.0]],
        fitted: 4,
    }
    .to_string();
    assert!(
        two.contains("2 stretches of the record (0.0-30.0 s, 60.0-90.0 s)"),
        "{two}"
    );
}
