//! A finding made with the stand's angle noise taken white for want of a sound gyro, said in its
//! evidence.
//!
//! Without a gyro whose outputs witness the motion ([`crate::stand::colour`]), the observer takes
//! the angles' noise white at the declared (or Nyquist-read) level. A real stand's is coloured,
//! most of it inside the motion's band (an optical reference, an encoder's interpolation); the
//! part beyond the white model is taken as motion, and the inputs computed from the angles hold
//! more than the motion where the motion is weak: the measured gain falls there. A fit across
//! frequency reads that fall as an effect that bends the gain down (a lag, a lever-arm error, a
//! resonance's flank). Measured (1 Dec and 2 Dec): an accelerometer alone on a
//! simulated real-like stand (`--stand real`, cruise, 120 s, seed 11), no effect hidden: the
//! diagnosis named a first-order lag of 1.7 ms and a lever-arm error of 12 mm and the
//! identification suspected the lever arm, `K` 1.06 % off; the same run with a gyro beside it
//! (the coloured model): nothing suspected, only the stand's 30 Hz band limit named, `K` 0.48 %
//! off.
//!
//! Said of the effects such a fall may read as ([`input_noise_reads_as`]): a lag, a lever-arm
//! error, a mount resonance, a g-sensitivity; not of a tone, a clock drift, a quadratic scale
//! factor, channel delays, the angle measurement's own lag, or its band limit, which raises the
//! gain (on a real-like stand's turbulent cruise, accelerometer alone, the stand's 30 Hz band
//! limit was named, rightly). The lag and the lever-arm error were measured to read so; the
//! resonance and the g-sensitivity are included by caution.

use crate::effect::Effect;
use crate::ident::suspicion::{WHITE_ANGLE_NOISE_READING, input_noise_reads_as};

/// The words added to the evidence of a finding of `effect` when the angle noise was taken white
/// (`None` for an effect input noise cannot read as).
#[must_use]
pub fn white_angle_noise_caveat(effect: Effect) -> Option<String> {
    input_noise_reads_as(effect).then(|| format!("; {WHITE_ANGLE_NOISE_READING}"))
}

#[cfg(test)]
mod tests {
    use super::white_angle_noise_caveat;
    use crate::effect::Effect;

    #[test]
    fn the_caveat_is_said_of_the_effects_that_bend_the_gain_down_only() {
        for e in [
            Effect::SensorLag,
            Effect::LeverArmError,
            Effect::GSensitivity,
            Effect::PlatformResonance,
        ] {
            let words = white_angle_noise_caveat(e).expect("said");
            assert!(
                words.starts_with("; the stand's angle noise is taken white here"),
                "{words}"
            );
        }
        for e in [
            Effect::VibrationTone,
            Effect::ClockDrift,
            Effect::ScaleNonlinearity,
            Effect::AxisTimeSkew,
            Effect::ReferenceBandLimit,
            Effect::ReferenceLag,
        ] {
            assert_eq!(white_angle_noise_caveat(e), None, "{e}");
        }
    }
}
