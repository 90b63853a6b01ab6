//! A finding's size in the lab's words and units, for people (the app, the command line's
//! summary): the report's `parameters` (contract section 5) read back and formatted, never JSON.

use serde_json::Value;

use super::report::Finding;
use super::structure::{LAG_DAMPING, LagShape, lag_damping_held};
use crate::effect::Effect;
use crate::ident::signals::channel_names;
use crate::model::band_limit::BandLimitShape;

/// Reads a number.
fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

/// Reads three numbers.
fn three(v: &Value) -> Option<[f64; 3]> {
    let a = v.as_array()?;
    Some([num(a.first()?)?, num(a.get(1)?)?, num(a.get(2)?)?])
}

/// ` ± 0.05` (the standard deviation, scaled), or nothing when it is unknown.
fn pm(sd: Option<f64>, scale: f64, decimals: usize) -> String {
    sd.filter(|v| v.is_finite())
        .map_or_else(String::new, |v| format!(" ± {:.decimals$}", v * scale))
}

/// A second-order lag's words: its -3 dB corner, natural frequency and damping (no frequencies
/// at `T = 0`); the caller gives `T`.
fn second_order_words(p: &Value, sd1: &dyn Fn(&str) -> Option<f64>) -> String {
    let zeta = p.get("damping").and_then(num).unwrap_or(f64::NAN);
    let frequencies = match (
        p.get("corner_hz").and_then(num),
        p.get("natural_frequency_hz").and_then(num),
    ) {
        (Some(corner), Some(natural)) => format!(
            ", -3 dB at {corner:.2}{} Hz (natural frequency {natural:.2}{} Hz)",
            pm(sd1("corner_hz"), 1.0, 2),
            pm(sd1("natural_frequency_hz"), 1.0, 2)
        ),
        _ => String::new(),
    };
    // Held at a bound of the range searched (a refit of an accepted lag on another band or
    // record can end there): the damping is the range's, not the data's.
    let held = if zeta.is_finite() && lag_damping_held(zeta) {
        format!(
            " (at a bound of the damping searched, {} to {}: not determined by the data; below, a \
             mount resonance, above, a first-order lag and a little delay may describe it better)",
            LAG_DAMPING[0], LAG_DAMPING[1]
        )
    } else {
        String::new()
    };
    format!(
        "second-order low-pass{frequencies}, damping {zeta:.3}{}{held}",
        pm(sd1("damping"), 1.0, 3)
    )
}

/// Three standard deviations, each possibly unknown.
fn three_std(v: Option<&Value>) -> [Option<f64>; 3] {
    let a = v.and_then(Value::as_array);
    [0, 1, 2].map(|i| a.and_then(|a| a.get(i)).and_then(num))
}

/// `gx +1.20 ± 0.05, gy -0.80 ± 0.05, gz +0.00 ± 0.05` with `scale` and `decimals`.
fn per_channel(names: [&str; 3], v: [f64; 3], sd: [Option<f64>; 3], scale: f64, decimals: usize) -> String {
    names
        .iter()
        .zip(v)
        .zip(sd)
        .map(|((n, x), sd)| format!("{n} {:+.decimals$}{}", x * scale, pm(sd, scale, decimals)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// When a tone is on, in words (nothing when on throughout or unknown).
fn when_on(p: &Value) -> Option<String> {
    let fraction = p.get("on_fraction").and_then(num)?;
    let stretches: Vec<[f64; 2]> = p
        .get("on_s")?
        .as_array()?
        .iter()
        .filter_map(|s| Some([num(s.get(0)?)?, num(s.get(1)?)?]))
        .collect();
    if fraction >= 1.0 || stretches.is_empty() {
        return None;
    }
    let shown: Vec<String> = stretches
        .iter()
        .take(4)
        .map(|[a, b]| format!("{a:.1}-{b:.1} s"))
        .collect();
    let more = stretches.len().saturating_sub(4);
    Some(format!(
        "on {:.0} % of the record, in {} stretch{}: {}{}",
        100.0 * fraction,
        stretches.len(),
        if stretches.len() == 1 { "" } else { "es" },
        shown.join(", "),
        if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        }
    ))
}

/// The finding's size as lines of text with units (empty when the parameters cannot be read).
#[must_use]
pub fn describe(f: &Finding) -> Vec<String> {
    describe_size(f.block, f.effect, &f.parameters, &f.parameter_std)
}

/// An effect's size (`parameters`, with `parameter_std` under the same keys) as lines of text
/// with units: a finding's, or an effect accepted into a model.
#[must_use]
pub fn describe_size(block: crate::block::Block, effect: Effect, p: &Value, std: &Value) -> Vec<String> {
    let sd = |key: &str| std.get(key);
    let sd1 = |key: &str| sd(key).and_then(num);
    let (inputs, outputs) = channel_names(block);
    let unit = match block {
        crate::block::Block::Gyro => "rad/s",
        crate::block::Block::Accel => "m/s²",
    };
    let lines = match effect {
        Effect::GSensitivity => p.get("G").and_then(Value::as_array).map(|rows| {
            let mut out = vec![format!("G, {unit} per m/s² (rows: outputs; columns: fx fy fz):")];
            for (name, row) in outputs.iter().zip(rows) {
                if let Some([a, b, c]) = three(row) {
                    out.push(format!("  {name}: {a:+.3e} {b:+.3e} {c:+.3e}"));
                }
            }
            out
        }),
        Effect::SensorLag => p.get("T_s").and_then(num).map(|t| {
            if LagShape::of_parameters(p) == LagShape::SecondOrder {
                vec![format!(
                    "{}, T = {:.3}{} ms",
                    second_order_words(p, &sd1),
                    t * 1e3,
                    pm(sd1("T_s"), 1e3, 3)
                )]
            } else {
                vec![format!(
                    "first-order lag, time constant T = {:.3}{} ms",
                    t * 1e3,
                    pm(sd1("T_s"), 1e3, 3)
                )]
            }
        }),
        Effect::ReferenceLag => p.get("T_s").and_then(num).map(|t| {
            let form = if LagShape::of_parameters(p) == LagShape::SecondOrder {
                format!(" ({})", second_order_words(p, &sd1))
            } else {
                String::new()
            };
            vec![format!(
                "the angle measurement lags: T = {:.3}{} ms{form}, the same on both blocks (the stand's band limit or latency, or one filter both sensor blocks share: this run cannot tell them apart)",
                t * 1e3,
                pm(sd1("T_s"), 1e3, 3)
            )]
        }),
        Effect::ReferenceBandLimit => band_limit_size(p, &sd1).map(|mut lines| {
            // Its deviation given, and `null`: held at a bound or unseen by the band.
            if sd("T_s").is_some_and(Value::is_null) {
                lines.push(
                    "the band does not determine it (at its bound, or its corner so far above the \
                     band that the data do not see it): its size has no deviation, and the \
                     model's others are those given it"
                        .to_owned(),
                );
            }
            lines
        }),
        Effect::AxisTimeSkew => p.get("skew_s").and_then(three).map(|s| {
            vec![format!(
                "channel delays relative to their mean, ms: {}",
                per_channel(outputs, s, three_std(sd("skew_s")), 1e3, 3)
            )]
        }),
        Effect::ScaleNonlinearity => p.get("k2").and_then(three).map(|k| {
            vec![format!(
                "quadratic scale factor k2 (x += k2 u|u|), per {unit}: {}",
                per_channel(outputs, k, three_std(sd("k2")), 1.0, 5)
            )]
        }),
        Effect::VibrationTone => {
            let fr = p.get("frequency_hz").and_then(num);
            let a = p.get("amplitude").and_then(three);
            fr.zip(a).map(|(fr, a)| {
                let mut lines = vec![format!(
                    "tone at {fr:.3}{} Hz; amplitude, {unit}: {}",
                    pm(sd1("frequency_hz"), 1.0, 3),
                    per_channel(outputs, a, three_std(sd("amplitude")), 1.0, 6)
                )];
                lines.extend(when_on(p));
                lines
            })
        }
        Effect::LeverArmError => p.get("offset_m").and_then(three).map(|o| {
            vec![format!(
                "lever arm off by (true minus declared), cm: {}",
                per_channel(["x", "y", "z"], o, three_std(sd("offset_m")), 100.0, 2)
            )]
        }),
        Effect::PlatformResonance => {
            let axis = p.get("axis_index").and_then(Value::as_u64).map(|a| a as usize);
            let fr = p.get("frequency_hz").and_then(num);
            let z = p.get("damping").and_then(num);
            match (axis, fr, z) {
                (Some(a), Some(fr), Some(z)) if a < 3 => Some(vec![format!(
                    "mount resonance on input {}: {fr:.2}{} Hz, damping ratio {z:.3}{}",
                    inputs[a],
                    pm(sd1("frequency_hz"), 1.0, 2),
                    pm(sd1("damping"), 1.0, 3)
                )]),
                _ => None,
            }
        }
        Effect::ClockDrift => {
            let d = p.get("drift_ppm").and_then(num);
            let c = p.get("delay_change_s").and_then(num);
            d.zip(c).map(|(d, c)| {
                vec![format!(
                    "block clock {} by {:.1} ppm: the delay changes by {:+.2} ms over the record",
                    if d >= 0.0 { "fast" } else { "slow" },
                    d.abs(),
                    c * 1e3
                )]
            })
        }
    };
    lines.unwrap_or_default()
}

/// Below this share of the misfit's power a finding is called small in its evidence.
pub const SMALL_SHARE: f64 = 0.01;

/// What a finding closes of the block's misfit, in words: the share of the misfit's power (all
/// channels) it removes, from the total gaps before and after it (dB), and, below
/// [`SMALL_SHARE`], that it is small: significant by its chi-square, yet most of the misfit is
/// something else (on real runs often the reference's part: the Bode tab's disturbance PSD).
#[must_use]
pub fn misfit_closed(before_total_db: f64, after_total_db: f64) -> String {
    let share = 1.0 - 10f64.powf((after_total_db - before_total_db) / 10.0);
    let percent = 100.0 * share;
    if share < SMALL_SHARE {
        format!(
            "it removes {percent:.3} % of the misfit's power: significant but small, most of the misfit \
             is something else"
        )
    } else {
        format!("it removes {percent:.1} % of the misfit's power")
    }
}

/// The parameters that are an effect's size (zero: no effect); empty for effects whose
/// parameters locate rather than size it (a tone's or resonance's frequency).
pub(crate) fn size_keys(effect: Effect) -> &'static [&'static str] {
    match effect {
        Effect::ScaleNonlinearity => &["k2"],
        Effect::LeverArmError => &["offset_m"],
        Effect::GSensitivity => &["G"],
        // The band limit's T (0: none), not its rise, which depends on the band's top (the
        // usable band's refit and another run's band end elsewhere).
        Effect::SensorLag | Effect::ReferenceLag | Effect::ReferenceBandLimit => &["T_s"],
        Effect::AxisTimeSkew => &["skew_s"],
        _ => &[],
    }
}

/// Whether every component of a finding's size lies within two of its standard deviations of
/// zero (all of them known): the chi-square shows a misfit of the effect's form, but its size is
/// not determined (on a real run, a misfit that piles up where the effect's regressors live
/// widens their standard deviations: `uncertainty`'s sandwich).
#[must_use]
pub fn size_within_noise(f: &Finding) -> bool {
    // The size figures as the comparisons read them (`compare::findings::figures`).
    let figures = crate::compare::findings::figures(f);
    !size_keys(f.effect).is_empty()
        && !figures.is_empty()
        && figures
            .iter()
            .all(|(_, v, sd)| sd.is_some_and(|sd| v.abs() <= 2.0 * sd))
}

/// Said in a finding's evidence when [`size_within_noise`].
pub const SIZE_WITHIN_NOISE: &str = "its size is within two standard deviations of zero in every component: \
     the data show a misfit of this form, not a size to certify";

/// A band limit's size in words ([`Effect::ReferenceBandLimit`]): the rise at the band's top and
/// the low-pass it comes from (a Butterworth's order and corner, or the interpolated reference's
/// rate); `None` where a figure is missing.
fn band_limit_size(p: &Value, sd1: &dyn Fn(&str) -> Option<f64>) -> Option<Vec<String>> {
    let rise = p.get("gain_rise_at_band_top").and_then(num);
    let top = p.get("band_top_hz").and_then(num);
    let corner = p.get("corner_hz").and_then(num);
    let shape = BandLimitShape::from_parameters(p)?;
    let causal = shape.causal();
    let rate = p.get("reference_rate_hz").and_then(num);
    let (Some(rise), Some(top), Some(corner)) = (rise, top, corner) else {
        return None;
    };
    let through = match (shape.order(), rate) {
        (Some(m), _) => format!(
            "through a {} order-{m} low-pass at {corner:.1}{} Hz",
            if causal { "causal" } else { "zero-phase" },
            pm(sd1("corner_hz"), 1.0, 1)
        ),
        (None, Some(rate)) => format!(
            "sampled at {rate:.1}{} Hz and interpolated linearly (sinc^2, corner {corner:.1} Hz; a \
             motion-capture reference resampled)",
            pm(sd1("reference_rate_hz"), 1.0, 1)
        ),
        (None, None) => return None,
    };
    let mut lines = vec![format!(
        "the outputs rise over the inputs by {:.2}{} % at {top:.1} Hz: the angle measurement \
         {through} (the inputs computed from it fall short of the motion; the stand's, not the \
         sensor's)",
        100.0 * rise,
        pm(sd1("gain_rise_at_band_top"), 100.0, 2),
    )];
    if causal && corner > 0.0 {
        lines.push(format!(
            "the angles lag the motion by its group delay, {:.3} ms: the block's delay with it is \
             against the motion, that much later than against the angles",
            1e3 * std::f64::consts::SQRT_2 / (std::f64::consts::TAU * corner)
        ));
    }
    Some(lines)
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::block::Block;

    fn finding(block: Block, effect: Effect, parameters: Value) -> Finding {
        Finding::sized(block, effect, parameters, Value::Null)
    }

    #[test]
    fn a_band_limit_is_said_in_its_own_shape() {
        let interpolated = json!({
            "T_s": 1.0 / 120.0, "shape": "interpolated", "causal": false, "band_top_hz": 38.0,
            "gain_rise_at_band_top": 0.398, "corner_hz": 38.27, "reference_rate_hz": 120.0
        });
        let sd = json!({"T_s": 3e-5, "corner_hz": 0.14, "reference_rate_hz": 0.43, "gain_rise_at_band_top": 0.004});
        let lines = describe_size(Block::Gyro, Effect::ReferenceBandLimit, &interpolated, &sd);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(
            lines[0].contains("by 39.80 ± 0.40 % at 38.0 Hz")
                && lines[0]
                    .contains("sampled at 120.0 ± 0.4 Hz and interpolated linearly (sinc^2, corner 38.3 Hz"),
            "{lines:?}"
        );
        let causal = json!({
            "T_s": 0.004, "shape": "causal2", "order": 2, "causal": true, "band_top_hz": 38.0,
            "gain_rise_at_band_top": 0.33, "corner_hz": 39.79
        });
        let lines = describe_size(Block::Gyro, Effect::ReferenceBandLimit, &causal, &Value::Null);
        assert!(
            lines[0].contains("through a causal order-2 low-pass at 39.8 Hz"),
            "{lines:?}"
        );
        // The group delay sqrt(2) / (2 pi 39.79 Hz) = 5.657 ms.
        assert!(lines[1].contains("group delay, 5.657 ms"), "{lines:?}");
        // A report written before findings named their shape: read from `causal` and `order`.
        let mut old = causal.clone();
        old.as_object_mut().expect("object").remove("shape");
        let lines = describe_size(Block::Gyro, Effect::ReferenceBandLimit, &old, &Value::Null);
        assert!(
            lines[0].contains("through a causal order-2 low-pass at 39.8 Hz"),
            "{lines:?}"
        );
        // Its deviation given as `null` (held at its bound, or unseen by the band): said; not
        // where no deviations are given at all (above).
        let unseen = json!({
            "T_s": 6.7e-4, "shape": "zero_phase", "order": 8, "causal": false, "band_top_hz": 33.9,
            "gain_rise_at_band_top": 1.4e-14, "corner_hz": 238.1
        });
        let held = json!({"T_s": null, "corner_hz": null, "gain_rise_at_band_top": null});
        let lines = describe_size(Block::Accel, Effect::ReferenceBandLimit, &unseen, &held);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].contains("by 0.00 % at 33.9 Hz") && lines[1].contains("does not determine it"),
            "{lines:?}"
        );
        let lines = describe_size(Block::Accel, Effect::ReferenceBandLimit, &unseen, &Value::Null);
        assert_eq!(lines.len(), 1, "{lines:?}");
        // Neither an order nor a rate: no words.
        let neither = json!({"T_s": 0.004, "causal": false, "band_top_hz": 38.0, "gain_rise_at_band_top": 0.1, "corner_hz": 39.8});
        let lines = describe_size(Block::Gyro, Effect::ReferenceBandLimit, &neither, &Value::Null);
        assert!(lines.iter().all(|l| !l.contains("low-pass")), "{lines:?}");
    }

    #[test]
    fn size_within_noise_needs_every_component_inside_two_sd() {
        let mut f = finding(
            Block::Gyro,
            Effect::ScaleNonlinearity,
            json!({"k2": [0.014, -0.001, 0.045]}),
        );
        f.parameter_std = json!({"k2": [0.0088, 0.0038, 0.045]});
        assert!(size_within_noise(&f));
        f.parameter_std = json!({"k2": [0.0088, 0.0038, 0.012]});
        assert!(!size_within_noise(&f), "z is 3.7 sd from zero");
        f.parameter_std = json!({"k2": [0.0088, null, 0.045]});
        assert!(!size_within_noise(&f), "an unknown sd says nothing");
        let mut g = finding(
            Block::Accel,
            Effect::GSensitivity,
            json!({"G": [[1e-4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]}),
        );
        g.parameter_std = json!({"G": [[1e-4, 1e-5, 1e-5], [1e-5, 1e-5, 1e-5], [1e-5, 1e-5, 1e-5]]});
        assert!(size_within_noise(&g));
        g.parameters = json!({"G": [[3e-4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]});
        assert!(!size_within_noise(&g));
        let mut tone = finding(Block::Gyro, Effect::VibrationTone, json!({"frequency_hz": 0.1}));
        tone.parameter_std = json!({"frequency_hz": 1.0});
        assert!(
            !size_within_noise(&tone),
            "a tone's frequency locates it, it does not size it"
        );
    }

    #[test]
    fn sizes_read_with_units() {
        let f = finding(Block::Gyro, Effect::SensorLag, json!({"T_s": 0.004_02}));
        assert_eq!(describe(&f), vec!["first-order lag, time constant T = 4.020 ms"]);
        // A second order: its corner, natural frequency and damping, `T` once; the shared
        // lag's words carry the same in brackets; no frequencies at `T = 0`.
        let second = json!({"T_s": 0.007_958, "damping": 0.72, "natural_frequency_hz": 20.0,
            "corner_hz": 20.0, "shape": "second_order"});
        let f = finding(Block::Gyro, Effect::SensorLag, second.clone());
        assert_eq!(
            describe(&f),
            vec![
                "second-order low-pass, -3 dB at 20.00 Hz (natural frequency 20.00 Hz), damping 0.720, T = 7.958 ms"
            ]
        );
        let f = finding(Block::Gyro, Effect::ReferenceLag, second);
        let words = describe(&f).join(" ");
        assert_eq!(words.matches("T = ").count(), 1, "{words}");
        assert!(
            words.contains("(second-order low-pass, -3 dB at 20.00 Hz"),
            "{words}"
        );
        let f = finding(
            Block::Gyro,
            Effect::SensorLag,
            json!({"T_s": 0.0, "damping": 0.72, "shape": "second_order"}),
        );
        assert_eq!(
            describe(&f),
            vec!["second-order low-pass, damping 0.720, T = 0.000 ms"]
        );
        // A damping held at a bound of the range searched is said not determined.
        for zeta in [0.5, 4.0] {
            let f = finding(
                Block::Gyro,
                Effect::SensorLag,
                json!({"T_s": 0.002, "damping": zeta, "shape": "second_order"}),
            );
            let words = describe(&f).join(" ");
            assert!(
                words.contains("at a bound of the damping searched, 0.5 to 4: not determined"),
                "{words}"
            );
        }
        let f = finding(
            Block::Accel,
            Effect::ClockDrift,
            json!({"drift_ppm": -19.9, "delay_change_s": -0.005_97}),
        );
        assert_eq!(
            describe(&f),
            vec!["block clock slow by 19.9 ppm: the delay changes by -5.97 ms over the record"]
        );
        let f = finding(
            Block::Accel,
            Effect::LeverArmError,
            json!({"offset_m": [0.02, -0.015, 0.0301]}),
        );
        assert_eq!(
            describe(&f),
            vec!["lever arm off by (true minus declared), cm: x +2.00, y -1.50, z +3.01"]
        );
        let f = finding(
            Block::Gyro,
            Effect::PlatformResonance,
            json!({"axis": "wy", "axis_index": 1, "frequency_hz": 24.13, "damping": 0.051}),
        );
        assert_eq!(
            describe(&f),
            vec!["mount resonance on input wy: 24.13 Hz, damping ratio 0.051"]
        );
    }

    #[test]
    fn sizes_carry_their_standard_deviations_where_known() {
        let mut f = finding(Block::Gyro, Effect::SensorLag, json!({"T_s": 0.004_02}));
        f.parameter_std = json!({"T_s": 0.000_031});
        assert_eq!(
            describe(&f),
            vec!["first-order lag, time constant T = 4.020 ± 0.031 ms"]
        );
        let mut f = finding(
            Block::Accel,
            Effect::ScaleNonlinearity,
            json!({"k2": [0.001, -0.002, 0.0]}),
        );
        f.parameter_std = json!({"k2": [0.000_2, null, 0.000_1]});
        assert_eq!(
            describe(&f),
            vec![
                "quadratic scale factor k2 (x += k2 u|u|), per m/s²: ax +0.00100 ± 0.00020, ay -0.00200, az +0.00000 ± 0.00010"
            ]
        );
    }

    #[test]
    fn a_tone_says_when_it_is_on() {
        let f = finding(
            Block::Gyro,
            Effect::VibrationTone,
            json!({"frequency_hz": 43.5, "amplitude": [0.001, 0.002, 0.0], "on_fraction": 0.4,
                   "on_s": [[0.0, 2.0], [5.0, 7.0], [10.0, 12.0], [15.0, 17.0], [20.0, 22.0]]}),
        );
        assert_eq!(
            describe(&f)[1],
            "on 40 % of the record, in 5 stretches: 0.0-2.0 s, 5.0-7.0 s, 10.0-12.0 s, 15.0-17.0 s and 1 more"
        );
        let f = finding(
            Block::Gyro,
            Effect::VibrationTone,
            json!({"frequency_hz": 43.5, "amplitude": [0.001, 0.002, 0.0], "on_fraction": 1.0, "on_s": [[0.0, 60.0]]}),
        );
        assert_eq!(describe(&f).len(), 1, "on throughout: nothing more to say");
    }

    #[test]
    fn unreadable_parameters_give_no_line() {
        let f = finding(Block::Gyro, Effect::SensorLag, json!({"T": "x"}));
        assert!(describe(&f).is_empty());
        let f = finding(Block::Gyro, Effect::VibrationTone, Value::Null);
        assert!(describe(&f).is_empty());
    }

    #[test]
    fn the_share_of_the_misfit_closed_is_said_in_percent() {
        // Half the power: 3.0103 dB.
        let half = super::misfit_closed(-10.0, -10.0 - 10.0 * 2f64.log10());
        assert_eq!(half, "it removes 50.0 % of the misfit's power");
        // 0.0004 dB: 0.0092 %, small.
        let tiny = super::misfit_closed(-13.235, -13.2354);
        assert!(
            tiny.starts_with("it removes 0.009 % of the misfit's power: significant but small"),
            "{tiny}"
        );
        assert!(!super::misfit_closed(-20.0, -20.1).contains("small"));
    }
}
