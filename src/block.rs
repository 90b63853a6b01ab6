//! The sensor blocks under test.

use serde::{Deserialize, Serialize};

/// A sensor block on the platform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Block {
    /// The gyro triad.
    Gyro,
    /// The accelerometer triad.
    Accel,
}

impl std::fmt::Display for Block {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Block {
    /// Both blocks, gyro first.
    pub const BOTH: [Block; 2] = [Block::Gyro, Block::Accel];

    /// The contract's name of the block.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Block::Gyro => "gyro",
            Block::Accel => "accel",
        }
    }

    /// The block in the lab's words, as readable names begin ("gyro", "accelerometer").
    #[must_use]
    pub fn word(self) -> &'static str {
        match self {
            Block::Gyro => "gyro",
            Block::Accel => "accelerometer",
        }
    }

    /// The block whose contract name is `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::BOTH.into_iter().find(|b| b.name() == name)
    }

    /// The unit of the block's outputs (and of its inputs): angular rate or specific force.
    #[must_use]
    pub fn output_unit(self) -> &'static str {
        match self {
            Block::Gyro => "rad/s",
            Block::Accel => "m/s^2",
        }
    }
}
