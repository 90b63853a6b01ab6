//! The sentences of the longer identification warnings ([`super::warnings::IdentWarning`]'s
//! `Display`), one function per warning: sizes in the units a reader checks (ms, %, rad).

use std::fmt;

/// A relative size in words: percent to two decimals from 0.01 %, parts per million below.
fn relative(x: f64) -> String {
    if x.abs() >= 1e-4 {
        format!("{:.2} %", x * 100.0)
    } else {
        format!("{:.0} ppm", x * 1e6)
    }
}

/// The words of [`super::warnings::IdentWarning::GainDependsOnAmplitude`].
pub(super) fn gain_depends_on_amplitude_words(
    f: &mut fmt::Formatter<'_>,
    outputs: &[super::odd_gain::OddOutput],
    band_hz: [f64; 2],
) -> fmt::Result {
    let each: Vec<String> = outputs
        .iter()
        .map(|o| {
            format!(
                "{} (k2 {:.2e} +- {:.1e}, K's diagonal {} {} its small-motion value, K's deviation {})",
                o.output,
                o.k2,
                o.k2_std,
                relative(o.gain_shift.abs()),
                if o.gain_shift >= 0.0 {
                    "larger than"
                } else {
                    "smaller than"
                },
                relative(o.k_relative_std)
            )
        })
        .collect();
    write!(
        f,
        "the gain depends on the motion's amplitude: over {:.2}-{:.1} Hz the output holds a part \
         odd-quadratic in its own input (k2 u|u|) that no linear model carries, so K is the gain \
         at this run's motion and a run with other motion reads another: {}; a quadratic scale \
         factor reads so (`discrepancy` sizes it as scale_nonlinearity, `identify --effects` fits \
         it beside K), and so may an output that clips or saturates",
        band_hz[0],
        band_hz[1],
        each.join("; ")
    )
}

/// The words of [`super::warnings::IdentWarning::GainChangesAcrossBand`].
pub(super) fn gain_change_words(w: &super::warnings::IdentWarning) -> String {
    let super::warnings::IdentWarning::GainChangesAcrossBand {
        rise,
        rise_std,
        k_bias,
        outputs,
        k_relative_std,
        rows_moved: _,
        largest_change: largest,
        band_hz,
        k_at_low_frequency,
    } = w
    else {
        return String::new();
    };
    let (rise, rise_std, k_relative_std, band_hz) = (*rise, *rise_std, *k_relative_std, *band_hz);
    // Against K's relative deviation, and the element moved furthest against its own (model
    // files written before the element was said have none: the relative deviation alone).
    let deviation = if largest.output.is_empty() {
        format!("more than K's deviation ({})", relative(k_relative_std))
    } else {
        format!(
            "K's relative deviation {}; K[{}][{}] moves by {:.1} of its own deviation",
            relative(k_relative_std),
            largest.output,
            largest.input,
            largest.sigmas
        )
    };
    let rows: Vec<String> = k_bias
        .iter()
        .zip(outputs)
        .map(|(b, name)| {
            format!(
                "{}{} ({name})",
                if *b >= 0.0 { "+" } else { "-" },
                relative(b.abs())
            )
        })
        .collect();
    let what = if *k_at_low_frequency {
        format!(
            "the delay-only fit's K, the band's mean gain, read its rows about {} off the gain at \
             low frequency ({deviation}): the block is fitted again over the even \
             gain, K is given at low frequency (its deviations not below the delay-only fit's) and \
             the model carries the change; a lower band top lessens it",
            rows.join(", "),
        )
    } else {
        format!(
            "K is the band's mean gain, and its rows read about {} off the gain at low \
             frequency ({deviation}): a lower band top lessens it",
            rows.join(", "),
        )
    };
    // A rise may be the stand's low-pass, which the diagnosis models in its own shape (the even
    // gain's two terms only approximate it: on 38 simulated reference-limited runs K was up to
    // 2 % off here and within 0.33 % with the band limit accepted).
    let remedy = if rise > 0.0 {
        "; the diagnosis (`discrepancy`, the app's Missing effects) tells whether it is the \
         stand's band limit (`reference_band_limit`, with its shape and corner or reference rate), \
         and accepted (`identify --effects`, Accept), K and the delay are fitted behind it"
    } else {
        ""
    };
    format!(
        "the gain {} by {} (+- {}) from {:.2} to {:.1} Hz with no phase of its own: the \
         reference's band limit (angles interpolated from a slower rate, e.g. a motion-capture \
         system's, or smoothed), a filter in the block, or inputs the angle-noise model shrank; \
         {what}{remedy}",
        if rise >= 0.0 { "rises" } else { "falls" },
        relative(rise.abs()),
        relative(rise_std),
        band_hz[0],
        band_hz[1],
    )
}

/// [`super::warnings::IdentWarning::StretchesWithoutDelay`]'s sentence.
pub(super) fn write_stretches_without_delay(
    f: &mut fmt::Formatter<'_>,
    spans_s: &[[f64; 2]],
    fitted: usize,
) -> fmt::Result {
    let spans: Vec<String> = spans_s.iter().map(|[a, b]| format!("{a:.1}-{b:.1} s")).collect();
    let which = if spans.len() == 1 {
        "a stretch".to_owned()
    } else {
        format!("{} stretches", spans.len())
    };
    write!(
        f,
        "no delay fits {which} of the record ({}) within the stationarity check's reach \
         (+-{} s: the best is its end): there the block's response is not the record's (a \
         recording fault, a clock jump, motion folded about Nyquist); the stationarity check and \
         the deviations' floor rest on the other {fitted} stretches",
        spans.join(", "),
        super::stretches::STRETCH_DELAY_REACH_S
    )
}

/// The words of [`super::warnings::IdentWarning::DelayStep`].
pub(super) fn delay_step_words(f: &mut fmt::Formatter<'_>, w: &super::warnings::IdentWarning) -> fmt::Result {
    let &super::warnings::IdentWarning::DelayStep {
        before_s,
        after_s,
        between_s: [from, to],
        samples,
        samples_std,
        drift_fitted,
        back_between_s,
    } = w
    else {
        return Ok(());
    };
    let back = back_between_s.map_or_else(String::new, |[a, b]| {
        format!(
            " and back to {:.3} ms between {a:.1} and {b:.1} s",
            before_s * 1e3
        )
    });
    let cause = if super::delay_step::whole_samples(samples, samples_std) {
        let n = samples.round().abs();
        let which = if samples > 0.0 {
            "lost from the angles or repeated in the outputs"
        } else {
            "lost from the outputs or repeated in the angles"
        };
        let reverse = if back_between_s.is_some() {
            ", and the reverse where it comes back"
        } else {
            ""
        };
        format!(
            "{n:.0} whole sample{}: samples {which} (a logger's slip){reverse}, not a clock drift",
            if n > 1.0 { "s" } else { "" }
        )
    } else if super::delay_step::definite(samples_std) && drift_fitted {
        "a fraction of a sample: one stream re-timed (a timestamp correction, resampling), not a \
         clock drift"
            .to_owned()
    } else if super::delay_step::definite(samples_std) && back_between_s.is_some() {
        "a fraction of a sample: one stream re-timed (a timestamp correction, resampling) and \
         back, not a clock drift"
            .to_owned()
    } else if super::delay_step::definite(samples_std) {
        "a fraction of a sample: one stream re-timed (a timestamp correction, resampling), or a \
         slip beside a clock drift, which too few stretches cannot tell apart"
            .to_owned()
    } else {
        "its size cannot tell a slip of whole samples from a re-timing (one side rests on a single \
         stretch, which may hold the step itself), not a clock drift"
            .to_owned()
    };
    write!(
        f,
        "the delay steps from {:.3} ms to {:.3} ms between {from:.1} and {to:.1} s{back} (from the \
         first sample analysed): {:+.2} +- {:.2} sample periods, {cause}; the model's delay and gains mix the two \
         delays and describe neither: analyse a stretch on one of them alone (span_s, in the \
         run's own time column)",
        before_s * 1e3,
        after_s * 1e3,
        samples,
        samples_std
    )
}

/// The words of [`super::warnings::IdentWarning::ZerosLead`].
pub(super) fn zeros_lead_words(
    f: &mut fmt::Formatter<'_>,
    order: usize,
    lead_s: f64,
    lead_std_s: f64,
    tau_s: f64,
    pole_lag_s: f64,
) -> fmt::Result {
    write!(
        f,
        "the order-{order} model's zeros lead by {:.3} +- {:.3} ms at low frequency, and a \
         sensor's filters do not lead. Two causes fit: the stand's angles lag the motion by about \
         that much (a filter with phase in the angle measurement, not a zero-phase band limit), \
         and the model's delay and poles alone ({:.3} ms at low frequency) are then the block's; \
         or the delay and the zeros split the block's delay between them (a sensor filter without \
         zeros can give such a lead), and the delay beside the poles is then {:.3} ms, not the \
         fitted {:.3} ms. Either way the net delay at low frequency is {:.3} ms; check the angle \
         sensors' filters and latency",
        lead_s * 1e3,
        lead_std_s * 1e3,
        (tau_s + pole_lag_s) * 1e3,
        (tau_s - lead_s) * 1e3,
        tau_s * 1e3,
        (tau_s + pole_lag_s - lead_s) * 1e3
    )
}

/// The words of [`super::warnings::IdentWarning::ZerosLag`].
pub(super) fn zeros_lag_words(f: &mut fmt::Formatter<'_>, w: &super::warnings::IdentWarning) -> fmt::Result {
    let &super::warnings::IdentWarning::ZerosLag {
        order,
        lag_s,
        lag_std_s,
        tau_s,
        tau_std_s,
        pole_lag_s,
    } = w
    else {
        return Ok(());
    };
    write!(
        f,
        "the order-{order} model's zeros lag by {:.3} +- {:.3} ms at low frequency: over the band \
         zeros that lag act as a delay, so the fitted delay ({:.3} +- {:.3} ms) and the zeros \
         split the delay beside the poles, {:.3} ms, between them, and the delay's deviation \
         does not cover the split; a filter without zeros (most sensors' anti-alias filters) has \
         all of it in its delay: quote {:.3} ms as the delay beside the poles, or the fitted delay \
         only if the block's filter is known to have zeros (net delay at low frequency, poles \
         included: {:.3} ms)",
        lag_s * 1e3,
        lag_std_s * 1e3,
        tau_s * 1e3,
        tau_std_s * 1e3,
        (tau_s + lag_s) * 1e3,
        (tau_s + lag_s) * 1e3,
        (tau_s + pole_lag_s + lag_s) * 1e3
    )
}

/// The words of [`super::warnings::IdentWarning::DelayAbsorbedByPoles`].
pub(super) fn delay_absorbed_words(
    f: &mut fmt::Formatter<'_>,
    order: usize,
    tau_s: f64,
    tau_std_s: f64,
    delay_only_tau_s: f64,
) -> fmt::Result {
    write!(
        f,
        "the order-{order} model's delay is negative ({:.3} +- {:.3} ms) where the delay-only model \
         gives {:.3} ms: its poles' lag stands in for the delay; this is the block's model only if \
         the stand's angles lag the block (angle latency), otherwise it fits the reference's own \
         response too: compare with order 0",
        tau_s * 1e3,
        tau_std_s * 1e3,
        delay_only_tau_s * 1e3
    )
}

/// The words of [`super::warnings::IdentWarning::PolesOrEvenGain`] (nothing for another warning).
pub(super) fn poles_or_even_gain_words(
    f: &mut fmt::Formatter<'_>,
    w: &super::warnings::IdentWarning,
) -> fmt::Result {
    let super::warnings::IdentWarning::PolesOrEvenGain {
        order,
        tau_s,
        tau_std_s,
        even_tau_s,
        even_tau_std_s,
        rise,
        band_hz,
        margin,
    } = *w
    else {
        return Ok(());
    };
    write!(
        f,
        "the gain {} by {} from {:.2} to {:.1} Hz, and the order-{order} model takes the change \
         for the block's dynamics: its delay is {:.3} ms (+- {:.3} ms), {}; the delay-only model \
         over an even gain (the reference's band limit: angles \
         interpolated from a slower rate, or smoothed) gives {:.3} ms (+- {:.3} ms) and explains \
         the data less well by {margin:.1} on the information criterion. A band-limited reference \
         and a filter in the block are told apart only by that margin: if the block has no filter \
         of its own, fix the order to 0 (K is then the gain at low frequency, the model carrying \
         the even gain)",
        if rise >= 0.0 { "rises" } else { "falls" },
        relative(rise.abs()),
        band_hz[0],
        band_hz[1],
        tau_s * 1e3,
        tau_std_s * 1e3,
        traded(tau_s, even_tau_s),
        even_tau_s * 1e3,
        even_tau_std_s * 1e3,
    )
}

/// How a model's delay `tau_s` stands to another model's `other_s` of the same data: earlier,
/// the poles' lag stands in for the rest; later, they lead by the difference.
fn traded(tau_s: f64, other_s: f64) -> String {
    if tau_s <= other_s {
        "its poles' lag standing in for the rest".to_owned()
    } else {
        format!(
            "{:.3} ms later, its poles leading by that much",
            (tau_s - other_s) * 1e3
        )
    }
}

/// The words of [`super::warnings::IdentWarning::DelayOutsideUsualRange`] (nothing for another
/// warning).
pub(super) fn delay_outside_words(
    f: &mut fmt::Formatter<'_>,
    w: &super::warnings::IdentWarning,
) -> fmt::Result {
    let super::warnings::IdentWarning::DelayOutsideUsualRange {
        tau_s,
        usual_s,
        reach_s,
        overlap_loss,
        wider_search,
        aligned_s,
        model_tau_s,
    } = *w
    else {
        return Ok(());
    };
    let ms = |s: f64| s * 1e3;
    // Whose delay: the model's, or the delay-only model's where the model's poles brought its
    // own back inside the range.
    let (whose, held) = match model_tau_s {
        Some(own) => (
            "the delay-only model's delay, ".to_owned(),
            format!(
                "which the delay-only model holds as the block's delay (the chosen model's is \
                 {:.3} ms, {})",
                ms(own),
                traded(own, tau_s)
            ),
        ),
        None => (
            "delay ".to_owned(),
            "which the model holds as the block's delay".to_owned(),
        ),
    };
    if !wider_search {
        return write!(
            f,
            "the model's delay, {:.3} ms, lies outside the {:.0} to {:.0} ms a sensor's own \
             delay is searched in, while the delay-only model's is inside it: the model's poles \
             trade with its delay; compare with order 0",
            ms(tau_s),
            ms(usual_s[0]),
            ms(usual_s[1])
        );
    }
    if tau_s.abs() >= reach_s - 1e-3 {
        write!(
            f,
            "{whose}{:.3} ms, at the end of the widest search (+-{:.0} ms): the true \
             delay may lie beyond it, and the model, K too, is not to be trusted; \
             align the angles and the outputs in time first",
            ms(tau_s),
            ms(reach_s)
        )?;
        if let Some(own) = model_tau_s {
            write!(f, " (the chosen model's is {:.3} ms)", ms(own))?;
        }
    } else {
        write!(
            f,
            "{whose}{:.3} ms, outside the {:.0} to {:.0} ms a sensor's own delay is \
             searched in (found by the search to +-{:.0} ms): most likely the angles \
             and the outputs are stamped by clocks offset from each other (a logging \
             or transport latency), {held}",
            ms(tau_s),
            ms(usual_s[0]),
            ms(usual_s[1]),
            ms(reach_s)
        )?;
        if aligned_s == 0.0 {
            write!(
                f,
                "; the Welch estimate smears a delay this long into a misfit a model with \
                 poles may fit: where a poor fit is said too, align the streams in time and \
                 identify again"
            )?;
        } else {
            write!(
                f,
                "; the outputs were moved by {:.3} ms against the angles before the spectra \
                 were estimated (whole samples), so the estimate is not smeared by it",
                ms(aligned_s)
            )?;
        }
    }
    if overlap_loss > super::warnings::OVERLAP_LOSS_SAID {
        write!(
            f,
            "; a delay this long lowers the measured gain by {:.2} % (the Welch \
             segments of the outputs and the angles overlap less): K reads low by \
             that much; align the streams, or take longer segments",
            overlap_loss * 100.0
        )?;
    }
    Ok(())
}

/// The words of [`super::warnings::IdentWarning::AngleNoiseOverstated`].
pub(super) fn angle_noise_overstated_words(
    f: &mut fmt::Formatter<'_>,
    declared_rad: f64,
    bound_rad: [f64; 3],
) -> fmt::Result {
    write!(
        f,
        "the sidecar's angle_noise_rad, {declared_rad:.1e} rad, is more than twice what the angles \
         hold inside the band: what the gyro leaves unexplained in them (their noise, the gyro's \
         own and any misfit), as a white level over most of the band's bins, is roll {:.1e}, yaw \
         {:.1e}, pitch {:.1e} rad per sample; the declared value is the floor of the \
         angle-noise model, and overstated it makes the observer smooth away motion it takes \
         for noise, biasing the gains where the motion is weak; correct it, or leave it out to \
         have it estimated (angles filtered or interpolated from a slower rate hold less noise \
         in the band than their per-sample value: leave it out for them too)",
        bound_rad[0], bound_rad[1], bound_rad[2],
    )
}

/// The words of [`super::warnings::IdentWarning::WitnessNoiseBias`]: its first-order `estimate`
/// for the input column `axis`. The multiples are measured (`super::witness_noise`): with a white
/// gyro noise the errors are now below the estimate (`tests/identify_accuracy.rs`); where the
/// gyro's bias drifts (`simulate --random-walk` 1.5e-2 to 3e-2, 1 Dec, seven runs) they were 7 to
/// 16 times it, a noise the white floor the estimate is capped by does not see.
pub(super) fn witness_noise_bias_words(
    f: &mut fmt::Formatter<'_>,
    estimate: f64,
    axis: usize,
) -> fmt::Result {
    write!(
        f,
        "the gyro's residual noise is not small beside this run's motion: the angle-noise \
         model cannot tell the gyro's own noise from the stand's, and as far as it is the \
         gyro's the gains read high, by about {:.2} % at first order (column {}), which the \
         standard deviations of K include; a gyro whose bias drifts (its noise growing toward \
         low frequency, beyond the floor this figure is measured by) reads further off: 7 to \
         16 times this figure on the simulated runs tried; move the stand more before \
         certifying the gains",
        estimate * 100.0,
        ["wx", "wy", "wz"].get(axis).copied().unwrap_or("?"),
    )
}

/// The words of [`super::warnings::IdentWarning::WitnessNoiseShared`], beside the gyro's
/// `gyro_estimate`.
pub(super) fn witness_noise_shared_words(f: &mut fmt::Formatter<'_>, gyro_estimate: f64) -> fmt::Result {
    write!(
        f,
        "this block's inputs come from the observer whose angle-noise model took part of the \
         gyro's own noise for the stand's (the gyro says witness_noise_bias, {:.2} % at first \
         order for its own gains, which does not size this block's): as far as it did, these \
         inputs were shrunk too and this block's gains are biased by an amount not in their \
         deviations (on simulated runs whose gyro bias drifts, an accelerometer's diagonal \
         gains 2.6 to 8 % off, 8 to 16 of their deviations, mostly high); move the stand more \
         before certifying this block's gains",
        gyro_estimate * 100.0
    )
}

/// The words of [`super::warnings::IdentWarning::AngleNoiseColourUnknown`].
pub(super) fn angle_noise_colour_unknown_words(
    f: &mut fmt::Formatter<'_>,
    angle_noise_rad: [f64; 3],
    declared: bool,
) -> fmt::Result {
    write!(
        f,
        "no sound gyro in this run to check the stand's angle noise against (none, or one with a \
         channel that never moves, holds samples or clips): it is taken as \
         white, roll {:.1e}, yaw {:.1e}, pitch {:.1e} rad per sample ({}); if the stand's angle \
         noise is coloured (an optical reference, an encoder's interpolation), this block's gains \
         are biased low where the motion is weak and poles may stand in for its delay: certify \
         with a sound gyro on the stand, or fix the order at 0 and compare",
        angle_noise_rad[0],
        angle_noise_rad[1],
        angle_noise_rad[2],
        if declared {
            "declared"
        } else {
            "estimated from the angles"
        }
    )
}

#[cfg(test)]
mod tests {
    use super::gain_change_words;
    use crate::ident::warnings::{ElementChange, IdentWarning};

    fn words(rise: f64, largest: &ElementChange) -> String {
        gain_change_words(&IdentWarning::GainChangesAcrossBand {
            rise,
            rise_std: 0.002,
            k_bias: [0.001, 0.002, 0.0],
            outputs: ["gx", "gy", "gz"].map(str::to_owned),
            k_relative_std: 0.0015,
            rows_moved: true,
            largest_change: largest.clone(),
            band_hz: [0.2, 40.0],
            k_at_low_frequency: true,
        })
    }

    #[test]
    fn a_rise_points_to_the_band_limit_and_a_fall_does_not() {
        let largest = ElementChange {
            output: "gy".to_owned(),
            input: "wy".to_owned(),
            sigmas: 3.66,
        };
        let rise = words(0.02, &largest);
        assert!(rise.contains("rises by 2.00 %"), "{rise}");
        assert!(
            rise.contains("K[gy][wy] moves by 3.7 of its own deviation"),
            "{rise}"
        );
        assert!(
            rise.contains("`reference_band_limit`") && rise.contains("fitted behind it"),
            "{rise}"
        );
        let fall = words(-0.02, &largest);
        assert!(
            fall.contains("falls by 2.00 %") && !fall.contains("reference_band_limit"),
            "{fall}"
        );
        // A model file written before the element was said: the relative deviation alone.
        let old = words(0.02, &ElementChange::default());
        assert!(
            old.contains("more than K's deviation (0.15 %)") && !old.contains("moves by"),
            "{old}"
        );
    }
}
