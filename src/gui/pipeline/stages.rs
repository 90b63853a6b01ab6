//! The stages' results and how each is computed from the one before.

use std::sync::Arc;

use super::display::{self, Spectra};
use super::{RunSummary, Series};
use crate::block::Block;
use crate::ident;
use crate::ident::signals::{BlockSignals, channel_names};
use crate::run::{Run, Sidecar};
use crate::spectral::{SpectralError, WelchPlanner, WelchSettings};
use crate::stand::inputs::{accel_input, differentiate, gyro_input};
use crate::stand::observer::{NoiseSource, ObserverError, ObserverSettings, observe};

/// Measured columns of a run: angles and the blocks' outputs.
#[derive(Debug)]
pub struct Measured {
    /// `[roll, yaw, pitch]`, rad.
    pub angles: [Series; 3],
    /// `[gx, gy, gz]`, rad/s.
    pub gyro: Option<[Series; 3]>,
    /// `[ax, ay, az]`, m/s^2.
    pub accel: Option<[Series; 3]>,
}

impl Measured {
    /// A block's outputs, if present.
    #[must_use]
    pub fn outputs(&self, block: Block) -> Option<&[Series; 3]> {
        match block {
            Block::Gyro => self.gyro.as_ref(),
            Block::Accel => self.accel.as_ref(),
        }
    }
}

/// The observer's estimate turned into block inputs, with plain differentiation for comparison.
#[derive(Debug)]
pub struct Motion {
    /// Angle noise used per axis, rad.
    pub angle_noise_rad: [f64; 3],
    /// The noise level came from the sidecar (else estimated from the data).
    pub noise_declared: bool,
    /// Gyro input `[wx, wy, wz]` from the observer, rad/s.
    pub body_rate: [Series; 3],
    /// The same from central differences of the measured angles.
    pub body_rate_differentiated: [Series; 3],
    /// Accelerometer input `[fx, fy, fz]` at the declared lever arm from the observer, m/s^2.
    pub specific_force: [Series; 3],
    /// The same from central differences.
    pub specific_force_differentiated: [Series; 3],
}

impl Motion {
    /// A block's inputs from the observer.
    #[must_use]
    pub fn inputs(&self, block: Block) -> &[Series; 3] {
        match block {
            Block::Gyro => &self.body_rate,
            Block::Accel => &self.specific_force,
        }
    }
}

/// Splits a loaded run into its summary and its plotted columns (moved, not copied).
#[must_use]
pub fn split_run(run: Run) -> (RunSummary, Measured, Sidecar) {
    let t0 = run.time_s.first().copied().unwrap_or(0.0);
    let dt = run.dt_s();
    let summary = RunSummary {
        file_name: run.source.file_name.clone(),
        path: run.source.path.clone(),
        regime: run.sidecar.regime.clone(),
        n_samples: run.len(),
        sample_rate_hz: run.sample_rate_hz,
        duration_s: run.duration_s(),
        blocks: run.blocks(),
        sha256: run.source.sha256.clone(),
        notices: run.notices.clone(),
        recording_faults: crate::faults::detect(&run),
    };
    let triple = |names: [&str; 3], cols: [Vec<f64>; 3]| {
        let [a, b, c] = cols;
        [
            Series::new(names[0], t0, dt, a),
            Series::new(names[1], t0, dt, b),
            Series::new(names[2], t0, dt, c),
        ]
    };
    let measured = Measured {
        angles: triple(["roll", "yaw", "pitch"], run.angles),
        gyro: run.gyro.map(|g| triple(["gx", "gy", "gz"], g)),
        accel: run.accel.map(|a| triple(["ax", "ay", "az"], a)),
    };
    (summary, measured, run.sidecar)
}

/// Observer, block inputs, and plain differentiation for comparison.
///
/// # Errors
/// What the observer refuses (too short a run, a bad declared noise).
pub fn motion(measured: &Measured, sample_rate_hz: f64, sidecar: &Sidecar) -> Result<Motion, ObserverError> {
    let [r, y, p] = &measured.angles;
    let angles = [r.values.as_slice(), y.values.as_slice(), p.values.as_slice()];
    let settings = ObserverSettings {
        angle_noise_rad: sidecar.angle_noise_rad,
        ..ObserverSettings::default()
    };
    let estimate = observe(angles, sample_rate_hz, &settings)?;
    let differentiated = differentiate(angles, sample_rate_hz);
    let (t0, dt) = (r.t0, r.dt);
    let triple = |names: [&str; 3], cols: [Vec<f64>; 3]| {
        let [a, b, c] = cols;
        [
            Series::new(names[0], t0, dt, a),
            Series::new(names[1], t0, dt, b),
            Series::new(names[2], t0, dt, c),
        ]
    };
    let (lever, g) = (sidecar.accel_lever_arm_m, sidecar.g_mps2);
    Ok(Motion {
        angle_noise_rad: estimate.angle_noise_rad,
        noise_declared: estimate.noise_source == NoiseSource::Declared,
        body_rate: triple(["wx", "wy", "wz"], gyro_input(&estimate.euler)),
        body_rate_differentiated: triple(
            ["wx (diff)", "wy (diff)", "wz (diff)"],
            gyro_input(&differentiated),
        ),
        specific_force: triple(["fx", "fy", "fz"], accel_input(&estimate.euler, lever, g)),
        specific_force_differentiated: triple(
            ["fx (diff)", "fy (diff)", "fz (diff)"],
            accel_input(&differentiated, lever, g),
        ),
    })
}

/// The identifier's Welch spectra of every block present (inputs from the observer, outputs as
/// measured), with what the spectra tab draws.
///
/// # Errors
/// What Welch refuses (segment longer than the run, bad overlap, ...).
pub fn spectra(
    planner: &mut WelchPlanner,
    measured: &Measured,
    motion: &Motion,
    sample_rate_hz: f64,
    welch: &WelchSettings,
) -> Result<Spectra, SpectralError> {
    let mut blocks = Vec::new();
    for block in Block::BOTH {
        let Some(outputs) = measured.outputs(block) else {
            continue;
        };
        let column = |s: &Series| s.values.clone();
        let signals = BlockSignals {
            block,
            input: motion.inputs(block).each_ref().map(column),
            output: ident::signals::bridged(outputs.each_ref().map(column)),
        };
        let core = ident::spectra::block_spectra(planner, &signals, sample_rate_hz, welch)?;
        let (inputs, outputs) = channel_names(block);
        let names = [
            inputs[0], inputs[1], inputs[2], outputs[0], outputs[1], outputs[2],
        ];
        blocks.push(display::block_spectra(block, names, Arc::new(core)));
    }
    Ok(Spectra {
        welch: *welch,
        blocks,
    })
}
