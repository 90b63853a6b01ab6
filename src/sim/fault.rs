//! Recording faults the simulator injects (`simulate --fault KIND[:CHANNEL]`, issue 14), each at a
//! seeded random time, into the finished recording, and reported in the sidecar's
//! `"truth"."faults"` so the detectors (`crate::faults`, the loader's unwrapping) can be tested on
//! data where the fault is hidden. The default channel is `gx` (`yaw` for `wrap`).
//!
//! - `glitch`: 1-3 consecutive samples offset by 10-20 times the channel's RMS, either sign.
//! - `hold`: 2 % of the samples, in runs of 1-3, replaced by the value before them (a logger
//!   dropping samples).
//! - `clip`: the channel limited at one side to the level that its most extreme 0.3 % (or more,
//!   until there are two flat tops of 3 samples) of samples exceed.
//! - `wrap`: an angle written in [0, 2 pi) (wrapping at every zero crossing), with the file's
//!   7 significant digits.
//! - `slip`: the channel's stream (all three channels of its block, or the three angles) slips
//!   one sample late: from a time drawn between 30 % and 70 % of the run, each sample is written
//!   one row later (the sample there repeated, the last dropped), as a logger that stalls for one
//!   sample of one stream writes it. The delay steps by one sample period there
//!   ([`crate::ident::delay_step`]).
//!
//! Faults are drawn between 5 % and 95 % of the run (a slip between 30 % and 70 %). Units: the channel's (rad, rad/s, m/s^2), s.

use std::f64::consts::TAU;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{SimError, SimulatedRun};
use crate::faults::Channel;
use crate::rng::Rng;

/// A fault kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// Isolated outlier.
    Glitch,
    /// Held samples.
    Hold,
    /// Clipping at one extreme.
    Clip,
    /// An angle wrapped into [0, 2 pi).
    Wrap,
    /// One stream one sample late from a time on.
    Slip,
}

/// `KIND[:CHANNEL]` of `--fault`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaultSpec {
    /// What to inject.
    pub kind: FaultKind,
    /// Where (`None`: `gx`, or `yaw` for a wrap).
    pub channel: Option<Channel>,
}

impl FromStr for FaultSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, channel) = s.split_once(':').map_or((s, None), |(k, c)| (k, Some(c)));
        let kind = match kind {
            "glitch" => FaultKind::Glitch,
            "hold" => FaultKind::Hold,
            "clip" => FaultKind::Clip,
            "wrap" => FaultKind::Wrap,
            "slip" => FaultKind::Slip,
            other => {
                return Err(format!(
                    "unknown fault '{other}' (known: glitch, hold, clip, wrap, slip)"
                ));
            }
        };
        let channel = channel
            .map(|c| {
                Channel::from_name(c)
                    .ok_or_else(|| format!("unknown channel '{c}' (known: roll yaw pitch gx gy gz ax ay az)"))
            })
            .transpose()?;
        Ok(FaultSpec { kind, channel })
    }
}

/// What the simulator injected, in the sidecar's `"truth"."faults"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FaultTruth {
    /// Samples `sample..sample + samples` offset by `size`.
    Glitch {
        /// Channel.
        channel: Channel,
        /// Time of the first sample, s.
        time_s: f64,
        /// 0-based index of the first sample.
        sample: usize,
        /// Number of samples.
        samples: usize,
        /// Offset added, channel units.
        size: f64,
    },
    /// Samples replaced by their predecessor.
    Hold {
        /// Channel.
        channel: Channel,
        /// Samples held.
        held: usize,
        /// Time of the first held sample, s.
        first_time_s: f64,
        /// 0-based index of the first held sample.
        first_sample: usize,
    },
    /// The channel limited at `level`.
    Clip {
        /// Channel.
        channel: Channel,
        /// `"max"` or `"min"`.
        side: String,
        /// The limit, channel units.
        level: f64,
        /// Samples at the limit.
        samples: usize,
        /// Time of the first sample at the limit, s.
        first_time_s: f64,
        /// 0-based index of the first sample at the limit.
        first_sample: usize,
    },
    /// An angle written in [0, 2 pi).
    Wrap {
        /// Channel.
        channel: Channel,
        /// Wrapping steps.
        wraps: usize,
        /// 0-based index of the sample after the first wrap (file line = index + 2).
        first_sample: usize,
    },
    /// A stream written one sample late from `sample` on.
    Slip {
        /// The channels that slipped (a block's three, or the three angles).
        channels: [Channel; 3],
        /// Time of the first repeated sample, s.
        time_s: f64,
        /// 0-based index of the first repeated sample.
        sample: usize,
    },
}

/// Injects `spec` into `run` with draws from `rng`.
///
/// # Errors
/// [`SimError::FaultChannel`] when the channel is not simulated, or a wrap is asked of a channel
/// that is not an angle.
pub fn inject(run: &mut SimulatedRun, spec: FaultSpec, rng: &mut Rng) -> Result<FaultTruth, SimError> {
    let default = if spec.kind == FaultKind::Wrap {
        Channel::Yaw
    } else {
        Channel::Gx
    };
    let channel = spec.channel.unwrap_or(default);
    let refuse = |why: &'static str| SimError::FaultChannel {
        channel: channel.name(),
        why,
    };
    if spec.kind == FaultKind::Wrap && !channel.is_angle() {
        return Err(refuse("only an angle wraps"));
    }
    if spec.kind == FaultKind::Slip {
        return slip(run, channel, rng).ok_or_else(|| refuse("its block is not simulated"));
    }
    let i = channel as usize;
    let x = match i {
        0..3 => Some(&mut run.angles[i]),
        3..6 => run.gyro.as_mut().map(|g| &mut g[i - 3]),
        _ => run.accel.as_mut().map(|a| &mut a[i - 6]),
    }
    .ok_or_else(|| refuse("its block is not simulated"))?;
    let n = x.len();
    let at = |rng: &mut Rng| rng.uniform_in(0.05 * n as f64, 0.95 * n as f64) as usize;
    let t = &run.time_s;
    Ok(match spec.kind {
        FaultKind::Glitch => {
            let mean = x.iter().sum::<f64>() / n as f64;
            let rms = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
            let sample = at(rng);
            let samples = 1 + (rng.next_u64() % 3) as usize;
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            let size = sign * rng.uniform_in(10.0, 20.0) * rms;
            x[sample..sample + samples].iter_mut().for_each(|v| *v += size);
            FaultTruth::Glitch {
                channel,
                time_s: t[sample],
                sample,
                samples,
                size,
            }
        }
        FaultKind::Hold => {
            let mut held = vec![false; n];
            while held.iter().filter(|h| **h).count() < n / 50 {
                let start = at(rng);
                let len = 1 + (rng.next_u64() % 3) as usize;
                held[start..start + len].iter_mut().for_each(|h| *h = true);
            }
            for j in 1..n {
                if held[j] {
                    x[j] = x[j - 1];
                }
            }
            let first_sample = held.iter().position(|h| *h).unwrap_or_default();
            FaultTruth::Hold {
                channel,
                held: held.iter().filter(|h| **h).count(),
                first_time_s: t[first_sample],
                first_sample,
            }
        }
        FaultKind::Clip => clip(x, t, channel, rng.uniform() < 0.5),
        // Done above: a slip moves a whole stream.
        FaultKind::Slip => return Err(refuse("a slip moves its whole stream")),
        FaultKind::Wrap => {
            for v in x.iter_mut() {
                *v = v.rem_euclid(TAU);
            }
            let steps = || x.windows(2).map(|w| (w[1] - w[0]).abs() > std::f64::consts::PI);
            FaultTruth::Wrap {
                channel,
                wraps: steps().filter(|w| *w).count(),
                first_sample: steps().position(|w| w).map_or(0, |i| i + 1),
            }
        }
    })
}

/// Slips the stream of `channel` (its block's three channels, or the three angles) one sample
/// late from a time drawn between 30 % and 70 % of the run. `None` when the block is not
/// simulated.
fn slip(run: &mut SimulatedRun, channel: Channel, rng: &mut Rng) -> Option<FaultTruth> {
    let i = channel as usize;
    let (stream, channels) = match i {
        0..3 => (&mut run.angles, [Channel::Roll, Channel::Yaw, Channel::Pitch]),
        3..6 => (run.gyro.as_mut()?, [Channel::Gx, Channel::Gy, Channel::Gz]),
        _ => (run.accel.as_mut()?, [Channel::Ax, Channel::Ay, Channel::Az]),
    };
    let n = run.time_s.len();
    let sample = (rng.uniform_in(0.3 * n as f64, 0.7 * n as f64) as usize).max(1);
    for x in stream.iter_mut() {
        x.copy_within(sample - 1..n - 1, sample);
    }
    Some(FaultTruth::Slip {
        channels,
        time_s: run.time_s[sample],
        sample,
    })
}

/// Limits `x` at its top (or bottom) quantile, the smallest share from 0.3 % that gives two flat
/// tops of 3 samples.
fn clip(x: &mut [f64], t: &[f64], channel: Channel, at_max: bool) -> FaultTruth {
    let sign = if at_max { 1.0 } else { -1.0 };
    let mut sorted: Vec<f64> = x.iter().map(|v| sign * v).collect();
    sorted.sort_by(f64::total_cmp);
    let n = x.len();
    let mut level = sorted[n - 1];
    for share in [0.003, 0.005, 0.01, 0.02, 0.05] {
        level = sorted[n - 1 - (share * n as f64) as usize];
        let mut tops = 0;
        let mut run = 0;
        for v in x.iter().chain([f64::NAN].iter()) {
            if sign * v >= level {
                run += 1;
            } else {
                tops += usize::from(run >= 3);
                run = 0;
            }
        }
        if tops >= 2 {
            break;
        }
    }
    let first_sample = x.iter().position(|v| sign * v >= level).unwrap_or_default();
    let samples = x.iter().filter(|v| sign * **v >= level).count();
    for v in x.iter_mut() {
        *v = sign * (sign * *v).min(level);
    }
    FaultTruth::Clip {
        channel,
        side: if at_max { "max" } else { "min" }.to_owned(),
        level: sign * level,
        samples,
        first_time_s: t[first_sample],
        first_sample,
    }
}
