//! Recording faults (issue 14): glitches, held samples and clipping in a loaded run's channels,
//! found by pure functions over the columns. Wrapped angles are the loader's business
//! (`run::wrap`): they are unwrapped, or refused, before a [`Run`] exists.
//!
//! # Contracts
//! - **Input**: a loaded [`Run`] (finite columns, at least 16 samples). Nothing is modified.
//! - **Empty or short channels**: too short to judge (fewer than 21 samples for glitches, one
//!   [`robust::BLOCK`] gives the local scales) find nothing; never a panic.
//! - **Units**: times in s from the run's own `t` column (not from 0); sizes and levels in the
//!   channel's units (rad, rad/s, m/s^2, see [`Channel::unit`]).
//! - **Order**: by channel in the run format's order (roll, yaw, pitch, gx .. az), then glitches
//!   in time order, held samples, clipping at the maximum, at the minimum.
//!
//! Thresholds (each module documents its rule): a glitch is more than
//! [`glitch::THRESHOLD`] (12) local robust standard deviations off its neighbours' straight line,
//! 1-3 samples long, with nothing above [`glitch::ISOLATED`] (5) left within 6 samples; held
//! samples are repeats beyond chance by more than 0.5 % of the samples where the channel moves,
//! or a run of 5; clipping is two or more flat tops of 3 or more samples at an extreme.
//! On the three real BROAD runs (`tests/data/real`) nothing is found; their finger taps ring for
//! 10 or more samples and are not isolated.

mod channel;
pub mod glitch;
pub mod hold;
pub mod robust;

use std::fmt;

use serde::{Deserialize, Serialize};

pub use channel::Channel;

use crate::run::Run;

/// Which extreme of a channel is clipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// The maximum.
    Max,
    /// The minimum.
    Min,
}

/// A fault of the recording itself, found in one channel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RecordingFault {
    /// An isolated outlier of 1-3 samples.
    Glitch {
        /// The channel.
        channel: Channel,
        /// Time of its first sample, s (the run's `t`).
        time_s: f64,
        /// 0-based index of its first sample (file line = index + 2).
        sample: usize,
        /// Its length, samples.
        samples: usize,
        /// The largest departure from the straight line between its neighbours, channel units.
        size: f64,
    },
    /// Samples repeating the previous value beyond chance, as a logger dropping samples writes.
    HeldSamples {
        /// The channel.
        channel: Channel,
        /// Repeated samples where the channel moves.
        held: usize,
        /// Repeats expected there by chance (quantisation).
        expected: f64,
        /// Runs of repeats.
        runs: usize,
        /// The longest run, samples.
        longest: usize,
        /// Time of the first repeated sample, s.
        first_time_s: f64,
    },
    /// Flat tops at the channel's extreme value: the sensor's or the logger's range.
    Clipping {
        /// The channel.
        channel: Channel,
        /// Which extreme.
        side: Side,
        /// The extreme value, channel units.
        level: f64,
        /// Runs of 3 or more samples at the level.
        flat_tops: usize,
        /// Samples at the level.
        samples: usize,
        /// Time of the first sample at the level, s.
        first_time_s: f64,
    },
}

impl RecordingFault {
    /// Where it starts, s (the run's `t`).
    #[must_use]
    pub fn time_s(&self) -> f64 {
        match self {
            RecordingFault::Glitch { time_s, .. } => *time_s,
            RecordingFault::HeldSamples { first_time_s, .. }
            | RecordingFault::Clipping { first_time_s, .. } => *first_time_s,
        }
    }

    /// What it is, in two or three words ("glitch in gx").
    #[must_use]
    pub fn short_label(&self) -> String {
        let what = match self {
            RecordingFault::Glitch { .. } => "glitch",
            RecordingFault::HeldSamples { .. } => "held samples",
            RecordingFault::Clipping { .. } => "clipping",
        };
        format!("{what} in {}", self.channel().name())
    }

    /// Whether it spoils the channel's recording beyond repair: held samples or clipping (a
    /// glitch is bridged before the analysis). A gyro channel so spoilt is no witness of the
    /// angles' noise (`ident::session`: what its stale or flat samples miss of the motion would
    /// be read as the angles' noise, and every block's inputs shrunk by it), and the fault's
    /// words say so; that includes a dead start long enough to be reported.
    #[must_use]
    pub fn spoils_recording(&self) -> bool {
        !matches!(self, RecordingFault::Glitch { .. })
    }

    /// The channel the fault is in.
    #[must_use]
    pub fn channel(&self) -> Channel {
        match self {
            RecordingFault::Glitch { channel, .. }
            | RecordingFault::HeldSamples { channel, .. }
            | RecordingFault::Clipping { channel, .. } => *channel,
        }
    }
}

impl fmt::Display for RecordingFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecordingFault::Glitch {
                channel,
                time_s,
                sample,
                samples,
                size,
            } => write!(
                f,
                "glitch in {} at t = {time_s:.4} s (line {}, {samples} sample{}): {size:+.4e} {} off \
                 its neighbours",
                channel.name(),
                sample + 2,
                if *samples == 1 { "" } else { "s" },
                channel.unit()
            ),
            RecordingFault::HeldSamples {
                channel,
                held,
                expected,
                runs,
                longest,
                first_time_s,
            } => write!(
                f,
                "held samples in {}: {held} samples repeat the previous value ({expected:.0} expected \
                 by chance) in {runs} runs of up to {longest}, from t = {first_time_s:.4} s; results \
                 using {} are unreliable{}",
                channel.name(),
                channel.name(),
                no_witness(*channel)
            ),
            RecordingFault::Clipping {
                channel,
                side,
                level,
                flat_tops,
                samples,
                first_time_s,
            } => write!(
                f,
                "clipping in {}: {flat_tops} flat tops at its {} {level:.6e} {} ({samples} \
                 samples), from t = {first_time_s:.4} s; results using {} are unreliable{}",
                channel.name(),
                if *side == Side::Max { "maximum" } else { "minimum" },
                channel.unit(),
                channel.name(),
                no_witness(*channel)
            ),
        }
    }
}

/// What a held or clipped gyro channel costs the other block
/// ([`RecordingFault::spoils_recording`]): empty for the other channels.
fn no_witness(channel: Channel) -> &'static str {
    if channel.is_gyro() {
        "; the gyro is then no witness of the angles' noise, taken white for every block"
    } else {
        ""
    }
}

/// Every recording fault in `run`'s channels (see the module docs for the order).
#[must_use]
pub fn detect(run: &Run) -> Vec<RecordingFault> {
    Channel::ALL
        .into_iter()
        .filter_map(|c| c.values(run).map(|x| (c, x)))
        .flat_map(|(channel, x)| detect_channel(channel, &run.time_s, x))
        .collect()
}

/// The faults of one channel `x` sampled at `time_s` (same length).
#[must_use]
pub fn detect_channel(channel: Channel, time_s: &[f64], x: &[f64]) -> Vec<RecordingFault> {
    let t = |i: usize| time_s.get(i).copied().unwrap_or(f64::NAN);
    let mut faults: Vec<RecordingFault> = glitch::find_glitches(x)
        .into_iter()
        .map(|g| RecordingFault::Glitch {
            channel,
            time_s: t(g.start),
            sample: g.start,
            samples: g.samples,
            size: g.size,
        })
        .collect();
    let clips = hold::find_clipping(x);
    let levels: Vec<f64> = clips.iter().map(|c| c.level).collect();
    faults.extend(hold::find_held(x, &levels).map(|h| RecordingFault::HeldSamples {
        channel,
        held: h.held,
        expected: h.expected,
        runs: h.runs,
        longest: h.longest,
        first_time_s: t(h.first),
    }));
    faults.extend(clips.into_iter().map(|c| RecordingFault::Clipping {
        channel,
        side: if c.at_max { Side::Max } else { Side::Min },
        level: c.level,
        flat_tops: c.flat_tops,
        samples: c.samples,
        first_time_s: t(c.first),
    }));
    faults
}

#[cfg(test)]
mod tests;
