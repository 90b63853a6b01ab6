//! Sines in the stand's programme (`simulate --sine AXIS:HZ:DEG`): a stand's test programme often
//! adds sines to the flight motion, one axis at a frequency, several axes at different ones. Their
//! lines are what puts an estimate's columns at different places in one Welch bin
//! (`spectral::centroid`, "Offset matrix").
//!
//! A sine is added to the programme before the servo, at the synthesis grid's bin nearest the
//! frequency asked (a whole number of periods on the periodic grid, so it stays a pure line; the
//! grid's spacing is below `1 / duration`), with a zero phase at the grid's start. Units: Hz,
//! rad (degrees on the command line).

use std::fmt;
use std::str::FromStr;

use num_complex::Complex64;

use super::synth::Grid;

/// The programme's axes, in the simulator's order.
pub const AXES: [&str; 3] = ["roll", "yaw", "pitch"];

/// One sine of the programme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgramSine {
    /// The axis, an index into [`AXES`].
    pub axis: usize,
    /// Frequency, Hz (placed at the nearest grid bin).
    pub frequency_hz: f64,
    /// Amplitude of the programme's angle, rad.
    pub amplitude_rad: f64,
}

/// Why a `--sine` argument was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SineSpecError {
    /// Not three fields.
    #[error("'{0}' is not AXIS:HZ:DEG (e.g. roll:2.5:3)")]
    Shape(String),
    /// An unknown axis.
    #[error("unknown axis '{0}' (known: roll, yaw, pitch)")]
    Axis(String),
    /// A frequency or amplitude that is not a positive number.
    #[error("{what} '{value}' is not a positive number")]
    Number {
        /// Which field.
        what: &'static str,
        /// The text given.
        value: String,
    },
}

impl FromStr for ProgramSine {
    type Err = SineSpecError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split(':').collect();
        let [axis, hz, deg] = parts[..] else {
            return Err(SineSpecError::Shape(s.to_owned()));
        };
        let axis = AXES
            .iter()
            .position(|a| *a == axis)
            .ok_or_else(|| SineSpecError::Axis(axis.to_owned()))?;
        let positive = |what: &'static str, value: &str| {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| SineSpecError::Number {
                    what,
                    value: value.to_owned(),
                })
        };
        Ok(Self {
            axis,
            frequency_hz: positive("frequency", hz)?,
            amplitude_rad: positive("amplitude", deg)?.to_radians(),
        })
    }
}

impl fmt::Display for ProgramSine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}",
            AXES[self.axis],
            self.frequency_hz,
            self.amplitude_rad.to_degrees()
        )
    }
}

/// Adds `sine` to the programme's spectrum of its axis on `grid`: `a cos(2 pi f t - pi / 2)` at the
/// nearest bin strictly between DC and Nyquist.
pub(super) fn add(grid: &mut Grid, program: &mut [Vec<Complex64>; 3], sine: &ProgramSine) {
    let n = grid.fft.len();
    let fs = grid.fft.sample_rate_hz();
    let last = program[sine.axis].len().saturating_sub(1);
    if last < 2 {
        return;
    }
    let k = ((sine.frequency_hz * n as f64 / fs).round() as usize).clamp(1, last - 1);
    let f = k as f64 * fs / n as f64;
    let samples: Vec<f64> = (0..n)
        .map(|i| sine.amplitude_rad * (2.0 * std::f64::consts::PI * f * i as f64 / fs).sin())
        .collect();
    let spectrum = grid.fft.forward(&samples);
    program[sine.axis][k] += spectrum[k];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sine_spec_is_parsed_and_bad_ones_are_named() {
        let s: ProgramSine = "yaw:2.5:3".parse().unwrap();
        assert_eq!(s.axis, 1);
        assert!((s.frequency_hz - 2.5).abs() < 1e-15);
        assert!((s.amplitude_rad - 3f64.to_radians()).abs() < 1e-15);
        let again: ProgramSine = s.to_string().parse().unwrap();
        assert_eq!((again.axis, again.frequency_hz), (s.axis, s.frequency_hz));
        assert!((again.amplitude_rad - s.amplitude_rad).abs() < 1e-15);
        assert!(matches!(
            "yaw:2.5".parse::<ProgramSine>(),
            Err(SineSpecError::Shape(_))
        ));
        assert!(matches!(
            "heave:2:1".parse::<ProgramSine>(),
            Err(SineSpecError::Axis(_))
        ));
        assert!(matches!(
            "roll:-1:1".parse::<ProgramSine>(),
            Err(SineSpecError::Number {
                what: "frequency",
                ..
            })
        ));
        assert!(matches!(
            "roll:1:nan".parse::<ProgramSine>(),
            Err(SineSpecError::Number {
                what: "amplitude",
                ..
            })
        ));
    }

    /// The added line is a pure sine of the amplitude asked at the nearest grid frequency, on its
    /// axis only.
    #[test]
    fn the_programme_gets_a_pure_line_of_the_amplitude_asked() {
        let mut grid = Grid::new(4000, 200.0);
        let bins = grid.omega.len();
        let mut program: [Vec<Complex64>; 3] = std::array::from_fn(|_| vec![Complex64::default(); bins]);
        let sine = ProgramSine {
            axis: 2,
            frequency_hz: 3.013,
            amplitude_rad: 0.05,
        };
        add(&mut grid, &mut program, &sine);
        let x = grid.fft.inverse(program[2].clone());
        // 4000 samples at 200 Hz: bins every 0.05 Hz, so 3.0 Hz.
        for (i, v) in x.iter().enumerate() {
            let want = 0.05 * (2.0 * std::f64::consts::PI * 3.0 * i as f64 / 200.0).sin();
            assert!((v - want).abs() < 1e-12, "sample {i}: {v} vs {want}");
        }
        assert!(program[0].iter().chain(&program[1]).all(|z| z.norm() == 0.0));
    }
}
