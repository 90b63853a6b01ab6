//! The gyro witness's delay behind the measured angles, per stretch of the record, and its drift
//! through a stretch (the gyro's clock against the angles'), for the coloured angle-noise model
//! ([`super::colour`]): a generalised cross-correlation weighted by the coherence above chance
//! ([`align`]), with the Cramér-Rao bound on the delay it finds.
//!
//! Units: delays in s (positive: the witness late), drifts in s per s. Spectra are the Hann-
//! windowed stretch's on a [`RecordFft`] grid. Bins with no power weigh nothing; a stretch with no
//! coherent bin gives an infinite deviation and no drift. NaN cannot arise from finite input.

use num_complex::Complex64;

use super::colour::BOUND_BAND_HZ;
use super::kinematics::euler_rate;
use super::observer::remove_line;
use crate::fourier::{RecordFft, fast_len};
use crate::spectral::Window;

/// The witness: the gyro's body rates `body` turned into Euler rates at the measured `angles`
/// (rad/s, axis order `[roll, yaw, pitch]`). Samples at gimbal lock (non-finite) become 0.
pub(super) fn witness_euler_rates(angles: [&[f64]; 3], body: [&[f64]; 3]) -> [Vec<f64>; 3] {
    euler_rates_of_axes(angles, body, [true; 3])
}

/// The Euler rates the body rates about the axes in `axes` make, the others taken as 0: the
/// witness ([`witness_euler_rates`]) with every axis, one body axis's part of it
/// ([`super::colour_split`]) with one. Samples at gimbal lock (non-finite) become 0.
pub(super) fn euler_rates_of_axes(angles: [&[f64]; 3], body: [&[f64]; 3], axes: [bool; 3]) -> [Vec<f64>; 3] {
    let n = angles[0].len().min(body[0].len());
    let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for i in 0..n {
        let rates = [0, 1, 2].map(|j| if axes[j] { body[j][i] } else { 0.0 });
        let r = euler_rate([angles[0][i], angles[1][i], angles[2][i]], rates);
        for a in 0..3 {
            out[a][i] = if r[a].is_finite() { r[a] } else { 0.0 };
        }
    }
    out
}

/// `x` times the (periodic) Hann window over its length, at the start of a zero buffer of `len`
/// samples.
pub(super) fn hann_windowed(x: &[f64], len: usize) -> Vec<f64> {
    let mut out: Vec<f64> = Window::Hann
        .coefficients(x.len())
        .iter()
        .zip(x)
        .map(|(w, v)| w * v)
        .collect();
    out.resize(len, 0.0);
    out
}

/// The witness as angles: integrated by trapezoids, its least-squares line removed.
pub(super) fn witness_angles(rates: &[f64], sample_rate_hz: f64) -> Vec<f64> {
    let mut angle = Vec::with_capacity(rates.len());
    let mut sum = 0.0;
    angle.push(sum);
    for pair in rates.windows(2) {
        sum += 0.5 * (pair[0] + pair[1]) / sample_rate_hz;
        angle.push(sum);
    }
    remove_line(&angle, sample_rate_hz).2
}

/// The angles' spectra on `fft`'s grid: each axis's least-squares line removed, Hann-windowed
/// ([`hann_windowed`]).
pub(super) fn angle_spectra(angles: [&[f64]; 3], fft: &mut RecordFft) -> [Vec<Complex64>; 3] {
    let rate = fft.sample_rate_hz();
    angles.map(|a| fft.forward(&hann_windowed(&remove_line(a, rate).2, fft.len())))
}

/// Independent bins in the window over which [`align`] smooths the coherency: enough for chance
/// to stay below [`align_weight`]'s level (0.48 at one false alarm in a hundred) where the two
/// signals are unrelated. A delay turns the phase across the window (the window is its width in
/// bins times the grid's spacing, about `1.6 ALIGN_INDEPENDENT / T` for a stretch of `T` s): at
/// the search's end, half a second, it shrinks a coherent bin's coherency by about a tenth on a
/// stretch of 25 s, nothing that brings it near chance.
const ALIGN_INDEPENDENT: f64 = 8.0;

/// The weight [`align`] gives a bin of squared coherency `coherency2` estimated over a window of
/// `independent` independent bins: how far it stands above what two unrelated signals reach
/// there, `((coherency2 - c0) / (1 - c0))_+`, `c0 = 1 - ALIGN_FALSE_ALARM^(1 / (independent - 1))`
/// the level they exceed with probability [`ALIGN_FALSE_ALARM`] (`P(coherency2 > x) = (1 - x)^(M -
/// 1)` for `M` independent bins of unrelated signals). Fewer than two independent bins: none.
fn align_weight(coherency2: f64, independent: f64) -> f64 {
    if independent <= 1.0 {
        return 0.0;
    }
    let c0 = 1.0 - ALIGN_FALSE_ALARM.powf(1.0 / (independent - 1.0));
    ((coherency2 - c0) / (1.0 - c0)).max(0.0)
}

/// How often two unrelated signals pass [`align_weight`]'s level in a bin: one bin in a hundred.
const ALIGN_FALSE_ALARM: f64 = 0.01;

/// Advances the witness's spectra `w` by its bulk delay behind the angles' `y`: the peak of their
/// summed cross-correlation with each bin divided by the two signals' smoothed power over
/// [`ALIGN_INDEPENDENT`] independent bins around it and weighted by how far their squared coherency there
/// stands above chance ([`align_weight`]; a generalised cross-correlation, "SCOT" with coherence
/// weighting), refined by a parabola. `independent_per_bin`: the independent bins per bin of the
/// transform (a Hann-windowed stretch of `n` samples on `len` bins: `2n / 3 / len`). A delay left
/// in would turn the phase across a smoothing window and leak motion into the unexplained part.
/// The plain cross-correlation is dominated by the slowest motion, whose peak is seconds wide: on
/// our simulator's approach runs with the angles 100 ms late it put the delay at 115-300 ms (the
/// gyro's `K` then 1.2-4.5 % off); weighted, every bin where the two agree counts alike and the
/// peak is as narrow as their common band allows. Weighted by the squared coherency itself, the
/// bins where the two are unrelated counted too: over a window of three or four independent bins
/// chance alone gives a squared coherency of about 0.3, and above the motion's band they
/// are most of the bins. On a real recording (the gyro 38.5 ms behind the motion capture, its
/// taps' broadband noise above 20 Hz) they outweighed the motion's band, the correlation's peaks
/// came 7 ms apart at nearly equal heights, and three of five stretches were aligned at 9.8,
/// -140.6 and 78.1 ms: their unexplained motion was taken for angle noise and the gyro's `K`
/// came out 3.4 % high, said by nothing. Returns the delay, s, and its standard deviation, s:
/// the Cramér-Rao bound for a delay between two signals of squared coherence `g` per independent
/// bin, `(sum 2 w^2 g / (1 - g))^-1/2` (Carter, 1987), with `g` the weight above chance (so the
/// bins chance fills do not count) capped at [`MAX_COHERENCE`]; the three axes' summed coherency
/// counts once, which errs on the wide side. A bound, reached where the peak is the right one.
pub(super) fn align(
    w: &mut [Vec<Complex64>; 3],
    y: &[Vec<Complex64>; 3],
    fft: &mut RecordFft,
    independent_per_bin: f64,
) -> (f64, f64) {
    let rate = fft.sample_rate_hz();
    let bins = fft.n_bins();
    let half = (ALIGN_INDEPENDENT / independent_per_bin / 2.0).ceil() as usize;
    let raw: Vec<Complex64> = (0..bins)
        .map(|k| (0..3).map(|a| y[a][k] * w[a][k].conj()).sum())
        .collect();
    let power = |x: &[Vec<Complex64>; 3], k: usize| (0..3).map(|a| x[a][k].norm_sqr()).sum::<f64>();
    // Prefix sums of the cross and of both powers, for the smoothed values at every bin.
    let mut sums = vec![(Complex64::default(), 0.0, 0.0); bins + 1];
    for k in 0..bins {
        let (c, py, pw) = sums[k];
        sums[k + 1] = (c + raw[k], py + power(y, k), pw + power(w, k));
    }
    // Fisher's information on the delay, s^-2 (below).
    let mut information = 0.0;
    let cross: Vec<Complex64> = (0..bins)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(bins));
            let (c, py, pw) = (
                sums[hi].0 - sums[lo].0,
                sums[hi].1 - sums[lo].1,
                sums[hi].2 - sums[lo].2,
            );
            let scale = (py * pw).sqrt();
            if k == 0 || !(scale > 0.0 && scale.is_finite()) {
                return Complex64::default();
            }
            let coherency = c.norm() / scale;
            let weight = align_weight(coherency * coherency, (hi - lo) as f64 * independent_per_bin);
            let omega = 2.0 * std::f64::consts::PI * fft.frequency_hz(k);
            let g = weight.min(MAX_COHERENCE);
            information += independent_per_bin * 2.0 * omega * omega * g / (1.0 - g);
            raw[k] * ((hi - lo) as f64 / scale) * weight
        })
        .collect();
    let correlation = fft.inverse(cross);
    let len = correlation.len();
    let max_lag = ((0.5 * rate) as usize).min(len / 2 - 1);
    let lag_of = |i: usize| {
        if i <= len / 2 {
            i as f64
        } else {
            i as f64 - len as f64
        }
    };
    let peak = (0..=max_lag)
        .chain(len - max_lag..len)
        .max_by(|&a, &b| correlation[a].total_cmp(&correlation[b]))
        .unwrap_or(0);
    let (before, after) = (correlation[(peak + len - 1) % len], correlation[(peak + 1) % len]);
    let curvature = before - 2.0 * correlation[peak] + after;
    let refine = if curvature < 0.0 {
        (0.5 * (before - after) / curvature).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    let delay_s = -(lag_of(peak) + refine) / rate;
    advance(w, delay_s, fft);
    (delay_s, information.sqrt().recip())
}

/// Advances spectra on `fft`'s grid by `delay_s` seconds (a phase turn per bin).
pub(super) fn advance(spectra: &mut [Vec<Complex64>], delay_s: f64, fft: &RecordFft) {
    for s in spectra {
        for (k, v) in s.iter_mut().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * fft.frequency_hz(k);
            *v *= Complex64::from_polar(1.0, omega * delay_s);
        }
    }
}

/// The largest squared coherency [`align`]'s information counts (`g / (1 - g)` grows without
/// bound as `g` nears 1, where the smoothed estimate is least sure of it).
const MAX_COHERENCE: f64 = 0.99;

/// The witness's delay behind the angles over a stretch (their spectra `y` on `fft`'s grid), from
/// the gyro's rates converted at the angles of the same instant, and its standard deviation, s
/// ([`align`]).
pub(super) fn first_delay(
    angles: [&[f64]; 3],
    body_rates: [&[f64]; 3],
    y: &[Vec<Complex64>; 3],
    fft: &mut RecordFft,
) -> (f64, f64) {
    let n = angles[0].len();
    let rate = fft.sample_rate_hz();
    let len = fft.len();
    let euler = witness_euler_rates(angles, body_rates);
    let mut w = euler.map(|r| fft.forward(&hann_windowed(&witness_angles(&r, rate), len)));
    let independent_per_bin = (2.0 * n as f64 / 3.0 / len as f64).min(1.0);
    align(&mut w, y, fft, independent_per_bin)
}

/// The phase a delay's change through a stretch must turn at the top of [`BOUND_BAND_HZ`] before
/// it is followed ([`drift`]): 0.05 rad, a change of 0.2 ms at 40 Hz. Below it the witness's
/// lost coherence (about the turn squared over 12) is under a thousandth (the colour model's
/// `MIN_SHARE`).
const DRIFT_PHASE_RAD: f64 = 0.05;

/// How many of its standard deviations the change of delay between a stretch's halves must be
/// before [`drift`] reads a drift from it: 5, about one false drift in two million stretches of a
/// steady gyro where the delays' errors are Gaussian at their bound.
const DRIFT_SIGMAS: f64 = 5.0;

/// The change of the witness's delay per second through a stretch (its clock drifts against the
/// angles'): the delays of the stretch's two halves ([`first_delay`] on each) apart, over the time
/// between their middles; 0 where the change over the stretch turns the phase at the top of
/// [`BOUND_BAND_HZ`] by less than [`DRIFT_PHASE_RAD`] or is within [`DRIFT_SIGMAS`] of its
/// standard deviation ([`align`]'s bound on each half's). A constant delay left on a drifting
/// witness turns its phase through the stretch, the coherence falls by about the turn squared
/// over 12, and that share of the angles' power was taken for their noise: the observer shrank
/// the inputs by it, most at high frequency, and a gyro drifting by 55 ppm gave the
/// accelerometer a false `lever_arm_error` of 1.4-3.3 mm (approach, 300 s, seeds 2 and 3;
/// README, 29 Nov).
pub(super) fn drift(angles: [&[f64]; 3], body_rates: [&[f64]; 3], rate: f64) -> f64 {
    let n = angles[0].len();
    let half = n / 2;
    if half < 64 {
        return 0.0;
    }
    let delays = [0..half, half..2 * half].map(|r| {
        let a = angles.map(|x| &x[r.clone()]);
        let w = body_rates.map(|x| &x[r.clone()]);
        let mut fft = RecordFft::new(fast_len(half), rate);
        let y = angle_spectra(a, &mut fft);
        first_delay(a, w, &y, &mut fft)
    });
    let change = delays[1].0 - delays[0].0;
    let change_std = delays[0].1.hypot(delays[1].1);
    let over_stretch = change * n as f64 / half as f64;
    if 2.0 * std::f64::consts::PI * BOUND_BAND_HZ[1].min(0.4 * rate) * over_stretch.abs() < DRIFT_PHASE_RAD
        || change.abs() <= DRIFT_SIGMAS * change_std
    {
        return 0.0;
    }
    change / (half as f64 / rate)
}

#[cfg(test)]
#[path = "witness_delay_tests.rs"]
mod tests;
