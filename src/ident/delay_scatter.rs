//! Stretches whose delays disagree beyond their own deviations, in a way neither a drift nor a
//! step describes ([`super::stretches`], [`super::delay_step`]): slips too small or too close
//! together to be placed one by one, a clock that wanders, a delay that changes with the motion.
//! The record's delay is then a mean over delays that differ, and its deviation is the stretches'
//! spread ([`super::stretches::widen`]), many times what the fit alone gives; that was said by
//! nothing. A test campaign found 120 s runs with a logger slip of one sample whose delay's
//! deviation grew seventy-fold, from 0.007 to 0.47 ms, with no word; now the widening is said.
//!
//! The test: `chi2 = sum ((tau_m - tau_w) / sd_m)^2` about the stretches' weighted mean; the
//! scatter is said when `chi2 / (M - 1)` is at least [`MIN_RATIO`], 25: the stretches' delays five
//! times as far from their mean, in rms, as their own deviations allow. Stretches that agree to
//! their deviations pass that by chance less than once in ten million records (2 degrees of
//! freedom: `P(chi2 > 50) = e^-25`; more make it rarer), so the ratio alone decides. The bar
//! is that high because the stretches' own deviations rest on the noise model and run two to
//! three times narrow on imperfect stands. Measured on a campaign of fault-free simulated runs
//! (coloured angle noise, reference band limits, latency, 60-600 s, 250-1000 Hz; about 120
//! blocks), `chi2 / (M - 1)` reached 4.8-9.9 on eight of them, with a constant delay; on runs
//! with one logger slip it was 670-15 000. A smaller spread is widened into the deviation
//! (honestly) and left to the stretch plot.
//!
//! Contract: delays and deviations in s; a stretch with a deviation that is not positive and
//! finite is left out of the test; fewer than three stretches left, no warning.

use std::fmt;

use super::stretches::Stationarity;
use super::warnings::IdentWarning;

/// Smallest `chi2 / (M - 1)` said: the stretches five times as far from their mean as their own
/// deviations allow (module docs: fault-free runs reach 10, a slip hundreds).
const MIN_RATIO: f64 = 25.0;
/// Fewest stretches the test is made on.
const MIN_STRETCHES: usize = 3;

/// The warning for `st`'s stretches when their delays disagree beyond their deviations and no
/// drift or step already says how (module docs); `None` otherwise.
#[must_use]
pub fn delay_scatter(st: &Stationarity) -> Option<IdentWarning> {
    if st.drifts() || st.delay_step.is_some() {
        return None;
    }
    let kept: Vec<(f64, f64)> = st
        .stretches
        .iter()
        .filter(|s| s.tau_s.is_finite() && s.tau_std_s.is_finite() && s.tau_std_s > 0.0)
        .map(|s| (s.tau_s, s.tau_std_s))
        .collect();
    if kept.len() < MIN_STRETCHES {
        return None;
    }
    let weight_sum: f64 = kept.iter().map(|(_, sd)| sd.powi(-2)).sum();
    let mean = kept.iter().map(|(t, sd)| t / (sd * sd)).sum::<f64>() / weight_sum;
    let chi2: f64 = kept.iter().map(|(t, sd)| ((t - mean) / sd).powi(2)).sum();
    let dof = (kept.len() - 1) as f64;
    if chi2 / dof < MIN_RATIO {
        return None;
    }
    let mut own: Vec<f64> = kept.iter().map(|(_, sd)| *sd).collect();
    own.sort_by(f64::total_cmp);
    let taus = kept.iter().map(|(t, _)| *t);
    Some(IdentWarning::DelayScatter {
        stretches: kept.len(),
        min_s: taus.clone().fold(f64::INFINITY, f64::min),
        max_s: taus.fold(f64::NEG_INFINITY, f64::max),
        own_std_s: own[own.len() / 2],
        chi2_per_dof: chi2 / dof,
        spread_std_s: st.tau_spread_std_s,
    })
}

/// The words of [`IdentWarning::DelayScatter`].
pub(super) fn delay_scatter_words(f: &mut fmt::Formatter<'_>, w: &IdentWarning) -> fmt::Result {
    let IdentWarning::DelayScatter {
        stretches,
        min_s,
        max_s,
        own_std_s,
        chi2_per_dof,
        spread_std_s,
    } = w
    else {
        return Ok(());
    };
    let own_of_record = own_std_s / (*stretches as f64).sqrt();
    write!(
        f,
        "the stretches' delays disagree beyond their own deviations: {:.3} to {:.3} ms over {} \
         stretches, each +- {:.3} ms (median), {:.0} times as far from their mean (rms) as those \
         deviations allow; either the delay moves through the record as neither a steady drift \
         nor a single step does (slips too small or too close together to place one by one, a \
         clock that wanders, a delay that changes with the motion), or the stretches' own \
         deviations are that much too narrow; the delay's deviation is widened to at least their \
         spread, {:.3} ms, about {:.0} times what their own deviations give: look at the \
         stretches' delays (the model's stationarity, the app's stretch plot) before quoting it",
        min_s * 1e3,
        max_s * 1e3,
        stretches,
        own_std_s * 1e3,
        chi2_per_dof.sqrt(),
        spread_std_s * 1e3,
        spread_std_s / own_of_record,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ident::stretches::StretchFit;

    fn stationarity(delays_ms: &[f64], sd_ms: f64) -> Stationarity {
        let stretches: Vec<StretchFit> = delays_ms
            .iter()
            .enumerate()
            .map(|(i, d)| StretchFit {
                span_s: [20.0 * i as f64, 20.0 * (i + 1) as f64],
                k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                tau_s: d * 1e-3,
                tau_std_s: sd_ms * 1e-3,
            })
            .collect();
        let m = stretches.len() as f64;
        let mean = stretches.iter().map(|s| s.tau_s).sum::<f64>() / m;
        let var = stretches.iter().map(|s| (s.tau_s - mean).powi(2)).sum::<f64>() / (m - 1.0);
        Stationarity {
            stretches,
            k_spread_std: [[0.0; 3]; 3],
            tau_spread_std_s: (var / m).sqrt(),
            segment_len: None,
            tau_trend: 0.0,
            tau_trend_std: 1.0,
            no_delay_s: Vec::new(),
            delay_step: None,
        }
    }

    #[test]
    fn delays_that_wander_are_said_and_delays_within_their_deviations_are_not() {
        // Up and down by a tenth of a millisecond, each +- 0.01 ms: no line, no step.
        let wander = stationarity(&[4.0, 4.12, 3.95, 4.1, 3.9, 4.08, 4.0], 0.01);
        let w = delay_scatter(&wander).expect("said");
        let IdentWarning::DelayScatter {
            stretches,
            min_s,
            max_s,
            chi2_per_dof,
            ..
        } = w
        else {
            panic!("{w:?}")
        };
        assert_eq!(stretches, 7);
        assert_eq!(
            (min_s.to_bits(), max_s.to_bits()),
            (3.9e-3_f64.to_bits(), 4.12e-3_f64.to_bits())
        );
        assert!(chi2_per_dof > 50.0, "{chi2_per_dof}");
        let words = w.to_string();
        assert!(words.contains("3.900 to 4.120 ms over 7 stretches"), "{words}");
        // The same scatter with deviations ten times wider is what they allow.
        assert!(delay_scatter(&stationarity(&[4.0, 4.12, 3.95, 4.1, 3.9, 4.08, 4.0], 0.1)).is_none());
        // Significant but not doubling the deviation (chi2/dof about 3 on 30 stretches): not said.
        let mild: Vec<f64> = (0..30)
            .map(|i| 4.0 + if i % 2 == 0 { 0.017 } else { -0.017 })
            .collect();
        assert!(delay_scatter(&stationarity(&mild, 0.01)).is_none());
        // Fewer than three stretches, or deviations that mean nothing: no test.
        assert!(delay_scatter(&stationarity(&[4.0, 5.0], 0.01)).is_none());
        assert!(delay_scatter(&stationarity(&[4.0, 5.0, 4.0, 5.0], 0.0)).is_none());
        assert!(delay_scatter(&stationarity(&[4.0, 5.0, 4.0, 5.0], f64::NAN)).is_none());
    }
}
