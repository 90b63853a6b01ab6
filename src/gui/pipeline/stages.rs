//! The stages' results and how each is computed from the one before.

use std::sync::Arc;

use super::display::{self, Spectra};
use super::{RunSummary, Series};
use crate::block::Block;
use crate::faults::Channel;
use crate::ident;
use crate::ident::signals::channel_names;
use crate::run::Run;
use crate::spectral::WelchSettings;
use crate::stand::inputs::{accel_input, differentiate, gyro_input};
use crate::stand::observer::{NoiseSource, ObserverEstimate};

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

/// A loaded run's summary and its measured columns, shared with the run (the core's pipeline
/// holds the same `Arc`).
#[must_use]
pub fn split_run(run: &Arc<Run>) -> (RunSummary, Measured) {
    let summary = RunSummary {
        file_name: run.source.file_name.clone(),
        path: run.source.path.clone(),
        regime: run.sidecar.regime.clone(),
        n_samples: run.len(),
        sample_rate_hz: run.sample_rate_hz,
        duration_s: run.duration_s(),
        start_s: run.time_s.first().copied().unwrap_or(0.0),
        blocks: run.blocks(),
        sha256: run.source.sha256.clone(),
        notices: run.notices.clone(),
        recording_faults: crate::faults::detect(run),
        run: run.clone(),
    };
    let column = |k: usize| Series::of_run(run, Channel::ALL[k]);
    let triple = |first: usize| [column(first), column(first + 1), column(first + 2)];
    let measured = Measured {
        angles: triple(0),
        gyro: run.gyro.is_some().then(|| triple(3)),
        accel: run.accel.is_some().then(|| triple(6)),
    };
    (summary, measured)
}

/// The observer's estimate as block inputs, with plain differentiation of the measured angles
/// for comparison.
#[must_use]
pub fn motion(estimate: &ObserverEstimate, measured: &Measured, run: &Run) -> Motion {
    let [r, y, p] = &measured.angles;
    let angles = [r.values(), y.values(), p.values()];
    let differentiated = differentiate(angles, run.sample_rate_hz);
    let sidecar = &run.sidecar;
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
    Motion {
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
    }
}

/// What the spectra tab draws from the identifier's own spectra of every block.
#[must_use]
pub fn spectra(core: Vec<(Block, Arc<ident::spectra::BlockSpectra>)>, welch: &WelchSettings) -> Spectra {
    let blocks = core
        .into_iter()
        .map(|(block, core)| {
            let (inputs, outputs) = channel_names(block);
            let names = [
                inputs[0], inputs[1], inputs[2], outputs[0], outputs[1], outputs[2],
            ];
            display::block_spectra(block, names, core)
        })
        .collect();
    Spectra {
        welch: *welch,
        blocks,
    }
}
