//! What the simulator put into a run, written to the sidecar under `"truth"`. Only tests read it:
//! the identifier and the diagnosis never do (they must work on real stand data).

use serde::{Deserialize, Serialize};

use super::effect::Effect;

/// Everything the simulator knows about a run it generated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Generator seed.
    pub seed: u64,
    /// Regime name.
    pub regime: String,
    /// White noise of the angle sensors (before quantisation), rad.
    pub angle_white_noise_rad: f64,
    /// Angle sensor quantum, rad.
    pub angle_quantum_rad: f64,
    /// The platform's servo loop.
    pub servo: ServoTruth,
    /// The accelerometer block's true lever arm (differs from the declared one only with
    /// `lever_arm_error`), m.
    pub accel_lever_arm_true_m: [f64; 3],
    /// The gyro block, when present.
    pub gyro: Option<BlockTruth>,
    /// The accelerometer block, when present.
    pub accel: Option<BlockTruth>,
    /// The stand's angle-measurement imperfections (absent: a perfect stand).
    #[serde(default, skip_serializing_if = "is_perfect")]
    pub stand: super::stand::StandImperfections,
    /// Recording faults injected (`simulate --fault`), in order (absent: none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<super::fault::FaultTruth>,
}

fn is_perfect(s: &super::stand::StandImperfections) -> bool {
    !s.any()
}

/// The closed-loop servo: platform angle = `w^2/(s^2 + 2 zeta w s + w^2)` program + jitter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ServoTruth {
    /// Closed-loop natural frequency, Hz.
    pub natural_hz: f64,
    /// Closed-loop damping ratio.
    pub damping: f64,
    /// RMS of the tracking jitter per axis, rad.
    pub jitter_rms_rad: f64,
}

/// One block's true model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockTruth {
    /// `K[i][j]`: gain from input axis j to output channel i.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Pure delay, s.
    pub tau_s: f64,
    /// Output biases, output units.
    pub bias: [f64; 3],
    /// Disturbance model.
    pub noise: NoiseTruth,
    /// Effects present in this block.
    pub effects: Vec<EffectTruth>,
    /// A second-order Butterworth low-pass on the outputs (a sensor's anti-alias filter,
    /// `simulate --sensor-filter-hz`), its corner in Hz; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anti_alias_hz: Option<f64>,
}

/// The disturbance's shaping filter: `psi(f) = D_w L_w xi_w + D_c L_c xi_c / (1 + j f/f_c)`, with
/// `D` diagonal amplitude spectral densities, `L` Cholesky factors of the correlation matrices and
/// `xi` unit white noises. One-sided density
/// `S(f) = D_w C_w D_w + D_c C_c D_c / (1 + (f/f_c)^2)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseTruth {
    /// White part, output units per sqrt(Hz) (one-sided).
    pub white_asd: [f64; 3],
    /// Correlation matrix of the white part.
    pub white_correlation: [[f64; 3]; 3],
    /// Coloured part's low-frequency amplitude density, output units per sqrt(Hz).
    pub coloured_asd: [f64; 3],
    /// Correlation matrix of the coloured part.
    pub coloured_correlation: [[f64; 3]; 3],
    /// Corner of the coloured part, Hz.
    pub coloured_corner_hz: f64,
    /// Rate random walk per channel (independent), output units per s per sqrt(s): the output
    /// drifts by `K sqrt(dt)` per step (`simulate --random-walk`; 0 by default).
    #[serde(default)]
    pub random_walk: [f64; 3],
}

impl NoiseTruth {
    /// The one-sided cross-spectral density matrix at `f_hz`, units^2/Hz.
    #[must_use]
    pub fn psd(&self, f_hz: f64) -> [[f64; 3]; 3] {
        let roll_off = 1.0 / (1.0 + (f_hz / self.coloured_corner_hz).powi(2));
        let mut s = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] = self.white_asd[i] * self.white_correlation[i][j] * self.white_asd[j]
                    + self.coloured_asd[i]
                        * self.coloured_correlation[i][j]
                        * self.coloured_asd[j]
                        * roll_off;
            }
            // One-sided density of a random walk: 2 K^2 / (2 pi f)^2.
            if self.random_walk[i] > 0.0 {
                s[i][i] += 2.0 * (self.random_walk[i] / (2.0 * std::f64::consts::PI * f_hz)).powi(2);
            }
        }
        s
    }
}

/// An effect and its size, as simulated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum EffectTruth {
    /// `x += G f`, `G` in output units per m/s^2.
    GSensitivity {
        /// The matrix G.
        g_matrix: [[f64; 3]; 3],
    },
    /// `1/(T s + 1)` on every channel.
    SensorLag {
        /// T, s.
        time_constant_s: f64,
    },
    /// Extra delay per output channel beyond `tau_s`.
    AxisTimeSkew {
        /// Per channel, s.
        channel_delay_s: [f64; 3],
    },
    /// `x_i += k2_i u_i |u_i|`.
    ScaleNonlinearity {
        /// Per channel, output units per input unit squared.
        k2: [f64; 3],
    },
    /// `x_i += g(t) a_i sin(2 pi f t + phi_i)`, `g` the gate (1 throughout by default).
    VibrationTone {
        /// Tone frequency, Hz.
        frequency_hz: f64,
        /// Amplitude per channel, output units.
        amplitude: [f64; 3],
        /// Phase per channel, rad.
        phase_rad: [f64; 3],
        /// When the tone is on (absent: throughout).
        #[serde(default, skip_serializing_if = "ToneGate::is_continuous")]
        gate: ToneGate,
    },
    /// True lever arm = declared + offset.
    LeverArmError {
        /// Offset, m.
        offset_m: [f64; 3],
    },
    /// `w^2/(s^2 + 2 zeta w s + w^2)` on one input axis.
    PlatformResonance {
        /// Input axis index (0 x, 1 y, 2 z).
        axis: usize,
        /// Natural frequency, Hz.
        frequency_hz: f64,
        /// Damping ratio.
        damping: f64,
    },
    /// The block's clock runs at `1 + drift_ppm 1e-6` against the stand's (both read 0 at the
    /// recording's start), so the block's delay grows by `drift_ppm` microseconds per second.
    ClockDrift {
        /// Clock rate error, parts per million (positive: the block's clock is fast).
        drift_ppm: f64,
    },
}

impl EffectTruth {
    /// The catalogue entry this is.
    #[must_use]
    pub fn effect(&self) -> Effect {
        match self {
            EffectTruth::GSensitivity { .. } => Effect::GSensitivity,
            EffectTruth::SensorLag { .. } => Effect::SensorLag,
            EffectTruth::AxisTimeSkew { .. } => Effect::AxisTimeSkew,
            EffectTruth::ScaleNonlinearity { .. } => Effect::ScaleNonlinearity,
            EffectTruth::VibrationTone { .. } => Effect::VibrationTone,
            EffectTruth::LeverArmError { .. } => Effect::LeverArmError,
            EffectTruth::PlatformResonance { .. } => Effect::PlatformResonance,
            EffectTruth::ClockDrift { .. } => Effect::ClockDrift,
        }
    }
}

/// When a simulated vibration tone is on (`simulate --tone-gate`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ToneGate {
    /// On throughout.
    #[default]
    Continuous,
    /// Off until `start_s` (s from the record's start), on after.
    From {
        /// Switch-on time, s.
        start_s: f64,
    },
    /// On for `on_s`, off for `off_s`, repeating from the record's start (on first).
    Pulsed {
        /// On time, s.
        on_s: f64,
        /// Off time, s.
        off_s: f64,
    },
}

impl ToneGate {
    /// Whether the tone is on throughout.
    #[must_use]
    pub fn is_continuous(&self) -> bool {
        *self == ToneGate::Continuous
    }

    /// Whether the tone is on at `t_s` (s from the record's start).
    #[must_use]
    pub fn is_on(&self, t_s: f64) -> bool {
        match *self {
            ToneGate::Continuous => true,
            ToneGate::From { start_s } => t_s >= start_s,
            ToneGate::Pulsed { on_s, off_s } => t_s >= 0.0 && t_s.rem_euclid(on_s + off_s) < on_s,
        }
    }
}
