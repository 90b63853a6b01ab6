//! The command line's `--effect ID[:block][@scale]` syntax. `@scale` (an extension of the contract) multiplies the
//! effect's default size, so tests can sweep from barely significant to large.
//!
//! Without `:block`, an effect that exists for one block only goes to that block, and an effect
//! that exists for either block goes to both.

use std::str::FromStr;

pub use crate::block::Block;
pub use crate::effect::Effect;

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
    #[error(transparent)]
    UnknownEffect(#[from] crate::effect::UnknownEffect),
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
        let effect: Effect = id.parse()?;
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
