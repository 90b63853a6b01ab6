//! The nine recorded channels a fault can sit in, named as the run format names them.

use serde::{Deserialize, Serialize};

use crate::run::Run;

/// A recorded channel of a run (contract section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Roll angle, rad.
    Roll,
    /// Yaw angle, rad.
    Yaw,
    /// Pitch angle, rad.
    Pitch,
    /// Gyro x, rad/s.
    Gx,
    /// Gyro y, rad/s.
    Gy,
    /// Gyro z, rad/s.
    Gz,
    /// Accelerometer x, m/s^2.
    Ax,
    /// Accelerometer y, m/s^2.
    Ay,
    /// Accelerometer z, m/s^2.
    Az,
}

impl Channel {
    /// Every channel, in the run format's order.
    pub const ALL: [Channel; 9] = [
        Channel::Roll,
        Channel::Yaw,
        Channel::Pitch,
        Channel::Gx,
        Channel::Gy,
        Channel::Gz,
        Channel::Ax,
        Channel::Ay,
        Channel::Az,
    ];

    /// The column's header name.
    #[must_use]
    pub fn name(self) -> &'static str {
        ["roll", "yaw", "pitch", "gx", "gy", "gz", "ax", "ay", "az"][self as usize]
    }

    /// The channel's unit.
    #[must_use]
    pub fn unit(self) -> &'static str {
        match self {
            Channel::Roll | Channel::Yaw | Channel::Pitch => "rad",
            Channel::Gx | Channel::Gy | Channel::Gz => "rad/s",
            Channel::Ax | Channel::Ay | Channel::Az => "m/s^2",
        }
    }

    /// Whether this is one of the gyro's three channels.
    #[must_use]
    pub fn is_gyro(self) -> bool {
        matches!(self, Channel::Gx | Channel::Gy | Channel::Gz)
    }

    /// Whether this is one of the three angles.
    #[must_use]
    pub fn is_angle(self) -> bool {
        (self as usize) < 3
    }

    /// The channel by its header name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// This channel's values in `run`, `None` when its block is absent.
    #[must_use]
    pub fn values(self, run: &Run) -> Option<&[f64]> {
        let i = self as usize;
        match i {
            0..3 => Some(&run.angles[i]),
            3..6 => run.gyro.as_ref().map(|g| g[i - 3].as_slice()),
            _ => run.accel.as_ref().map(|a| a[i - 6].as_slice()),
        }
    }
}
