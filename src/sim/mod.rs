//! The stand simulator (`imu-attest simulate`): signal generator -> servo -> gimbaled platform ->
//! angle sensors, with the gyro and accelerometer blocks riding on the platform.
//!
//! Everything is synthesised on a periodic, band-limited grid padded by [`PAD_S`] on each side of
//! the recorded window, so that delays and linear filters are exact and the recorded window does
//! not wrap around (its ends do not match, as in a real recording). Same configuration and seed,
//! same numbers, bit for bit.
//!
//! Units: s, Hz, rad, rad/s, m/s^2.

pub mod block;
pub mod effect;
pub mod fault;
pub use crate::interp;
pub mod regime;
pub mod sines;
pub mod stand;
pub mod synth;
pub mod truth;
pub mod write;

use num_complex::Complex64;
use serde::Serialize;

use self::block::{BlockDrive, block_outputs, draw_block, draw_effect};
use self::effect::{Block, EffectSpec};
use self::fault::FaultSpec;
use self::regime::Regime;
use self::stand::StandImperfections;
use self::synth::{Grid, resonant_lowpass};
use self::truth::{EffectTruth, ServoTruth, Truth};
use crate::fourier::fast_len;
use crate::rng::Rng;
use crate::stand::kinematics::EulerSeries;

/// Padding of the synthesis grid on each side of the recorded window, s.
pub const PAD_S: f64 = 5.0;
/// Standard gravity, m/s^2.
pub const G_STANDARD: f64 = 9.806_65;
/// Fewest samples a simulated run may have.
pub const MIN_SAMPLES: usize = 256;
/// Most samples a simulated run may have (about 4.6 hours at 1 kHz).
pub const MAX_SAMPLES: usize = 1 << 24;

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    /// Flight regime of the program.
    pub regime: Regime,
    /// Recorded duration, s.
    pub duration_s: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Seed of every random draw.
    pub seed: u64,
    /// Effects to hide in the blocks.
    pub effects: Vec<EffectSpec>,
    /// Blocks mounted (at least one).
    pub blocks: Vec<Block>,
    /// Imperfections of the stand's angle measurement (none by default).
    pub stand: StandImperfections,
    /// Recording faults to inject into the finished recording, in order (none by default).
    pub faults: Vec<FaultSpec>,
    /// The sensors' noise beyond the drawn default.
    pub sensor_noise: SensorNoiseOptions,
    /// A vibration tone's frequency and when it is on, instead of the drawn defaults.
    pub tone: ToneOptions,
    /// Sines added to the programme (none by default).
    pub sines: Vec<sines::ProgramSine>,
    /// A second-order Butterworth low-pass at this corner (Hz) on both blocks' outputs, a
    /// sensor's anti-alias filter (none by default).
    pub sensor_filter_hz: Option<f64>,
}

/// How a hidden `vibration_tone` is made (`simulate --tone-hz`, `--tone-gate`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToneOptions {
    /// Its frequency, Hz (drawn in 25-38 Hz when `None`).
    pub frequency_hz: Option<f64>,
    /// When it is on.
    pub gate: truth::ToneGate,
}

/// Changes to the sensors' drawn noise (white plus a first-order coloured part by default), for
/// runs whose noise terms have closed forms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SensorNoiseOptions {
    /// Only the white part: no coloured part.
    pub white_only: bool,
    /// A rate (acceleration) random walk `K` on every output channel of both blocks, in each
    /// block's output units per s per sqrt(s) (Allan variance `K^2 tau / 3`).
    pub random_walk: f64,
}

impl SimConfig {
    /// A run of `regime` with the defaults: 300 s at 500 Hz, seed 1, both blocks, no effects.
    #[must_use]
    pub fn new(regime: Regime) -> Self {
        Self {
            regime,
            duration_s: 300.0,
            rate_hz: 500.0,
            seed: 1,
            effects: Vec::new(),
            blocks: Block::BOTH.to_vec(),
            stand: StandImperfections::default(),
            faults: Vec::new(),
            sensor_noise: SensorNoiseOptions::default(),
            tone: ToneOptions::default(),
            sines: Vec::new(),
            sensor_filter_hz: None,
        }
    }
}

/// Why a configuration cannot be simulated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// Duration not positive and finite.
    #[error("duration {0} s is not a positive number")]
    BadDuration(f64),
    /// Rate not positive and finite.
    #[error("sample rate {0} Hz is not a positive number")]
    BadRate(f64),
    /// Too few or too many samples.
    #[error("{samples} samples is outside the simulator's range {min}..={max} (duration x rate)")]
    SampleCount {
        /// Requested samples.
        samples: f64,
        /// Minimum.
        min: usize,
        /// Maximum.
        max: usize,
    },
    /// The rate cannot carry the stand's motion (which reaches about 60 Hz).
    #[error("sample rate {0} Hz is too low for the stand's motion (at least 150 Hz)")]
    RateTooLow(f64),
    /// No block mounted.
    #[error("no sensor block to simulate")]
    NoBlock,
    /// A tone frequency outside (0, Nyquist) or a gate time that is not a positive number.
    #[error("vibration tone: {0}")]
    BadTone(String),
    /// A programme sine at or above the Nyquist frequency.
    #[error("programme sine {frequency_hz} Hz is not below the Nyquist frequency {nyquist_hz} Hz")]
    SineAboveNyquist {
        /// The sine's frequency, Hz.
        frequency_hz: f64,
        /// Half the sample rate, Hz.
        nyquist_hz: f64,
    },
    /// An effect asks for a block that is not mounted.
    #[error("effect '{effect}' needs the {block} block, which is not simulated")]
    EffectWithoutBlock {
        /// Effect id.
        effect: &'static str,
        /// Block name.
        block: &'static str,
    },
    /// A fault asks for a channel it cannot go to.
    #[error("fault in channel '{channel}': {why}")]
    FaultChannel {
        /// The channel's name.
        channel: &'static str,
        /// Why not.
        why: &'static str,
    },
}

/// The sidecar fields the simulator writes beyond the run format's (its hidden truth, which only
/// tests read; [`SimSidecar::truth`]): the loader ignores them without a notice.
pub const EXTRA_SIDECAR_FIELDS: [&str; 1] = ["truth"];

/// The sidecar the simulator writes (contract section 2, plus `"truth"`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SimSidecar {
    /// Always `"stand-run/1"`.
    pub format: &'static str,
    /// Regime name.
    pub regime: String,
    /// Gravity used, m/s^2.
    pub g_mps2: f64,
    /// Declared accelerometer lever arm, m.
    pub accel_lever_arm_m: [f64; 3],
    /// Declared gyro lever arm, m.
    pub gyro_lever_arm_m: [f64; 3],
    /// Standard deviation of one angle sample's noise, quantisation included, rad.
    pub angle_noise_rad: f64,
    /// Free text.
    pub notes: String,
    /// What was simulated (tests only).
    pub truth: Truth,
}

/// A simulated recording.
#[derive(Clone, Debug)]
pub struct SimulatedRun {
    /// Sample times, s (from 0).
    pub time_s: Vec<f64>,
    /// Measured angles `[roll, yaw, pitch]`, rad (noisy, quantised).
    pub angles: [Vec<f64>; 3],
    /// Gyro outputs, rad/s.
    pub gyro: Option<[Vec<f64>; 3]>,
    /// Accelerometer outputs, m/s^2.
    pub accel: Option<[Vec<f64>; 3]>,
    /// The sidecar, truth included.
    pub sidecar: SimSidecar,
    /// The platform's true motion at the sample times (tests compare the observer with it).
    pub true_motion: EulerSeries,
}

const DECLARED_ACCEL_LEVER_ARM_M: [f64; 3] = [0.30, 0.12, 0.0];
const GYRO_LEVER_ARM_M: [f64; 3] = [0.10, 0.05, 0.02];
const ANGLE_WHITE_NOISE_RAD: f64 = 1.0e-5;
const SERVO: ServoTruth = ServoTruth {
    natural_hz: 35.0,
    damping: 0.7,
    jitter_rms_rad: 4.0e-6,
};

fn validate(config: &SimConfig) -> Result<usize, SimError> {
    if !(config.duration_s.is_finite() && config.duration_s > 0.0) {
        return Err(SimError::BadDuration(config.duration_s));
    }
    if !(config.rate_hz.is_finite() && config.rate_hz > 0.0) {
        return Err(SimError::BadRate(config.rate_hz));
    }
    if config.rate_hz < 150.0 {
        return Err(SimError::RateTooLow(config.rate_hz));
    }
    let samples = (config.duration_s * config.rate_hz).round();
    if !(samples >= MIN_SAMPLES as f64 && samples <= MAX_SAMPLES as f64) {
        return Err(SimError::SampleCount {
            samples,
            min: MIN_SAMPLES,
            max: MAX_SAMPLES,
        });
    }
    if config.blocks.is_empty() {
        return Err(SimError::NoBlock);
    }
    if let Some(f) = config.tone.frequency_hz
        && !(f.is_finite() && f > 0.0 && f < 0.5 * config.rate_hz)
    {
        return Err(SimError::BadTone(format!(
            "frequency {f} Hz is not between 0 and the Nyquist frequency {} Hz",
            0.5 * config.rate_hz
        )));
    }
    if let Some(sine) = config
        .sines
        .iter()
        .find(|s| s.frequency_hz >= 0.5 * config.rate_hz)
    {
        return Err(SimError::SineAboveNyquist {
            frequency_hz: sine.frequency_hz,
            nyquist_hz: 0.5 * config.rate_hz,
        });
    }
    let positive = |v: f64| v.is_finite() && v > 0.0;
    match config.tone.gate {
        truth::ToneGate::From { start_s } if !(start_s.is_finite() && start_s >= 0.0) => {
            return Err(SimError::BadTone(format!(
                "switch-on time {start_s} s is not a number >= 0"
            )));
        }
        truth::ToneGate::Pulsed { on_s, off_s } if !(positive(on_s) && positive(off_s)) => {
            return Err(SimError::BadTone(format!(
                "on {on_s} s and off {off_s} s must be positive"
            )));
        }
        _ => {}
    }
    for spec in &config.effects {
        for b in &spec.blocks {
            if !config.blocks.contains(b) {
                return Err(SimError::EffectWithoutBlock {
                    effect: spec.effect.id(),
                    block: b.name(),
                });
            }
        }
    }
    Ok(samples as usize)
}

/// Simulates a stand run.
///
/// # Errors
/// Fails if the duration or rate is not a positive number, the rate is below 150 Hz, the run would
/// have fewer than [`MIN_SAMPLES`] or more than [`MAX_SAMPLES`] samples, no block is mounted, or an
/// effect names a block that is not mounted.
pub fn simulate(config: &SimConfig) -> Result<SimulatedRun, SimError> {
    let n = validate(config)?;
    let fs = config.rate_hz;
    let pad = (PAD_S * fs).round() as usize;
    let mut grid = Grid::new(fast_len(n + 2 * pad), fs);
    let root = Rng::new(config.seed);
    let motion = platform_motion(&mut grid, config.regime, &config.sines, &mut root.fork(1));

    let mut accel_lever_arm = DECLARED_ACCEL_LEVER_ARM_M;
    let mut blocks_truth = Vec::new();
    let grid_time: Vec<f64> = (0..grid.fft.len())
        .map(|i| (i as f64 - pad as f64) / fs)
        .collect();
    let gyro_input = motion.body_rates();
    for (index, &block) in Block::BOTH.iter().enumerate() {
        if !config.blocks.contains(&block) {
            continue;
        }
        let mut rng = root.fork(10 + index as u64);
        let mut truth = draw_block(block, &mut rng);
        truth.anti_alias_hz = config.sensor_filter_hz;
        if config.sensor_noise.white_only {
            truth.noise.coloured_asd = [0.0; 3];
        }
        truth.noise.random_walk = [config.sensor_noise.random_walk; 3];
        let rms_probe = match block {
            Block::Gyro => &gyro_input,
            Block::Accel => &motion.specific_forces(DECLARED_ACCEL_LEVER_ARM_M, G_STANDARD),
        };
        let input_rms = rms_probe
            .each_ref()
            .map(|c| (c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64).sqrt());
        for spec in config.effects.iter().filter(|s| s.blocks.contains(&block)) {
            let mut e = draw_effect(spec.effect, block, spec.scale, input_rms, &mut rng);
            if let EffectTruth::VibrationTone {
                frequency_hz, gate, ..
            } = &mut e
            {
                *frequency_hz = config.tone.frequency_hz.unwrap_or(*frequency_hz);
                *gate = config.tone.gate;
            }
            if let EffectTruth::LeverArmError { offset_m } = e {
                accel_lever_arm = [0, 1, 2].map(|k| DECLARED_ACCEL_LEVER_ARM_M[k] + offset_m[k]);
            }
            truth.effects.push(e);
        }
        blocks_truth.push((block, truth));
    }

    let force_at_gyro = motion.specific_forces(GYRO_LEVER_ARM_M, G_STANDARD);
    let accel_input = motion.specific_forces(accel_lever_arm, G_STANDARD);
    let window = |v: &[f64]| v[pad..pad + n].to_vec();
    let mut gyro = None;
    let mut accel = None;
    let (mut gyro_truth, mut accel_truth) = (None, None);
    for (index, (block, truth)) in blocks_truth.into_iter().enumerate() {
        // Noise has its own stream, so adding an effect changes nothing else in the run.
        let mut rng = root.fork(20 + index as u64);
        let input = if block == Block::Gyro {
            &gyro_input
        } else {
            &accel_input
        };
        let drive = BlockDrive {
            input,
            force_at_block: &force_at_gyro,
            time_s: &grid_time,
        };
        let out = block_outputs(&mut grid, &truth, &drive, &mut rng)
            .each_ref()
            .map(|c| window(c));
        if block == Block::Gyro {
            gyro = Some(out);
            gyro_truth = Some(truth);
        } else {
            accel = Some(out);
            accel_truth = Some(truth);
        }
    }

    let quantum = 2.0 * std::f64::consts::PI / f64::from(1u32 << 22);
    let mut noise_rng = root.fork(2);
    let mut stand_rng = root.fork(3);
    let measured: [Vec<f64>; 3] = std::array::from_fn(|axis| {
        stand::measured_angle(&mut grid, &motion.angle[axis], &config.stand, &mut stand_rng)
    });
    let angles = measured.each_ref().map(|a| {
        window(a)
            .iter()
            .map(|v| ((v + ANGLE_WHITE_NOISE_RAD * noise_rng.normal()) / quantum).round() * quantum)
            .collect()
    });
    let true_motion = EulerSeries {
        angle: motion.angle.each_ref().map(|c| window(c)),
        rate: motion.rate.each_ref().map(|c| window(c)),
        accel: motion.accel.each_ref().map(|c| window(c)),
    };
    let truth = Truth {
        seed: config.seed,
        regime: config.regime.name().to_owned(),
        angle_white_noise_rad: ANGLE_WHITE_NOISE_RAD,
        angle_quantum_rad: quantum,
        servo: SERVO,
        accel_lever_arm_true_m: accel_lever_arm,
        gyro: gyro_truth,
        accel: accel_truth,
        stand: config.stand,
        faults: Vec::new(),
    };
    let sidecar = SimSidecar {
        format: "stand-run/1",
        regime: config.regime.name().to_owned(),
        g_mps2: G_STANDARD,
        accel_lever_arm_m: DECLARED_ACCEL_LEVER_ARM_M,
        gyro_lever_arm_m: GYRO_LEVER_ARM_M,
        angle_noise_rad: (ANGLE_WHITE_NOISE_RAD.powi(2) + quantum * quantum / 12.0).sqrt(),
        notes: notes(config),
        truth,
    };
    let mut run = SimulatedRun {
        time_s: (0..n).map(|i| i as f64 / fs).collect(),
        angles,
        gyro,
        accel,
        sidecar,
        true_motion,
    };
    for (k, &spec) in config.faults.iter().enumerate() {
        let truth = fault::inject(&mut run, spec, &mut root.fork(40 + k as u64))?;
        run.sidecar.truth.faults.push(truth);
    }
    Ok(run)
}

fn notes(config: &SimConfig) -> String {
    let effects: Vec<String> = config
        .effects
        .iter()
        .map(|s| {
            format!(
                "{}:{}@{}",
                s.effect.id(),
                s.blocks.iter().map(|b| b.name()).collect::<Vec<_>>().join("+"),
                s.scale
            )
        })
        .collect();
    let faults = if config.faults.is_empty() {
        String::new()
    } else {
        format!(
            ", {} recording fault(s) injected (see truth.faults)",
            config.faults.len()
        )
    };
    let sines = if config.sines.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = config.sines.iter().map(ToString::to_string).collect();
        format!(", programme sines [{}] (axis:Hz:deg)", list.join(", "))
    };
    format!(
        "simulated by imu-attest {}: regime {}, {} s at {} Hz, seed {}, effects [{}]{faults}{sines}",
        env!("CARGO_PKG_VERSION"),
        config.regime.name(),
        config.duration_s,
        config.rate_hz,
        config.seed,
        effects.join(", ")
    )
}

/// The platform's true Euler motion on the whole grid: program modes through the servo, plus
/// tracking jitter.
fn platform_motion(
    grid: &mut Grid,
    regime: Regime,
    sines: &[sines::ProgramSine],
    rng: &mut Rng,
) -> EulerSeries {
    let bins = grid.omega.len();
    let mut program: [Vec<Complex64>; 3] = std::array::from_fn(|_| vec![Complex64::default(); bins]);
    for mode in regime.modes() {
        let shaped = grid.shape(&grid.white(rng), |f| resonant_lowpass(f, mode.f0_hz, mode.zeta));
        let scale = mode.rms_rad / grid.mean_square(&shaped).sqrt().max(f64::MIN_POSITIVE);
        for (axis, p) in program.iter_mut().enumerate() {
            let g = mode.axis_gain(axis) * scale;
            p.iter_mut().zip(&shaped).for_each(|(pv, s)| *pv += s * g);
        }
    }
    for sine in sines {
        sines::add(grid, &mut program, sine);
    }
    let mut motion = EulerSeries::default();
    for axis in 0..3 {
        let servo = grid.shape(&program[axis], |f| {
            resonant_lowpass(f, SERVO.natural_hz, SERVO.damping)
        });
        // Tracking jitter peaks near 25 Hz and is rolled off by the platform's inertia above 40 Hz,
        // so the angular acceleration it causes is band-limited too.
        let jitter = grid.shape(&grid.white(rng), |f| {
            resonant_lowpass(f, 25.0, 0.5) * resonant_lowpass(f, 40.0, 0.7)
        });
        let jitter_scale = SERVO.jitter_rms_rad / grid.mean_square(&jitter).sqrt().max(f64::MIN_POSITIVE);
        let angle: Vec<Complex64> = servo
            .iter()
            .zip(&jitter)
            .map(|(s, j)| s + j * jitter_scale)
            .collect();
        motion.rate[axis] = grid.fft.inverse(grid.derivative(&angle, 1));
        motion.accel[axis] = grid.fft.inverse(grid.derivative(&angle, 2));
        motion.angle[axis] = grid.fft.inverse(angle);
    }
    motion
}

#[cfg(test)]
#[path = "sim_tests.rs"]
mod tests;
