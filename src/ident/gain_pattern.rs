//! What an implausible `K` looks like, where it looks like something: the self-check's
//! `gain_pattern` ([`super::warnings::IdentWarning::GainPattern`]), said beside the
//! element-by-element `implausible_gain`.
//!
//! The usual causes of a `K` far from a calibrated block's are a lab's bookkeeping, not the
//! sensor: outputs written in deg/s, in g or in mg where the run format asks rad/s and m/s^2,
//! angles in degrees, an axis reversed or two axes swapped between the sensor's columns and the
//! stand's. Each gives `K` as a scale times a signed permutation of the identity, to the
//! sensor's own few-per-mille errors. [`gain_pattern`] finds the signed permutation nearest to
//! `K` (the one whose elements carry most of `K`), and says it where every one of its elements
//! lies within [`PATTERN_TOLERANCE`] of their common size and every other element below that
//! share of it: then it names the unit whose factor the size matches within [`UNIT_TOLERANCE`]
//! (only those that apply to the block: a gyro's outputs in deg/s, an accelerometer's outputs in
//! g or mg; angles in degrees scale no block's inputs, which hold their sines and cosines, the
//! Euler rates' conversion to body rates and gravity's direction, and a stand's moves of a
//! degree or more in degrees read as radians make `K` no pattern at all), and each output that
//! follows another input or the reversed one.
//! A pattern with neither (the identity at a scale no unit explains) is not said.
//!
//! Units: `K` dimensionless (output unit over input unit, as the run format's); the scale is
//! `K`'s. NaN elements: no pattern.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::block::Block;
use crate::ident::signals::channel_names;

/// Largest relative spread of the permutation's elements about their common size, and largest
/// other element relative to it: a calibrated sensor's scale and alignment errors are a few per
/// mille, a unit slip or a swap keeps them so.
pub const PATTERN_TOLERANCE: f64 = 0.05;
/// Largest relative distance of `K`'s size from a unit's factor for that unit to be named.
pub const UNIT_TOLERANCE: f64 = 0.03;
/// Standard gravity, m/s^2 (the unit g).
const STANDARD_GRAVITY: f64 = 9.80665;

/// A unit slip the scale of `K` matches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnitSlip {
    /// A gyro's outputs in deg/s (`K` near `180 / pi`).
    OutputsInDegPerS,
    /// An accelerometer's outputs in g (`K` near `1 / 9.80665`).
    OutputsInG,
    /// An accelerometer's outputs in mg (`K` near `1000 / 9.80665`).
    OutputsInMilliG,
}

impl UnitSlip {
    /// The slips that scale `block`'s `K`.
    #[must_use]
    pub fn of(block: Block) -> &'static [UnitSlip] {
        match block {
            Block::Gyro => &[UnitSlip::OutputsInDegPerS],
            Block::Accel => &[UnitSlip::OutputsInG, UnitSlip::OutputsInMilliG],
        }
    }

    /// The factor the slip puts on `K`.
    #[must_use]
    pub fn factor(self) -> f64 {
        match self {
            UnitSlip::OutputsInDegPerS => 180.0 / std::f64::consts::PI,
            UnitSlip::OutputsInG => 1.0 / STANDARD_GRAVITY,
            UnitSlip::OutputsInMilliG => 1000.0 / STANDARD_GRAVITY,
        }
    }

    fn words(self) -> &'static str {
        match self {
            UnitSlip::OutputsInDegPerS => {
                "the outputs look to be in deg/s (K near 180/pi = 57.30), where the run format's unit is rad/s"
            }
            UnitSlip::OutputsInG => {
                "the outputs look to be in g (K near 1/9.807 = 0.1020), where the run format's unit is m/s^2"
            }
            UnitSlip::OutputsInMilliG => {
                "the outputs look to be in mg (K near 1000/9.807 = 102.0), where the run format's unit is m/s^2"
            }
        }
    }
}

/// An output that follows another input than its own, or its own reversed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisFollows {
    /// The output channel (`K`'s row).
    pub output: String,
    /// The input it follows (`K`'s column).
    pub input: String,
    /// Whether it follows that input reversed (a negative element).
    pub reversed: bool,
}

/// `K` as a scale times a signed permutation of the identity (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GainPattern {
    /// The permutation's elements' common size (their mean magnitude).
    pub scale: f64,
    /// The unit slip the scale matches, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<UnitSlip>,
    /// The outputs off their own axis or reversed (empty: the identity).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub axes: Vec<AxisFollows>,
}

/// The six permutations of three axes.
const PERMUTATIONS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];

/// The pattern `block`'s `k` shows, if it shows one worth saying (module docs).
#[must_use]
pub fn gain_pattern(block: Block, k: &[[f64; 3]; 3]) -> Option<GainPattern> {
    if k.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    let carried = |p: &[usize; 3]| (0..3).map(|i| k[i][p[i]].abs()).sum::<f64>();
    let p = PERMUTATIONS
        .iter()
        .max_by(|a, b| carried(a).total_cmp(&carried(b)))?;
    let scale = carried(p) / 3.0;
    if scale <= 0.0 {
        return None;
    }
    let fits = (0..3).all(|i| {
        (0..3).all(|j| {
            let v = k[i][j].abs() / scale;
            if j == p[i] {
                (v - 1.0).abs() <= PATTERN_TOLERANCE
            } else {
                v <= PATTERN_TOLERANCE
            }
        })
    });
    if !fits {
        return None;
    }
    let units = UnitSlip::of(block)
        .iter()
        .copied()
        .find(|u| (scale / u.factor() - 1.0).abs() <= UNIT_TOLERANCE);
    let (inputs, outputs) = channel_names(block);
    let axes: Vec<AxisFollows> = (0..3)
        .filter(|&i| p[i] != i || k[i][p[i]] < 0.0)
        .map(|i| AxisFollows {
            output: outputs[i].to_owned(),
            input: inputs[p[i]].to_owned(),
            reversed: k[i][p[i]] < 0.0,
        })
        .collect();
    (units.is_some() || !axes.is_empty()).then_some(GainPattern { scale, units, axes })
}

impl fmt::Display for GainPattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let shape = if self.axes.is_empty() {
            "the identity"
        } else {
            "the identity with axes swapped or reversed"
        };
        write!(
            f,
            "K reads as {:.4} times {shape} (its elements within {:.0} % of that, the others below): ",
            self.scale,
            PATTERN_TOLERANCE * 100.0
        )?;
        if let Some(u) = self.units {
            write!(f, "{}", u.words())?;
            if !self.axes.is_empty() {
                write!(f, "; ")?;
            }
        }
        if !self.axes.is_empty() {
            let follows: Vec<String> = self
                .axes
                .iter()
                .map(|a| {
                    let sign = if a.reversed { "-" } else { "" };
                    format!("{} follows {sign}{}", a.output, a.input)
                })
                .collect();
            write!(
                f,
                "{}: the outputs' axis order or signs differ from the stand's axes",
                follows.join(", ")
            )?;
        }
        write!(
            f,
            ". Convert or reorder the columns and identify again: this model is of the run as recorded"
        )
    }
}

#[cfg(test)]
#[path = "gain_pattern_tests.rs"]
mod tests;
