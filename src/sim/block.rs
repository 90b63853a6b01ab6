//! A sensor block on the platform: draws its true model from the seed and computes its outputs
//! from its true input on the synthesis grid.
//!
//! Output channel `i` is
//! `sum_j K_ij (L u_j)(t - tau - skew_i) + k2_i ud_i |ud_i| + (G f)(t - tau) + tone_i + noise_i + bias_i`,
//! where `L` is the optional lag times the optional anti-alias filter and `u_j` has passed the
//! optional mount resonance. Delays and linear filters are exact (frequency domain on a band-limited periodic signal). A clock drift
//! is applied last, as a time warp of the whole output (8-point Lagrange interpolation).

use num_complex::Complex64;

use super::effect::{Block, Effect};
use super::synth::{Grid, butterworth2, first_order_lowpass, resonant_lowpass};
use super::truth::{BlockTruth, EffectTruth, NoiseTruth};
use crate::interp::lagrange;
use crate::rng::Rng;

/// Draws a block's true model (without effects) from `rng`.
#[must_use]
pub fn draw_block(block: Block, rng: &mut Rng) -> BlockTruth {
    // (scale error, misalignment, delay range, bias, white ASD, coloured ASD, corner)
    let (scale, misalign, (tau_lo, tau_hi), bias, white, coloured, corner) = match block {
        Block::Gyro => (800e-6, 1.5e-3, (1.5e-3, 6.0e-3), 1e-4, 3.0e-5, 1.5e-4, 0.5),
        Block::Accel => (1500e-6, 2.0e-3, (0.5e-3, 4.0e-3), 0.02, 4.0e-4, 2.0e-3, 0.3),
    };
    let mut k = [[0.0; 3]; 3];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = if i == j {
                1.0 + rng.uniform_in(-scale, scale)
            } else {
                rng.uniform_in(-misalign, misalign)
            };
        }
    }
    let tau_s = rng.uniform_in(tau_lo, tau_hi);
    let bias = [0; 3].map(|_| rng.uniform_in(-bias, bias));
    let noise = NoiseTruth {
        white_asd: [0; 3].map(|_| white * rng.uniform_in(0.8, 1.25)),
        white_correlation: random_correlation(rng, 0.5),
        coloured_asd: [0; 3].map(|_| coloured * rng.uniform_in(0.8, 1.25)),
        coloured_correlation: random_correlation(rng, 0.7),
        coloured_corner_hz: corner,
        random_walk: [0.0; 3],
    };
    BlockTruth {
        k,
        tau_s,
        bias,
        noise,
        effects: Vec::new(),
        anti_alias_hz: None,
    }
}

/// A random correlation matrix `normalise((I + c R)(I + c R)^T)`, R uniform in [-1, 1].
fn random_correlation(rng: &mut Rng, coupling: f64) -> [[f64; 3]; 3] {
    let mut b = [[0.0; 3]; 3];
    for (i, row) in b.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = f64::from(u8::from(i == j)) + coupling * rng.uniform_in(-1.0, 1.0);
        }
    }
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|m| b[i][m] * b[j][m]).sum();
        }
    }
    let d = [c[0][0].sqrt(), c[1][1].sqrt(), c[2][2].sqrt()];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] /= d[i] * d[j];
        }
    }
    c
}

/// Lower Cholesky factor of a 3x3 positive-definite matrix (correlations drawn above are).
fn cholesky3(c: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s: f64 = (0..j).map(|m| l[i][m] * l[j][m]).sum();
            l[i][j] = if i == j {
                (c[i][i] - s).max(0.0).sqrt()
            } else {
                (c[i][j] - s) / l[j][j].max(f64::MIN_POSITIVE)
            };
        }
    }
    l
}

/// What a block needs to compute its outputs, all on the synthesis grid.
pub struct BlockDrive<'a> {
    /// The true input `u` (rate or specific force), columns x, y, z.
    pub input: &'a [Vec<f64>; 3],
    /// The specific force at the block (for g-sensitivity; the gyro block's own lever arm).
    pub force_at_block: &'a [Vec<f64>; 3],
    /// Time of every grid sample, s.
    pub time_s: &'a [f64],
}

/// Computes the block's outputs on the whole grid; noise draws come from `rng`.
pub fn block_outputs(
    grid: &mut Grid,
    truth: &BlockTruth,
    drive: &BlockDrive<'_>,
    rng: &mut Rng,
) -> [Vec<f64>; 3] {
    let mut u_spec: [Vec<Complex64>; 3] = drive.input.each_ref().map(|u| grid.fft.forward(u));
    let mut lag_s = None;
    let mut skew = [0.0; 3];
    for e in &truth.effects {
        match *e {
            EffectTruth::PlatformResonance {
                axis,
                frequency_hz,
                damping,
            } => {
                u_spec[axis] = grid.shape(&u_spec[axis], |f| resonant_lowpass(f, frequency_hz, damping));
            }
            EffectTruth::SensorLag { time_constant_s } => lag_s = Some(time_constant_s),
            EffectTruth::AxisTimeSkew { channel_delay_s } => skew = channel_delay_s,
            _ => {}
        }
    }
    // The block's own dynamics beyond its delay: a lag effect and an anti-alias filter.
    let dynamics = |f: f64| {
        let lag = lag_s.map_or(Complex64::from(1.0), |t| {
            first_order_lowpass(f, 1.0 / (2.0 * std::f64::consts::PI * t))
        });
        truth.anti_alias_hz.map_or(lag, |fc| lag * butterworth2(f, fc))
    };
    let mut out: [Vec<f64>; 3] = Default::default();
    for i in 0..3 {
        let mut x = vec![Complex64::default(); u_spec[0].len()];
        for (j, u) in u_spec.iter().enumerate() {
            x.iter_mut().zip(u).for_each(|(xi, uj)| *xi += uj * truth.k[i][j]);
        }
        let x = grid.shape(&grid.delay(&x, truth.tau_s + skew[i]), dynamics);
        out[i] = grid.fft.inverse(x);
    }
    for e in &truth.effects {
        match *e {
            EffectTruth::ScaleNonlinearity { k2 } => {
                for i in 0..3 {
                    let seen = grid.shape(&grid.delay(&u_spec[i], truth.tau_s + skew[i]), dynamics);
                    let ud = grid.fft.inverse(seen);
                    out[i]
                        .iter_mut()
                        .zip(&ud)
                        .for_each(|(x, u)| *x += k2[i] * u * u.abs());
                }
            }
            EffectTruth::GSensitivity { g_matrix } => {
                let fd: Vec<Vec<f64>> = drive
                    .force_at_block
                    .iter()
                    .map(|f| {
                        let spec = grid.fft.forward(f);
                        grid.fft.inverse(grid.delay(&spec, truth.tau_s))
                    })
                    .collect();
                for i in 0..3 {
                    for (n, x) in out[i].iter_mut().enumerate() {
                        *x += (0..3).map(|j| g_matrix[i][j] * fd[j][n]).sum::<f64>();
                    }
                }
            }
            EffectTruth::VibrationTone {
                frequency_hz,
                amplitude,
                phase_rad,
                gate,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency_hz;
                for i in 0..3 {
                    out[i]
                        .iter_mut()
                        .zip(drive.time_s)
                        .filter(|(_, t)| gate.is_on(**t))
                        .for_each(|(x, t)| *x += amplitude[i] * (w * t + phase_rad[i]).sin());
                }
            }
            _ => {}
        }
    }
    add_noise(grid, &truth.noise, &mut out, rng);
    for (col, b) in out.iter_mut().zip(truth.bias) {
        for x in col.iter_mut() {
            *x += b;
        }
    }
    for e in &truth.effects {
        if let EffectTruth::ClockDrift { drift_ppm } = *e {
            for col in &mut out {
                *col = clock_drifted(col, drive.time_s, drift_ppm * 1e-6);
            }
        }
    }
    out
}

/// `x` (on the grid `time_s`) as a block whose clock runs at `1 + drift` samples it: the sample
/// the block stamps `t` was taken at the stand's `t / (1 + drift)` (the clocks agree at `t = 0`,
/// the recording's start). The stand's rows are stamped by the stand, so the block's delay
/// grows by `drift` per second of the run.
fn clock_drifted(x: &[f64], time_s: &[f64], drift: f64) -> Vec<f64> {
    let (Some(&t0), Some(&t1)) = (time_s.first(), time_s.get(1)) else {
        return x.to_vec();
    };
    let rate = 1.0 / (t1 - t0);
    time_s
        .iter()
        .map(|t| lagrange(x, rate, t / (1.0 + drift) - t0))
        .collect()
}

/// Adds the cross-correlated coloured disturbance of [`NoiseTruth`].
fn add_noise(grid: &mut Grid, noise: &NoiseTruth, out: &mut [Vec<f64>; 3], rng: &mut Rng) {
    let lw = cholesky3(&noise.white_correlation);
    let lc = cholesky3(&noise.coloured_correlation);
    let xi_w: [Vec<Complex64>; 3] = [0; 3].map(|_| grid.white(rng));
    let xi_c: [Vec<Complex64>; 3] = [0; 3].map(|_| grid.white(rng));
    let corner = noise.coloured_corner_hz;
    for i in 0..3 {
        let mut spec = vec![Complex64::default(); xi_w[0].len()];
        for m in 0..=i {
            let (a, b) = (noise.white_asd[i] * lw[i][m], noise.coloured_asd[i] * lc[i][m]);
            spec.iter_mut().zip(&xi_w[m]).for_each(|(s, x)| *s += x * a);
            let coloured = grid.shape(&xi_c[m], |f| first_order_lowpass(f, corner) * b);
            spec.iter_mut().zip(&coloured).for_each(|(s, x)| *s += x);
        }
        let t = grid.fft.inverse(spec);
        out[i].iter_mut().zip(&t).for_each(|(x, n)| *x += n);
    }
    // The random walk in time (it is not periodic); drawn only when asked for, so that runs
    // without it keep their noise.
    let step = (1.0 / grid.fft.sample_rate_hz()).sqrt();
    for (col, &k) in out.iter_mut().zip(&noise.random_walk) {
        if k > 0.0 {
            let mut walk = 0.0;
            for x in col.iter_mut() {
                walk += k * step * rng.normal();
                *x += walk;
            }
        }
    }
}

/// The most damped `platform_resonance` drawn (a small `scale`): the catalogue's mode is lightly
/// damped, and one damped beyond 0.5 attenuates even at its own frequency, where the diagnosis no
/// longer names it (`diagnose::workflow`); 0.4 keeps a gain of 1.25 there.
pub const MAX_SIMULATED_DAMPING: f64 = 0.4;

/// Draws the size of `effect` on `block` (default size times `scale`). `input_rms` is the RMS of
/// the block's true input per axis (sizes of the quadratic term are relative to it).
#[must_use]
pub fn draw_effect(
    effect: Effect,
    block: Block,
    scale: f64,
    input_rms: [f64; 3],
    rng: &mut Rng,
) -> EffectTruth {
    let sign = |rng: &mut Rng| if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    let output_unit = match block {
        Block::Gyro => 1.0,
        Block::Accel => 10.0,
    };
    match effect {
        Effect::GSensitivity => {
            let mut g = [[0.0; 3]; 3];
            g.iter_mut()
                .flatten()
                .for_each(|v| *v = scale * 5e-4 * rng.uniform_in(-1.0, 1.0));
            EffectTruth::GSensitivity { g_matrix: g }
        }
        Effect::SensorLag => EffectTruth::SensorLag {
            time_constant_s: scale * 4e-3 * rng.uniform_in(0.8, 1.25),
        },
        // Stand side: not a sensor effect, never drawn (`EffectSpec` parses only `Effect::ALL`;
        // the stand's lag and band limit are `--stand real`, `--angle-latency`, `--angle-band-hz`,
        // `--angle-filter-hz`, `--angle-rate-hz`). A zero lag changes nothing.
        Effect::ReferenceLag | Effect::ReferenceBandLimit => EffectTruth::SensorLag { time_constant_s: 0.0 },
        Effect::AxisTimeSkew => {
            let mut d = [0.0, 1.2e-3, 0.8e-3].map(|v| scale * v * sign(rng));
            d.rotate_left((rng.next_u64() % 3) as usize);
            EffectTruth::AxisTimeSkew { channel_delay_s: d }
        }
        Effect::ScaleNonlinearity => EffectTruth::ScaleNonlinearity {
            k2: input_rms.map(|r| scale * 0.01 / r.max(1e-12) * sign(rng)),
        },
        Effect::VibrationTone => EffectTruth::VibrationTone {
            frequency_hz: rng.uniform_in(25.0, 38.0),
            amplitude: [0; 3].map(|_| scale * 5e-4 * output_unit * rng.uniform_in(0.3, 1.0)),
            phase_rad: [0; 3].map(|_| rng.uniform_in(0.0, 2.0 * std::f64::consts::PI)),
            gate: super::truth::ToneGate::Continuous,
        },
        Effect::LeverArmError => EffectTruth::LeverArmError {
            offset_m: [0.02, -0.015, 0.03].map(|v| scale * v * rng.uniform_in(0.7, 1.3)),
        },
        Effect::PlatformResonance => EffectTruth::PlatformResonance {
            axis: (rng.next_u64() % 3) as usize,
            frequency_hz: rng.uniform_in(18.0, 32.0),
            damping: (0.05 / scale).min(MAX_SIMULATED_DAMPING),
        },
        Effect::ClockDrift => EffectTruth::ClockDrift {
            drift_ppm: scale * 50.0 * rng.uniform_in(0.8, 1.25) * sign(rng),
        },
    }
}
