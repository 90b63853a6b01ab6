//! The effect catalogue (contract section 5) as the simulator applies it, and the command line's
//! `--effect ID[:block][@scale]` syntax. `@scale` (an extension of the contract) multiplies the
//! effect's default size, so tests can sweep from barely significant to large.
//!
//! Without `:block`, an effect that exists for one block only goes to that block, and an effect
//! that exists for either block goes to both.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

pub use crate::block::Block;

/// The catalogue's effects; ids are stable (contract section 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Gyro outputs respond to the specific force at the block: `x += G f`.
    GSensitivity,
    /// A first-order lag `1/(T s + 1)` beyond the pure delay.
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
}

impl Effect {
    /// Every effect, in catalogue order.
    pub const ALL: [Effect; 7] = [
        Effect::GSensitivity,
        Effect::SensorLag,
        Effect::AxisTimeSkew,
        Effect::ScaleNonlinearity,
        Effect::VibrationTone,
        Effect::LeverArmError,
        Effect::PlatformResonance,
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
        }
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
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// One `--effect` request: the effect, the blocks it goes to, and a size multiplier.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectSpec {
    /// Which effect.
    pub effect: Effect,
    /// Which blocks carry it.
    pub blocks: Vec<Block>,
    /// Multiplier of the default size (1 = default).
    pub scale: f64,
}

/// Why an `--effect` argument was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EffectSpecError {
    /// Not an id of the catalogue.
    #[error(
        "unknown effect '{0}' (known: g_sensitivity, sensor_lag, axis_time_skew, scale_nonlinearity, vibration_tone, lever_arm_error, platform_resonance)"
    )]
    UnknownEffect(String),
    /// Not `gyro` or `accel`.
    #[error("unknown block '{0}' (known: gyro, accel)")]
    UnknownBlock(String),
    /// The effect does not exist for that block.
    #[error("effect '{effect}' does not apply to the {block} block")]
    WrongBlock {
        /// The effect id.
        effect: &'static str,
        /// The block name.
        block: &'static str,
    },
    /// `@scale` not a positive finite number.
    #[error("effect scale '{0}' is not a positive number")]
    BadScale(String),
}

impl FromStr for EffectSpec {
    type Err = EffectSpecError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (head, scale) = match s.split_once('@') {
            Some((h, sc)) => match sc.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => (h, v),
                _ => return Err(EffectSpecError::BadScale(sc.to_owned())),
            },
            None => (s, 1.0),
        };
        let (id, block) = match head.split_once(':') {
            Some((i, b)) => (i, Some(b)),
            None => (head, None),
        };
        let effect = Effect::ALL
            .into_iter()
            .find(|e| e.id() == id)
            .ok_or_else(|| EffectSpecError::UnknownEffect(id.to_owned()))?;
        let blocks = match block {
            None => effect.blocks().to_vec(),
            Some(name) => {
                let b = Block::BOTH
                    .into_iter()
                    .find(|b| b.name() == name)
                    .ok_or_else(|| EffectSpecError::UnknownBlock(name.to_owned()))?;
                if !effect.blocks().contains(&b) {
                    return Err(EffectSpecError::WrongBlock {
                        effect: effect.id(),
                        block: b.name(),
                    });
                }
                vec![b]
            }
        };
        Ok(EffectSpec {
            effect,
            blocks,
            scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_ids_blocks_and_scales() {
        let s: EffectSpec = "sensor_lag".parse().unwrap();
        assert_eq!(
            (s.effect, s.blocks.clone(), s.scale),
            (Effect::SensorLag, Block::BOTH.to_vec(), 1.0)
        );
        let s: EffectSpec = "g_sensitivity".parse().unwrap();
        assert_eq!(s.blocks, vec![Block::Gyro]);
        let s: EffectSpec = "platform_resonance:accel@0.25".parse().unwrap();
        assert_eq!(
            (s.effect, s.blocks, s.scale),
            (Effect::PlatformResonance, vec![Block::Accel], 0.25)
        );
        for e in Effect::ALL {
            assert_eq!(e.id().parse::<EffectSpec>().unwrap().effect, e);
        }
    }

    #[test]
    fn refuses_bad_specs() {
        assert!(matches!(
            "lag".parse::<EffectSpec>(),
            Err(EffectSpecError::UnknownEffect(_))
        ));
        assert!(matches!(
            "sensor_lag:mag".parse::<EffectSpec>(),
            Err(EffectSpecError::UnknownBlock(_))
        ));
        assert!(matches!(
            "g_sensitivity:accel".parse::<EffectSpec>(),
            Err(EffectSpecError::WrongBlock { .. })
        ));
        assert!(matches!(
            "lever_arm_error:gyro".parse::<EffectSpec>(),
            Err(EffectSpecError::WrongBlock { .. })
        ));
        for bad in ["sensor_lag@0", "sensor_lag@-1", "sensor_lag@x", "sensor_lag@inf"] {
            assert!(
                matches!(bad.parse::<EffectSpec>(), Err(EffectSpecError::BadScale(_))),
                "{bad}"
            );
        }
    }
}
