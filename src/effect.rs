//! The effect catalogue (contract section 5): the physical effects the paper's model
//! `K e^(-tau s)` leaves out, with their stable ids and readable names. One module that the
//! simulator (which hides them in runs) and the diagnosis (which names them) both use.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::block::Block;

/// The catalogue's effects; ids are stable (contract section 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Gyro outputs respond to the specific force at the block: `x += G f`.
    GSensitivity,
    /// The sensor's own bandwidth beyond the pure delay: a first-order lag `1/(T s + 1)` or a
    /// second-order low-pass (`diagnose::structure::LagShape`).
    SensorLag,
    /// Per-channel delays.
    AxisTimeSkew,
    /// `x_i += k2_i u_i |u_i|`.
    ScaleNonlinearity,
    /// A sinusoid at a fixed frequency, incoherent with the input.
    VibrationTone,
    /// The true accelerometer lever arm differs from the declared one.
    LeverArmError,
    /// A lightly damped second-order mount mode on one input axis.
    PlatformResonance,
    /// The block's clock runs at `1 + drift` against the stand's: its delay grows linearly
    /// through the run.
    ClockDrift,
    /// Stand side, not a sensor effect: the angle measurement lags (its band limit or latency),
    /// which both blocks see through their inputs as the same lag (or one filter both sensor blocks
    /// share, which one run cannot tell apart). Not in
    /// [`Effect::ALL`] (the sensors' catalogue the simulator hides); the diagnosis names it.
    ReferenceLag,
    /// Stand side, not a sensor effect: the angle measurement is low-passed (a reference
    /// interpolated from a slower rate, a zero-phase band limit, a tracker's own causal filter),
    /// so both blocks' outputs rise over the inputs computed from the angles towards the band's
    /// top (with no phase of their own, or a causal filter's lead). Not in [`Effect::ALL`]; the
    /// diagnosis names it (`diagnose::band_limit`).
    ReferenceBandLimit,
}

impl Effect {
    /// Every effect, in catalogue order.
    pub const ALL: [Effect; 8] = [
        Effect::GSensitivity,
        Effect::SensorLag,
        Effect::AxisTimeSkew,
        Effect::ScaleNonlinearity,
        Effect::VibrationTone,
        Effect::LeverArmError,
        Effect::PlatformResonance,
        Effect::ClockDrift,
    ];

    /// The stable id.
    #[must_use]
    pub fn id(self) -> &'static str {
        match self {
            Effect::GSensitivity => "g_sensitivity",
            Effect::SensorLag => "sensor_lag",
            Effect::AxisTimeSkew => "axis_time_skew",
            Effect::ScaleNonlinearity => "scale_nonlinearity",
            Effect::VibrationTone => "vibration_tone",
            Effect::LeverArmError => "lever_arm_error",
            Effect::PlatformResonance => "platform_resonance",
            Effect::ClockDrift => "clock_drift",
            Effect::ReferenceLag => "reference_lag",
            Effect::ReferenceBandLimit => "reference_band_limit",
        }
    }

    /// What the effect is, in the lab's words (without the block).
    #[must_use]
    pub fn what(self) -> &'static str {
        match self {
            Effect::GSensitivity => "g-sensitivity",
            Effect::SensorLag => "first-order lag",
            Effect::AxisTimeSkew => "channel time skew",
            Effect::ScaleNonlinearity => "quadratic scale factor",
            Effect::VibrationTone => "vibration tone",
            Effect::LeverArmError => "lever-arm error",
            Effect::PlatformResonance => "mount resonance",
            Effect::ClockDrift => "clock drift",
            Effect::ReferenceLag => "angle-measurement lag (stand side)",
            Effect::ReferenceBandLimit => "angle-measurement band limit (stand side)",
        }
    }

    /// The readable name on a block, e.g. "gyro g-sensitivity".
    #[must_use]
    pub fn name_on(self, block: Block) -> String {
        format!("{} {}", block.word(), self.what())
    }

    /// The blocks the effect can apply to.
    #[must_use]
    pub fn blocks(self) -> &'static [Block] {
        match self {
            Effect::GSensitivity => &[Block::Gyro],
            Effect::LeverArmError => &[Block::Accel],
            _ => &Block::BOTH,
        }
    }

    /// Whether the effect is the stand's (its angle measurement), not a sensor's.
    #[must_use]
    pub fn is_stand_side(self) -> bool {
        matches!(self, Effect::ReferenceLag | Effect::ReferenceBandLimit)
    }

    /// Whether the effect is a filter, the block's or the stand's, whose misfit grows towards the
    /// band's top (a mount mode, a lag, a band limit, channel delays): what a band ended early
    /// by the identified model's misfit there (`band_top_misfit`) may have missed, so that the
    /// model with it accepted is tried through that band again (`diagnose::extend`).
    #[must_use]
    pub fn shapes_the_band_top(self) -> bool {
        match self {
            Effect::SensorLag
            | Effect::AxisTimeSkew
            | Effect::PlatformResonance
            | Effect::ReferenceLag
            | Effect::ReferenceBandLimit => true,
            // A clock drift's misfit grows with frequency too, but its correction resamples the
            // outputs: its chi2 is of another design, and the stretch's test compares chi2s.
            Effect::ClockDrift
            | Effect::GSensitivity
            | Effect::ScaleNonlinearity
            | Effect::VibrationTone
            | Effect::LeverArmError => false,
        }
    }

    /// Every id, comma-separated (for messages).
    #[must_use]
    pub fn known_ids() -> String {
        Effect::ALL.map(Effect::id).join(", ")
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// An id that is not in the catalogue.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown effect '{0}' (known: {known})", known = Effect::known_ids())]
pub struct UnknownEffect(pub String);

impl FromStr for Effect {
    type Err = UnknownEffect;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Effect::ALL
            .into_iter()
            .find(|e| e.id() == s)
            .ok_or_else(|| UnknownEffect(s.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_through_text_and_json() {
        for e in Effect::ALL {
            assert_eq!(e.id().parse::<Effect>(), Ok(e));
            assert_eq!(serde_json::to_string(&e).ok(), Some(format!("\"{}\"", e.id())));
        }
        assert_eq!("lag".parse::<Effect>(), Err(UnknownEffect("lag".to_owned())));
        // The stand side's are the diagnosis's, not the simulator's: JSON only (accepted-effects
        // files, reports).
        for e in [Effect::ReferenceLag, Effect::ReferenceBandLimit] {
            let json = format!("\"{}\"", e.id());
            assert_eq!(serde_json::to_string(&e).ok(), Some(json.clone()));
            assert_eq!(serde_json::from_str::<Effect>(&json).ok(), Some(e));
            assert!(e.is_stand_side() && e.id().parse::<Effect>().is_err());
        }
        assert!(UnknownEffect("x".into()).to_string().contains("clock_drift"));
    }

    #[test]
    fn names_and_blocks() {
        assert_eq!(Effect::GSensitivity.name_on(Block::Gyro), "gyro g-sensitivity");
        assert_eq!(
            Effect::ClockDrift.name_on(Block::Accel),
            "accelerometer clock drift"
        );
        assert_eq!(Effect::LeverArmError.blocks(), &[Block::Accel]);
        assert_eq!(Effect::ClockDrift.blocks(), &Block::BOTH);
    }
}
