//! Flight regimes: spectral models of an aircraft's perturbed angular motion about a steady flight
//! path, used as the stand's program signal.
//!
//! A regime is a sum of independent modes. Mode `m` is unit white noise through a second-order
//! resonant low-pass (`f0`, `zeta`), scaled to an RMS angle and distributed over the axes
//! `[roll, yaw, pitch]` by a complex gain vector, so that modes which move several axes (the Dutch
//! roll couples roll and yaw with a phase lag) make the axes cross-correlated. The modes cover the
//! slow path deviations, the short-period and Dutch-roll oscillations, the response to turbulence
//! and airframe/buffet motion up to about 20 Hz.

use std::fmt;
use std::str::FromStr;

use num_complex::Complex64;
use serde::Serialize;

/// One mode of a regime.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mode {
    /// What the mode represents.
    pub name: &'static str,
    /// Natural frequency, Hz.
    pub f0_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// RMS angle of the mode on an axis whose gain magnitude is 1, rad.
    pub rms_rad: f64,
    /// Gain magnitude per axis `[roll, yaw, pitch]`.
    pub gain: [f64; 3],
    /// Phase per axis, degrees.
    pub phase_deg: [f64; 3],
}

impl Mode {
    /// Complex gain of axis `axis`.
    #[must_use]
    pub fn axis_gain(&self, axis: usize) -> Complex64 {
        Complex64::from_polar(self.gain[axis], self.phase_deg[axis].to_radians())
    }
}

/// The flight regimes the stand can replay.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    /// Cruise in calm air.
    Cruise,
    /// Cruise in moderate turbulence.
    TurbulentCruise,
    /// Approach and landing configuration: larger, slower manoeuvres, flap buffet.
    Approach,
}

impl Regime {
    /// Every regime, in a fixed order.
    pub const ALL: [Regime; 3] = [Regime::Cruise, Regime::TurbulentCruise, Regime::Approach];

    /// The regime's name as used on the command line and in sidecars.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Regime::Cruise => "cruise",
            Regime::TurbulentCruise => "turbulent_cruise",
            Regime::Approach => "approach",
        }
    }

    /// The regime's modes.
    #[must_use]
    pub fn modes(self) -> Vec<Mode> {
        // (scale of slow, short-period, Dutch roll, turbulence, buffet, high band; buffet f0)
        let (slow, sp, dr, turb, buffet, high, buffet_f0) = match self {
            Regime::Cruise => (1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 9.0),
            Regime::TurbulentCruise => (1.2, 1.5, 1.5, 4.0, 3.0, 2.5, 9.0),
            Regime::Approach => (3.0, 2.0, 1.5, 2.0, 1.5, 1.5, 7.0),
        };
        vec![
            mode(
                "path deviation",
                0.08,
                0.5,
                0.010 * slow,
                [0.6, 1.0, 0.8],
                [0.0, 0.0, 30.0],
            ),
            mode(
                "short period",
                0.5,
                0.6,
                0.004 * sp,
                [0.2, 0.1, 1.0],
                [0.0, 10.0, 0.0],
            ),
            mode(
                "dutch roll",
                0.35,
                0.12,
                0.004 * dr,
                [1.0, 0.6, 0.05],
                [0.0, -100.0, 0.0],
            ),
            mode(
                "turbulence response",
                1.5,
                0.7,
                0.0015 * turb,
                [1.0, 0.4, 0.7],
                [0.0, 20.0, -40.0],
            ),
            mode(
                "airframe buffet",
                buffet_f0,
                0.25,
                2.0e-4 * buffet,
                [1.0, 0.5, 0.8],
                [0.0, 0.0, 60.0],
            ),
            mode(
                "high band",
                16.0,
                0.3,
                1.0e-4 * high,
                [0.7, 1.0, 0.6],
                [0.0, -30.0, 0.0],
            ),
        ]
    }
}

fn mode(
    name: &'static str,
    f0_hz: f64,
    zeta: f64,
    rms_rad: f64,
    gain: [f64; 3],
    phase_deg: [f64; 3],
) -> Mode {
    Mode {
        name,
        f0_hz,
        zeta,
        rms_rad,
        gain,
        phase_deg,
    }
}

impl fmt::Display for Regime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A regime name that is not one of [`Regime::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown regime '{0}' (known: cruise, turbulent_cruise, approach)")]
pub struct UnknownRegime(pub String);

impl FromStr for Regime {
    type Err = UnknownRegime;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Regime::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| UnknownRegime(s.to_owned()))
    }
}
