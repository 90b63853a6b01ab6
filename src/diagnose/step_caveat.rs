//! A finding that a step of the block's delay can make ([`crate::ident::delay_step`]: a slipped
//! or repeated sample, found by the identifier's stretches), said in its evidence. Over a record
//! whose delay is `tau_1` for a fraction `p` of it and `tau_2 = tau_1 + d` for the rest, the
//! block's response is the two averaged, `e^(-s tau_1) (p + (1 - p) e^(-s d))`: a delay between
//! them and a gain that falls as `1 - p (1 - p) (w d)^2 / 2`, which a first-order lag
//! `1 / (T s + 1)` matches with `T = d sqrt(p (1 - p))`, at most `d / 2`. A slip in one channel
//! alone moves that channel's delay by whole samples and the block's fitted delay by less: a
//! channel skew of up to a sample period or the step, whichever is larger. On simulated runs with one
//! slipped sample at 500 Hz (`d` = 2 ms, 180-300 s) the diagnosis named a gyro lag of 0.93-1.08
//! ms on 3 of 3 (a helper's campaign, 30 Nov), with nothing said of the step it had found.
//!
//! A clock drift named where the stretches are too few to test for a step
//! ([`TOO_FEW_FOR_A_STEP`]: the step test leaves out the stretch that holds a step and needs
//! [`crate::ident::delay_step::MIN_KEPT`] others) may be a slipped sample: a line fitted through
//! a step in the middle of a record changes by 1.5 times the step over it. A helper's campaign
//! named `clock_drift` on 5 of 5 runs of 60-120 s with one slipped sample, from four stretches
//! each (delays such as 2.82, 2.82, 3.58, 4.82 ms: two levels and the mixed stretch between); its
//! evidence now says so, with the stretches' delays (three stretches or more: the two halves a
//! short record falls back to tell nothing of levels).
//!
//! Units: s; the step's size in sample periods as [`DelayStep::samples`].

use crate::effect::Effect;
use crate::ident::delay_step::DelayStep;
use serde_json::Value;

/// Stretches at or below which a step cannot be tested (one left out for the step, fewer than
/// [`crate::ident::delay_step::MIN_KEPT`] kept).
pub const TOO_FEW_FOR_A_STEP: usize = crate::ident::delay_step::MIN_KEPT;

/// Fewest stretches whose delays can show two levels and a mixed one between.
const MIN_SHOWN: usize = 3;

/// The words to add to a clock drift's evidence where the stretches' delays `delays_s` were too
/// few to test for a step (`None` for another effect or no delays).
#[must_use]
pub fn untested_step_caveat(effect: Effect, delays_s: &[f64]) -> Option<String> {
    if effect != Effect::ClockDrift || delays_s.len() < MIN_SHOWN {
        return None;
    }
    let shown: Vec<String> = delays_s.iter().map(|d| format!("{:.2}", d * 1e3)).collect();
    Some(format!(
        "; the record has {} stretches, too few to test for a step of the delay reliably (the test leaves \
         out the stretch that holds a step; a slipped or repeated sample, which a drift fitted through it \
         reads as about 1.5 times the step over the record); their \
         delays, ms: {}: a drift if they change steadily, a slip if they hold two levels",
        delays_s.len(),
        shown.join(", ")
    ))
}

/// How much longer than `d / 2` a lag may be and still be said to be the step's (the fit's
/// scatter and the step's own deviation).
const LAG_MARGIN: f64 = 1.2;

/// The first-order lag's time constant whose gain droops as a lag's does at low frequency: `T`
/// for the first order; for the second order, whose droop is `(2 zeta^2 - 1) (w T)^2` against
/// the first order's `(w T)^2 / 2`, `T sqrt(4 zeta^2 - 2)`; `None` where it does not droop
/// (`zeta <= 1 / sqrt 2`: flat or rising, which no step makes, so it is never the step's).
fn lag_droop_time_s(parameters: &Value) -> Option<f64> {
    let t = parameters.get("T_s")?.as_f64()?;
    match parameters.get("damping") {
        None => Some(t),
        Some(z) => {
            let zeta = z.as_f64()?;
            // Rounding: a Butterworth's 1/sqrt(2) squared is 0.5 to within one unit.
            let square = 4.0 * zeta * zeta - 2.0;
            (square > 1e-12).then(|| t * square.sqrt())
        }
    }
}

/// The words to add to a finding of `effect` with `parameters` on a block whose delay steps as
/// `step` says; `None` where the finding cannot be the step's (another
/// effect, or a size beyond what the step makes).
#[must_use]
pub fn step_caveat(effect: Effect, parameters: &Value, step: &DelayStep) -> Option<String> {
    let d = (step.after_s - step.before_s).abs();
    if !(d.is_finite() && d > 0.0) {
        return None;
    }
    // A slip in one channel moves that channel's delay by whole samples and the block's fitted
    // delay by less: the skew is bounded by the sample period as well as by the block's step.
    let period = if step.samples.abs() > 0.0 {
        d / step.samples.abs()
    } else {
        d
    };
    let fits = match effect {
        Effect::SensorLag | Effect::ReferenceLag => lag_droop_time_s(parameters)? <= LAG_MARGIN * d / 2.0,
        Effect::AxisTimeSkew => parameters
            .get("skew_s")?
            .as_array()?
            .iter()
            .filter_map(Value::as_f64)
            .all(|s| s.abs() <= LAG_MARGIN * d.max(period)),
        _ => false,
    };
    let back = step.back_between_s.map_or_else(String::new, |[a, b]| {
        format!(" and back between {a:.0} and {b:.0} s")
    });
    fits.then(|| {
        format!(
            "; the block's delay steps by {:.2} sample periods ({:.3} ms) between {:.0} and {:.0} s of the record{back} \
             (a slipped or repeated sample): a record with two delays reads as their mean with a gain that falls \
             like a lag's of up to half the step, and a slip in one channel as a skew, so this finding may be the \
             step's, not the block's own (diagnose the stretch before or after it alone to tell)",
            step.samples.abs(),
            d * 1e3,
            step.between_s[0],
            step.between_s[1]
        )
    })
}

#[cfg(test)]
mod tests {
    use num_complex::Complex64;
    use serde_json::json;

    use super::*;

    fn step(d: f64) -> DelayStep {
        DelayStep {
            before_s: 4e-3,
            after_s: 4e-3 + d,
            between_s: [60.0, 110.0],
            samples: d * 500.0,
            samples_std: 0.01,
            trend: None,
            back_between_s: None,
        }
    }

    #[test]
    fn two_delays_averaged_droop_like_a_lag_of_at_most_half_the_step() {
        // |p + (1 - p) e^(-j w d)| against |1 / (1 + j w T)|, T = d sqrt(p (1 - p)), at low
        // frequency; the largest T, at p = 1/2, is d / 2.
        let d = 2e-3;
        for p in [0.2, 0.5, 0.7] {
            let t = d * f64::sqrt(p * (1.0 - p));
            assert!(t <= d / 2.0 + 1e-15);
            for f in [5.0, 10.0, 20.0] {
                let w = std::f64::consts::TAU * f;
                let mix = (p + (1.0 - p) * Complex64::new(0.0, -w * d).exp()).norm();
                let lag = 1.0 / (1.0 + (w * t).powi(2)).sqrt();
                assert!((mix - lag).abs() < 2e-4, "{p} {f}: {mix} vs {lag}");
            }
        }
    }

    #[test]
    fn a_lag_or_skew_the_step_can_make_is_said_and_no_other() {
        let s = step(2e-3);
        let said = step_caveat(Effect::SensorLag, &json!({"T_s": 1.0e-3}), &s).expect("said");
        assert!(
            said.contains("1.00 sample periods") && said.contains("between 60 and 110 s"),
            "{said}"
        );
        assert!(step_caveat(Effect::ReferenceLag, &json!({"T_s": 1.1e-3}), &s).is_some());
        // A 4 ms lag is more than two delays 2 ms apart make.
        assert!(step_caveat(Effect::SensorLag, &json!({"T_s": 4e-3}), &s).is_none());
        assert!(
            step_caveat(
                Effect::AxisTimeSkew,
                &json!({"skew_s": [1.5e-3, -1e-3, -0.5e-3]}),
                &s
            )
            .is_some()
        );
        assert!(step_caveat(Effect::AxisTimeSkew, &json!({"skew_s": [5e-3, -2e-3, -3e-3]}), &s).is_none());
        assert!(step_caveat(Effect::GSensitivity, &json!({"G": []}), &s).is_none());
        assert!(step_caveat(Effect::SensorLag, &json!({"T_s": 1e-3}), &step(0.0)).is_none());
        assert!(step_caveat(Effect::SensorLag, &json!({}), &s).is_none());
        // A second-order lag by its droop: 0.5 ms at damping 2 droops as a first-order 1.87 ms
        // does (beyond the step's 1.2 ms), 0.3 ms as 1.12 ms (within); a Butterworth's is flat.
        let second = |t: f64, zeta: f64| json!({"T_s": t, "damping": zeta, "shape": "second_order"});
        assert!(step_caveat(Effect::SensorLag, &second(0.5e-3, 2.0), &s).is_none());
        assert!(step_caveat(Effect::SensorLag, &second(0.3e-3, 2.0), &s).is_some());
        assert!(step_caveat(Effect::SensorLag, &second(0.1e-3, 0.5f64.sqrt()), &s).is_none());
        // An angle slip steps the delay down: said by its size; a slip that comes back, both places.
        let mut down = step(-2e-3);
        down.back_between_s = Some([150.0, 170.0]);
        let said = step_caveat(Effect::SensorLag, &json!({"T_s": 1.0e-3}), &down).expect("said");
        assert!(
            said.contains("by 1.00 sample periods (2.000 ms)") && said.contains("back between 150 and 170 s"),
            "{said}"
        );
        // A one-channel slip's skew of most of a sample beside a block step of a third of one.
        let third = DelayStep {
            samples: 0.33,
            after_s: 4e-3 + 0.66e-3,
            ..step(2e-3)
        };
        let skew = json!({"skew_s": [1.6e-3, -0.8e-3, -0.8e-3]});
        assert!(step_caveat(Effect::AxisTimeSkew, &skew, &third).is_some());
    }

    #[test]
    fn a_drift_from_too_few_stretches_says_a_slip_would_read_alike() {
        let delays = [2.82e-3, 2.82e-3, 3.59e-3, 4.82e-3];
        let said = untested_step_caveat(Effect::ClockDrift, &delays).expect("said");
        assert!(
            said.contains("4 stretches") && said.contains("2.82, 2.82, 3.59, 4.82"),
            "{said}"
        );
        assert!(untested_step_caveat(Effect::SensorLag, &delays).is_none());
        assert!(untested_step_caveat(Effect::ClockDrift, &[]).is_none());
        assert!(untested_step_caveat(Effect::ClockDrift, &delays[..2]).is_none());
    }

    #[test]
    fn a_line_through_a_middle_step_changes_by_one_and_a_half_steps() {
        // Least squares over t in [0, 1] of a unit step at 1/2: slope 1.5.
        let n = 10_000_usize;
        let t: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        let y: Vec<f64> = t.iter().map(|&t| if t < 0.5 { 0.0 } else { 1.0 }).collect();
        let (tm, ym) = (t.iter().sum::<f64>() / n as f64, y.iter().sum::<f64>() / n as f64);
        let sxy: f64 = t.iter().zip(&y).map(|(t, y)| (t - tm) * (y - ym)).sum();
        let sxx: f64 = t.iter().map(|t| (t - tm).powi(2)).sum();
        assert!((sxy / sxx - 1.5).abs() < 1e-3, "{}", sxy / sxx);
    }
}
