//! A block's identification signals: its input `u` computed from the observer's estimate of the
//! platform motion (never from any simulated truth), and its measured output `x`.
//!
//! Gyro block: `u` = body rate (rad/s), `x` = `gx, gy, gz`. Accelerometer block: `u` = specific
//! force at the sidecar's declared lever arm with the vertical channel g-compensated (m/s^2),
//! `x` = `ax, ay, az`. Isolated glitches (`faults::glitch`) are bridged by a straight line in the
//! identifier's copy: in the outputs here, in the angles before the observer
//! ([`crate::ident::session::Session::motion`]).

use crate::block::Block;
use crate::faults::glitch::{bridge_glitches, find_glitches};
use crate::run::Run;
use crate::stand::inputs::{ACCEL_INPUTS, GYRO_INPUTS, accel_input, gyro_input};
use crate::stand::kinematics::EulerSeries;

/// Output channel names of the gyro block (contract section 4).
pub const GYRO_OUTPUTS: [&str; 3] = ["gx", "gy", "gz"];
/// Output channel names of the accelerometer block (contract section 4).
pub const ACCEL_OUTPUTS: [&str; 3] = ["ax", "ay", "az"];

/// Input and output channel names of a block.
#[must_use]
pub fn channel_names(block: Block) -> ([&'static str; 3], [&'static str; 3]) {
    match block {
        Block::Gyro => (GYRO_INPUTS, GYRO_OUTPUTS),
        Block::Accel => (ACCEL_INPUTS, ACCEL_OUTPUTS),
    }
}

/// One block's input and output columns, same length and sample rate.
#[derive(Clone, Debug)]
pub struct BlockSignals {
    /// Which block.
    pub block: Block,
    /// Input `u`, columns x, y, z.
    pub input: [Vec<f64>; 3],
    /// Output `x`, channels 1..3.
    pub output: [Vec<f64>; 3],
}

/// `columns` with their isolated glitches bridged by a straight line: they would leak broadband
/// power into every Welch segment they touch (they are reported by `faults::detect` from the run
/// itself). The session applies it to the outputs and to the angles.
#[must_use]
pub fn bridged(mut columns: [Vec<f64>; 3]) -> [Vec<f64>; 3] {
    for x in &mut columns {
        let glitches = find_glitches(x);
        bridge_glitches(x, &glitches);
    }
    columns
}

/// The block's signals, or `None` when the run has no such block.
#[must_use]
pub fn block_signals(run: &Run, motion: &EulerSeries, block: Block) -> Option<BlockSignals> {
    let output = bridged(run.outputs(block)?.clone());
    let input = match block {
        Block::Gyro => gyro_input(motion),
        Block::Accel => accel_input(motion, run.sidecar.accel_lever_arm_m, run.sidecar.g_mps2),
    };
    Some(BlockSignals { block, input, output })
}
