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
}
