//! What [`super::warnings::IdentWarning::EffectSuspected`] carries and says: a catalogue effect
//! that the paper's model takes into `K` and the delay without a misfit, found by
//! `crate::diagnose::suspect` (the evidence, and how far `K` and the delay move once it is
//! fitted beside them).
//!
//! Units: chi2 in units of the expected disturbance, shifts in s and relative to `K`'s largest
//! element, deviations as counts. A figure without a deviation is `None` and left out of the
//! file (the model file holds no `null` outside `*_std` fields).

use std::fmt;

use serde::{Deserialize, Serialize};

use super::warnings::ElementChange;
use crate::effect::Effect;

/// A suspected effect's evidence and what it moves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Suspicion {
    /// The effect.
    pub effect: Effect,
    /// The `chi2` it removes.
    pub delta_chi2: f64,
    /// The `chi2` it must remove: BIC's `ln n` per parameter and the diagnosis's look-elsewhere
    /// cost (`crate::diagnose::suspect`).
    pub threshold: f64,
    /// The band tested (the model's), Hz.
    pub band_hz: [f64; 2],
    /// The rival it was fitted beside, one that gains more on its own (a lag, a mount
    /// resonance, the stand's band limit: `crate::diagnose::suspect`); `None`: beside the
    /// paper's model alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beside: Option<Effect>,
    /// How much later the delay comes out with the effect fitted than without, s: the paper's
    /// model (with `beside`) fitted on the whole record over the band, not the identified
    /// model itself (its delay and `K` are those of the same data over the same band, by
    /// another estimator).
    pub delay_shift_s: f64,
    /// How far the delay moves over the model's delay deviation (`None`: no deviation); for
    /// channel delays, the channel that moves furthest over a channel's deviation (sqrt(3)
    /// times the model's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay_shift_sigmas: Option<f64>,
    /// For channel delays: each output channel's delay with them fitted, less the delay
    /// without, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel_delays_s: Option<[f64; 3]>,
    /// The element of `K` that moves furthest against its own deviation (`None`: no deviations).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_shift: Option<ElementChange>,
    /// The largest move of an element of `K`, relative to the largest element of `K`.
    pub k_shift_relative: f64,
    /// Whether the run's angle noise was taken white for want of a sound gyro (the block also
    /// says `angle_noise_colour_unknown`) and the effect is one that inputs holding it may read
    /// as ([`input_noise_reads_as`]): a stand's coloured angle noise, taken as motion, enters
    /// the inputs where the motion is weak and lowers the gain there, and a fit across frequency
    /// reads that as a smooth effect too (on accelerometer-only runs of a real-like stand, a lever-arm error
    /// moving `K` by 5 %, the same runs with a gyro beside it clean). Left out of the file when
    /// false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub angle_noise_taken_white: bool,
}

/// What a smooth effect found with the angle noise taken white for want of a sound gyro may be
/// instead (`angle_noise_colour_unknown`): the stand's coloured angle noise, taken as motion,
/// enters the inputs where the motion is weak and lowers the measured gain there
/// (errors in variables), and a fit across frequency reads the gain's fall as the effect
/// (`crate::diagnose::white_angles` says it of the diagnosis's findings).
pub const WHITE_ANGLE_NOISE_READING: &str = "the stand's angle noise is taken white here (no sound gyro in \
     this run): a coloured one enters the inputs as motion where the motion is weak and lowers \
     the measured gain there, which a fit across frequency can take for this effect, so confirm \
     it with a sound gyro on the stand before correcting for it";

/// Whether a fit across frequency may read inputs that hold an angle noise taken white as
/// `effect`: the noise taken as motion lowers the measured gain where the motion is weak, with no
/// phase of its own (errors in variables). Measured to read so: a sensor's lag and a lever-arm
/// error (`crate::diagnose::white_angles`); included by caution: a mount resonance (its flank
/// above the peak) and a g-sensitivity (a cross-axis filter). Not an effect of phase alone
/// (channel delays, the angle measurement's lag), one that raises the gain (the angle
/// measurement's band limit), a line (a tone), a re-timing (a clock drift) or a part of the
/// outputs not linear in the inputs (a quadratic scale factor).
#[must_use]
pub fn input_noise_reads_as(effect: Effect) -> bool {
    matches!(
        effect,
        Effect::SensorLag | Effect::LeverArmError | Effect::PlatformResonance | Effect::GSensitivity
    )
}

/// A relative size in words: percent to two decimals from 0.01 %, parts per million below.
fn relative(x: f64) -> String {
    if x.abs() >= 1e-4 {
        format!("{:.2} %", x * 100.0)
    } else {
        format!("{:.0} ppm", x * 1e6)
    }
}

impl fmt::Display for Suspicion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.effect {
            Effect::GSensitivity => "the outputs follow the specific force, as a g-sensitive gyro's do",
            Effect::LeverArmError => {
                "the outputs follow the motion as from a lever arm other than the sidecar's"
            }
            Effect::AxisTimeSkew => "the output channels are delayed apart",
            Effect::ScaleNonlinearity => {
                "the outputs hold a part quadratic in their inputs (a quadratic scale factor)"
            }
            _ => "the outputs hold a catalogue effect the model does not",
        };
        let beside = self
            .beside
            .map_or_else(String::new, |r| format!(" with {r} fitted first"));
        let sigmas = |z: Option<f64>| z.map_or_else(String::new, |z| format!(" ({z:.1} of its deviations)"));
        write!(
            f,
            "{what} ({} over {:.2}-{:.1} Hz removes chi2 {:.1}{beside}, {:.1} needed): \
             the model's K and delay hold part of it, without a misfit the self-check sees; with \
             it fitted beside them, ",
            self.effect, self.band_hz[0], self.band_hz[1], self.delta_chi2, self.threshold,
        )?;
        if let Some(d) = self.channel_delays_s {
            let of_a_channel = self.delay_shift_sigmas.map_or_else(String::new, |z| {
                format!(" (the furthest {z:.1} of a channel's deviation)")
            });
            write!(
                f,
                "the channels' delays are {:+.1}, {:+.1}, {:+.1} us from the model's{of_a_channel}",
                d[0] * 1e6,
                d[1] * 1e6,
                d[2] * 1e6,
            )?;
        } else {
            let way = if self.delay_shift_s >= 0.0 {
                "later"
            } else {
                "earlier"
            };
            write!(
                f,
                "the delay comes out {:.1} us {way}{}",
                self.delay_shift_s.abs() * 1e6,
                sigmas(self.delay_shift_sigmas)
            )?;
        }
        write!(f, " and K moves by up to {}", relative(self.k_shift_relative))?;
        if let Some(e) = &self.k_shift {
            write!(
                f,
                " (its {}/{} element by {:.1} of its deviations)",
                e.output, e.input, e.sigmas
            )?;
        }
        if self.angle_noise_taken_white {
            write!(f, "; {WHITE_ANGLE_NOISE_READING}")?;
        }
        write!(
            f,
            ". `imu-attest discrepancy` sizes it and `identify --effects` fits it beside K (in the \
             app: Missing effects, Accept)"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::Suspicion;
    use crate::effect::Effect;
    use crate::ident::warnings::{ElementChange, IdentWarning};

    fn g_sensitivity() -> Suspicion {
        Suspicion {
            effect: Effect::GSensitivity,
            delta_chi2: 348.04,
            threshold: 88.66,
            band_hz: [0.12, 39.9],
            beside: None,
            delay_shift_s: 25.5e-6,
            delay_shift_sigmas: Some(14.04),
            channel_delays_s: None,
            k_shift: Some(ElementChange {
                output: "gy".to_owned(),
                input: "wz".to_owned(),
                sigmas: 2.64,
            }),
            k_shift_relative: 1.1e-3,
            angle_noise_taken_white: false,
        }
    }

    #[test]
    fn a_suspected_effect_says_what_it_is_its_evidence_and_what_it_moves() {
        let text = IdentWarning::EffectSuspected(g_sensitivity()).to_string();
        for part in [
            "the outputs follow the specific force, as a g-sensitive gyro's do",
            "g_sensitivity over 0.12-39.9 Hz removes chi2 348.0, 88.7 needed",
            "the delay comes out 25.5 us later (14.0 of its deviations)",
            "K moves by up to 0.11 % (its gy/wz element by 2.6 of its deviations)",
            "`identify --effects`",
        ] {
            assert!(text.contains(part), "{part:?} not in: {text}");
        }
        assert!(!text.contains("fitted first"));
        let skew = Suspicion {
            effect: Effect::AxisTimeSkew,
            channel_delays_s: Some([-1.2e-4, 2.4e-4, -1.2e-4]),
            ..g_sensitivity()
        }
        .to_string();
        assert!(
            skew.contains("the channels' delays are -120.0, +240.0, -120.0 us from the model's (the furthest 14.0 of a channel's deviation)"),
            "{skew}"
        );
        assert!(
            skew.starts_with("the output channels are delayed apart (axis_time_skew over"),
            "{skew}"
        );
        // Beside a rival, without deviations.
        let bare = Suspicion {
            effect: Effect::LeverArmError,
            beside: Some(Effect::SensorLag),
            delay_shift_s: -6.0e-6,
            delay_shift_sigmas: None,
            k_shift: None,
            k_shift_relative: 5e-5,
            ..g_sensitivity()
        }
        .to_string();
        for part in [
            "lever arm other than the sidecar's",
            "removes chi2 348.0 with sensor_lag fitted first",
            "the delay comes out 6.0 us earlier and K moves by up to 50 ppm. `imu-attest discrepancy`",
        ] {
            assert!(bare.contains(part), "{part:?} not in: {bare}");
        }
        assert!(!bare.contains("taken white"), "{bare}");
        // With the angle noise taken white for want of a sound gyro, the other reading is said.
        let white = Suspicion {
            angle_noise_taken_white: true,
            ..g_sensitivity()
        }
        .to_string();
        assert!(
            white.contains(
                "(14.0 of its deviations) and K moves by up to 0.11 % (its gy/wz element by 2.6 of \
                 its deviations); the stand's angle noise is taken white here (no sound gyro in \
                 this run): a coloured one enters the inputs as motion where the motion is weak \
                 and lowers the measured gain there, which a fit across frequency can take for \
                 this effect, so confirm it with a sound gyro on the stand before correcting for \
                 it. `imu-attest discrepancy`"
            ),
            "{white}"
        );
    }

    /// Figures without deviations are left out of the file, not written as `null` (which the
    /// model file's finiteness check refuses outside `*_std` fields), and read back the same.
    #[test]
    fn figures_without_deviations_are_left_out_of_the_file_and_read_back() {
        let s = Suspicion {
            delay_shift_sigmas: None,
            k_shift: None,
            ..g_sensitivity()
        };
        let w = IdentWarning::EffectSuspected(s);
        let json = serde_json::to_value(&w).expect("serialised");
        assert_eq!(json["kind"], "effect_suspected");
        assert_eq!(json["effect"], "g_sensitivity");
        for absent in [
            "delay_shift_sigmas",
            "channel_delays_s",
            "k_shift",
            "beside",
            "angle_noise_taken_white",
        ] {
            assert!(json.get(absent).is_none(), "{absent}: {json}");
        }
        assert!(!json.to_string().contains("null"), "{json}");
        let back: IdentWarning = serde_json::from_value(json).expect("read back");
        assert_eq!(back, w);
        let white = IdentWarning::EffectSuspected(Suspicion {
            angle_noise_taken_white: true,
            ..g_sensitivity()
        });
        let json = serde_json::to_value(&white).expect("serialised");
        assert_eq!(json["angle_noise_taken_white"], true);
        let back: IdentWarning = serde_json::from_value(json).expect("read back");
        assert_eq!(back, white);
    }
}
