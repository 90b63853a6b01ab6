//! Tones that come and go (issue 15): when a line found in the residual is on. A vibrating
//! device switched on part-way through a run, or pulsed, puts a line in the whole-record
//! spectrum whose sidebands carry its on-off pattern; a constant sinusoid fits only the line.
//!
//! The line's complex envelope is the inverse DFT of the residual's bins within
//! [`BANDWIDTH_HZ`] of it (whitened by the expected disturbance), divided by the Hann taper the
//! bins carry (where the taper is above [`MIN_TAPER`]). Its part in phase with each channel's
//! tone, the channels weighted by their tone's strength, is the tone's amplitude in time
//! (linear in the gate, so a blurred switch crosses its middle where it switches); the part in
//! quadrature is noise alone and measures the noise.
//! Two gates are tried on its power: one that repeats (the power folded over each period,
//! which averages the cycles: a pulsed tone too weak to follow in time is still resolved, and
//! the record's ends, where the taper leaves no envelope, are tiled), and one that switches at
//! arbitrary times (the power smoothed as little as the tone's strength allows). The one whose
//! two levels explain the power best is kept; a tone off for less than [`MIN_OFF_FRACTION`] of
//! the record, or with neither gate significant, is on throughout (`None`).
//!
//! Times are s from the record's (the analysed span's) start.

use num_complex::Complex64;
use rustfft::FftPlanner;

use super::design::Design;

/// Half-width of the band around the line whose bins make the envelope, Hz: its time
/// resolution is about `1 / (2 B)` = 0.5 s.
pub const BANDWIDTH_HZ: f64 = 1.0;
/// Smallest taper value the envelope is divided by.
const MIN_TAPER: f64 = 0.05;
/// Longest period of a repeating gate searched, s (a slower one is followed in time).
const MAX_PERIOD_S: f64 = 60.0;
/// A tone off for less of the record than this is on throughout.
const MIN_OFF_FRACTION: f64 = 0.03;

/// When a tone is on.
#[derive(Clone, Debug, PartialEq)]
pub struct Gate {
    /// Stretches `[start, end]`, s, where the tone is on, in order.
    pub on_s: Vec<[f64; 2]>,
    /// Fraction of the record it is on.
    pub on_fraction: f64,
    /// Its free parameters: a repeating gate's period, phase and on-time (3), or each switch
    /// time of one that switches at arbitrary times.
    pub parameters: usize,
}

impl Gate {
    /// Whether the tone is on at `t_s`.
    #[must_use]
    pub fn is_on(&self, t_s: f64) -> bool {
        on_at(&self.on_s, t_s)
    }

    /// Number of switch times in a record of `duration_s`.
    #[must_use]
    pub fn switches(on_s: &[[f64; 2]], duration_s: f64) -> usize {
        on_s.iter()
            .map(|s| usize::from(s[0] > 0.0) + usize::from(s[1] < duration_s))
            .sum()
    }
}

/// The gate of the line at `frequency_hz` (band bin `peak`) in `residual`; `None` when it is on throughout or
/// the record is too short to tell.
#[must_use]
pub fn estimate_gate(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    peak: usize,
    frequency_hz: f64,
) -> Option<Gate> {
    let fs = design.sample_rate_hz;
    let df = fs / design.fft_len as f64;
    let duration = design.n_samples as f64 / fs;
    let half = ((BANDWIDTH_HZ / df).round() as usize).max(4);
    let (lo, hi) = (peak.saturating_sub(half), (peak + half + 1).min(design.n_bins()));
    let len = (4 * (hi - lo)).next_power_of_two();
    let ifft = FftPlanner::<f64>::new().plan_fft_inverse(len);
    // Envelope sample j is at t = j fft_len / (len fs); the peak bin's frequency is taken off,
    // the line's own is f: what is left rotates at f - f_peak, which is taken off too.
    let dt = design.fft_len as f64 / (len as f64 * fs);
    let offset_hz = frequency_hz - design.frequency_hz[peak];
    let times: Vec<f64> = (0..len).map(|j| j as f64 * dt).collect();
    let taper: Vec<f64> = times
        .iter()
        .map(|&t| (std::f64::consts::PI * t / duration).sin().powi(2))
        .collect();
    let keep: Vec<usize> = (0..len)
        .filter(|&j| times[j] < duration && taper[j] > MIN_TAPER)
        .collect();
    if keep.len() < 20 {
        return None;
    }
    let envelopes: Vec<Vec<Complex64>> = (0..3)
        .map(|i| {
            let scale = 1.0 / design.expected[i][peak].sqrt();
            let mut buf = vec![Complex64::default(); len];
            for k in lo..hi {
                let at = (k as isize - peak as isize).rem_euclid(len as isize) as usize;
                buf[at] = residual[i][k] * scale;
            }
            ifft.process(&mut buf);
            keep.iter()
                .map(|&j| {
                    buf[j]
                        * Complex64::from_polar(1.0 / taper[j], -std::f64::consts::TAU * offset_hz * times[j])
                })
                .collect()
        })
        .collect();
    // Each channel's tone has one phase: the envelope's in-phase part, summed over channels
    // weighted by their coherent sums (a matched filter), is the tone's amplitude in time, linear
    // in the gate; the quadrature part is noise alone and measures it.
    let mut raw = vec![0.0; keep.len()];
    let mut quadrature = vec![0.0; keep.len()];
    for e in &envelopes {
        let sum: Complex64 = e.iter().sum();
        for (k, z) in e.iter().enumerate() {
            let rotated = z * sum.conj();
            raw[k] += rotated.re;
            quadrature[k] += rotated.im;
        }
    }
    let norm = raw
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
        .max(f64::MIN_POSITIVE);
    for v in raw.iter_mut().chain(quadrature.iter_mut()) {
        *v /= norm;
    }
    let noise_sd = (quadrature.iter().map(|v| v * v).sum::<f64>() / quadrature.len() as f64).sqrt();
    let times: Vec<f64> = keep.iter().map(|&j| times[j]).collect();
    let resolution = 1.0 / (2.0 * BANDWIDTH_HZ);
    let per_independent = (resolution / dt).max(1.0);
    let noise_var = (noise_sd * noise_sd).max(f64::MIN_POSITIVE);
    let candidates = [
        periodic_gate(&times, &raw, noise_sd, duration, resolution).map(|g| (g, 3)),
        stepped_gate(&times, &raw, noise_sd, duration, dt).map(|g| {
            let n = Gate::switches(&g, duration);
            (g, n)
        }),
    ];
    // The gate whose two levels (on and off) explain the envelope best, each of its parameters
    // (a repeating gate's period, phase and length; every switch time of the other) charged
    // twice the noise of an independent envelope sample (AIC).
    let gate = candidates
        .into_iter()
        .flatten()
        .map(|(on_s, params)| {
            let on: Vec<bool> = times.iter().map(|&t| on_at(&on_s, t)).collect();
            let score = two_level_misfit(&raw, &on) / noise_var + 2.0 * params as f64 * per_independent;
            (score, on_s, params)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    let (gate, parameters) = (gate.1, gate.2);
    let on: f64 = gate.iter().map(|s| s[1] - s[0]).sum();
    let on_fraction = on / duration;
    (on_fraction < 1.0 - MIN_OFF_FRACTION && on_fraction > 0.0).then_some(Gate {
        on_s: gate,
        on_fraction,
        parameters,
    })
}

fn on_at(on_s: &[[f64; 2]], t: f64) -> bool {
    let k = on_s.partition_point(|s| s[1] < t);
    on_s.get(k).is_some_and(|s| s[0] <= t)
}

/// Sum of squares of `q` about the mean of its state (on or off).
fn two_level_misfit(q: &[f64], on: &[bool]) -> f64 {
    let mean = |state: bool| {
        let (sum, count) = q
            .iter()
            .zip(on)
            .filter(|(_, o)| **o == state)
            .fold((0.0, 0_usize), |(s, c), (v, _)| (s + v, c + 1));
        sum / count.max(1) as f64
    };
    let (m_on, m_off) = (mean(true), mean(false));
    q.iter()
        .zip(on)
        .map(|(v, o)| (v - if *o { m_on } else { m_off }).powi(2))
        .sum()
}

/// A gate that repeats: the envelope's power folded over each period from four resolutions to
/// a quarter of the record, in phase bins of about one resolution; the period whose folded
/// profile varies most beyond chance (its `chi2` over the bins, against the noise of the power,
/// above `nb + 6 sqrt(2 nb)`), split at the middle of the profile's extremes and tiled over the
/// whole record. Folding averages the cycles, so a pulsed tone too weak to follow in time is
/// still resolved.
fn periodic_gate(
    times: &[f64],
    q: &[f64],
    noise_sd: f64,
    duration: f64,
    resolution: f64,
) -> Option<Vec<[f64; 2]>> {
    let mean = q.iter().sum::<f64>() / q.len() as f64;
    let noise_var = (noise_sd * noise_sd).max(f64::MIN_POSITIVE);
    let step = (times.get(1).copied().unwrap_or(1.0) - times[0]).max(1e-3);
    let fold = |period: f64| -> Option<(f64, Vec<f64>)> {
        let nb = ((2.0 * period / resolution).round() as usize).max(8);
        let (mut sum, mut count) = (vec![0.0; nb], vec![0_usize; nb]);
        for (&t, &v) in times.iter().zip(q) {
            let cycles = t / period;
            let b = (((cycles - cycles.floor()) * nb as f64) as usize).min(nb - 1);
            sum[b] += v;
            count[b] += 1;
        }
        if count.contains(&0) {
            return None;
        }
        let profile: Vec<f64> = sum.iter().zip(&count).map(|(s, &c)| s / c as f64).collect();
        // Independent samples per bin: the envelope is correlated over a resolution.
        let chi2: f64 = profile
            .iter()
            .zip(&count)
            .map(|(m, &c)| (m - mean).powi(2) * (c as f64 * step / resolution).max(1.0) / noise_var)
            .sum();
        let excess = chi2 - (nb as f64 + 6.0 * (2.0 * nb as f64).sqrt());
        (excess > 0.0).then_some((excess, profile))
    };
    // Candidate periods from the envelope's own spectrum: its strongest peaks between
    // 1/longest and 1/(4 resolutions), each as the fundamental or the second harmonic; then a
    // fold on a fine grid (neighbours drifting apart by an eighth of a resolution over the
    // record) within the spectral peak's uncertainty around each.
    let ratio = resolution / duration / 8.0;
    let longest = (duration / 4.0).min(MAX_PERIOD_S);
    let mut best: Option<(f64, f64, Vec<f64>)> = None;
    let keep = |period: f64, best: &mut Option<(f64, f64, Vec<f64>)>| {
        if let Some((excess, profile)) = fold(period)
            && best.as_ref().is_none_or(|b| excess > b.0)
        {
            *best = Some((excess, period, profile));
        }
    };
    for f in spectral_peaks(q, mean, step, [1.0 / longest, 1.0 / (4.0 * resolution)], 3) {
        for harmonic in [1.0, 2.0] {
            let centre = harmonic / f;
            if !(4.0 * resolution..=longest).contains(&centre) {
                continue;
            }
            // The peak's frequency is known to about a bin of the record, 1/duration: a coarse
            // pass over that spread, eight fine steps apart.
            let spread = 2.0 * centre * centre / duration;
            let mut period = (centre - spread).max(4.0 * resolution);
            while period <= (centre + spread).min(longest) {
                keep(period, &mut best);
                period *= 1.0 + 8.0 * ratio;
            }
        }
    }
    if let Some(coarse) = best.as_ref().map(|b| b.1) {
        for j in -8..=8 {
            keep(coarse * (1.0 + ratio * f64::from(j)), &mut best);
        }
    }
    let (_, period, profile) = best?;
    // The on-arc of the cycle: the contiguous (circular) run of phase bins whose two levels fit
    // the profile best; the blurred edges of a pulse cross the middle where it switches.
    let nb = profile.len();
    let width = period / nb as f64;
    let (start, len) = best_arc(&profile);
    // The fold's bins are noisy: period, start and length are refined on the envelope itself,
    // by the two-level fit of the tiled gate over every sample.
    let tile = |period: f64, start: f64, length: f64| -> Vec<[f64; 2]> {
        let mut on_s: Vec<[f64; 2]> = Vec::new();
        let mut cycle = start.rem_euclid(period) - period;
        while cycle < duration {
            let (a, e) = (cycle.max(0.0), (cycle + length).min(duration));
            if e > a {
                push_stretch(&mut on_s, [a, e], 0.25 * resolution);
            }
            cycle += period;
        }
        on_s
    };
    let misfit = |on_s: &[[f64; 2]]| {
        let on: Vec<bool> = times.iter().map(|&t| on_at(on_s, t)).collect();
        two_level_misfit(q, &on)
    };
    let (mut p0, mut a0, mut l0) = (period, start as f64 * width, len as f64 * width);
    let mut best_misfit = misfit(&tile(p0, a0, l0));
    for scale in [1.0, 0.25] {
        let (dp, da) = (scale * period * resolution / duration, scale * resolution / 4.0);
        let (pc, ac, lc) = (p0, a0, l0);
        for i in -8..=8 {
            for j in -4..=4 {
                for k in -2..=2 {
                    let (p, a, l) = (
                        pc + f64::from(i) * dp,
                        ac + f64::from(j) * da,
                        lc + f64::from(k) * da,
                    );
                    if l <= 0.0 || l >= p {
                        continue;
                    }
                    let m = misfit(&tile(p, a, l));
                    if m < best_misfit {
                        (best_misfit, p0, a0, l0) = (m, p, a, l);
                    }
                }
            }
        }
    }
    Some(tile(p0, a0, l0))
}

/// The circular run `(start, length)` of `profile`'s bins that, as the higher of two levels,
/// leaves the least sum of squares (brute force over every start and length).
fn best_arc(profile: &[f64]) -> (usize, usize) {
    let nb = profile.len();
    let total: f64 = profile.iter().sum();
    let total_sq: f64 = profile.iter().map(|v| v * v).sum();
    let mut best = (f64::INFINITY, 0, 1);
    for start in 0..nb {
        let mut sum = 0.0;
        for len in 1..nb {
            sum += profile[(start + len - 1) % nb];
            let rest = total - sum;
            let (m_on, m_off) = (sum / len as f64, rest / (nb - len) as f64);
            if m_on <= m_off {
                continue;
            }
            // Sum of squares about the two means: total_sq - n_on m_on^2 - n_off m_off^2.
            let misfit = total_sq - len as f64 * m_on * m_on - (nb - len) as f64 * m_off * m_off;
            if misfit < best.0 {
                best = (misfit, start, len);
            }
        }
    }
    (best.1, best.2)
}

/// The frequencies, Hz, of the `count` strongest local maxima of the spectrum of `q - mean`
/// (samples `step` s apart) inside `range`.
fn spectral_peaks(q: &[f64], mean: f64, step: f64, range: [f64; 2], count: usize) -> Vec<f64> {
    let len = (2 * q.len()).next_power_of_two();
    let mut buf: Vec<Complex64> = q.iter().map(|v| Complex64::from(v - mean)).collect();
    buf.resize(len, Complex64::default());
    FftPlanner::<f64>::new().plan_fft_forward(len).process(&mut buf);
    let df = 1.0 / (len as f64 * step);
    let power: Vec<f64> = buf[..len / 2].iter().map(Complex64::norm_sqr).collect();
    let mut peaks: Vec<(f64, f64)> = (1..power.len() - 1)
        .filter(|&k| {
            let f = k as f64 * df;
            f >= range[0] && f <= range[1] && power[k] >= power[k - 1] && power[k] >= power[k + 1]
        })
        .map(|k| (power[k], k as f64 * df))
        .collect();
    peaks.sort_by(|a, b| b.0.total_cmp(&a.0));
    peaks.into_iter().take(count).map(|p| p.1).collect()
}

/// A gate that switches at arbitrary times: the envelope's power smoothed over the finest
/// width (1, 2, 4, ... independent envelope samples) at which on and off differ by six
/// standard deviations of the smoothed noise, split at the middle of its 10th and 90th
/// percentiles; gaps and stretches shorter than the smoothing are bridged or dropped.
fn stepped_gate(times: &[f64], raw: &[f64], noise_sd: f64, duration: f64, dt: f64) -> Option<Vec<[f64; 2]>> {
    let per_independent = (1.0 / (2.0 * BANDWIDTH_HZ) / dt).max(1.0);
    let max_width = (raw.len() / 10).max(1);
    let mut independent = 1.0_f64;
    let (width, smoothed, threshold) = loop {
        let width = ((independent * per_independent).round() as usize).clamp(1, max_width);
        let smoothed = moving_average(raw, width);
        let mut sorted = smoothed.clone();
        sorted.sort_by(f64::total_cmp);
        let pct = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
        let (low, high) = (pct(0.1), pct(0.9));
        let sd = noise_sd / (width as f64 / per_independent).max(1.0).sqrt();
        if high - low >= 6.0 * sd {
            break (width, smoothed, 0.5 * (low + high));
        }
        if width >= max_width {
            return None;
        }
        independent *= 2.0;
    };
    let shortest = (width as f64 * dt).max(1.0 / (2.0 * BANDWIDTH_HZ));
    let mut on_s: Vec<[f64; 2]> = Vec::new();
    let mut start: Option<f64> = None;
    for (k, (&t, &p)) in times.iter().zip(&smoothed).enumerate() {
        let edge = if k == 0 { 0.0 } else { t };
        match (p > threshold, start) {
            (true, None) => start = Some(edge),
            (false, Some(s)) => {
                push_stretch(&mut on_s, [s, t], shortest);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        push_stretch(&mut on_s, [s, duration], shortest);
    }
    on_s.retain(|s| s[1] - s[0] >= shortest);
    // Next to the taper's ends the smoothing is one-sided and the envelope noisier: a switch
    // within two resolutions of the first or last envelope sample is not resolved, and the
    // stretch is taken to the record's end.
    let edge = 2.0 * shortest;
    let (first, last) = (
        times.first().copied().unwrap_or(0.0),
        times.last().copied().unwrap_or(duration),
    );
    if let Some(s) = on_s.first_mut()
        && s[0] > 0.0
        && s[0] - first < edge
    {
        s[0] = 0.0;
    }
    if let Some(s) = on_s.last_mut()
        && s[1] < duration
        && last - s[1] < edge
    {
        s[1] = duration;
    }
    Some(on_s)
}

/// Appends `next`, joined to the last stretch when the gap between them is under `shortest`.
fn push_stretch(on_s: &mut Vec<[f64; 2]>, next: [f64; 2], shortest: f64) {
    match on_s.last_mut() {
        Some(last) if next[0] - last[1] < shortest => last[1] = next[1],
        _ => on_s.push(next),
    }
}

/// Centred moving average over `width` samples (shrinking at the ends).
fn moving_average(x: &[f64], width: usize) -> Vec<f64> {
    let mut prefix = vec![0.0; x.len() + 1];
    for (k, v) in x.iter().enumerate() {
        prefix[k + 1] = prefix[k] + v;
    }
    let half = width / 2;
    (0..x.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half + 1).min(x.len()));
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{Gate, moving_average};

    #[test]
    fn a_gate_reads_its_stretches() {
        let g = Gate {
            on_s: vec![[0.0, 2.0], [5.0, 7.0], [10.0, 12.0]],
            on_fraction: 0.5,
            parameters: 3,
        };
        assert!(g.is_on(0.0) && g.is_on(1.9) && g.is_on(6.0) && g.is_on(12.0));
        assert!(!g.is_on(2.5) && !g.is_on(8.0) && !g.is_on(12.5));
        assert_eq!(
            Gate::switches(&g.on_s, 12.0),
            4,
            "starts on at 0 and ends on at the record's end"
        );
        assert_eq!(Gate::switches(&g.on_s, 20.0), 5);
    }

    #[test]
    fn the_on_arc_of_a_blurred_profile_is_where_it_crosses_the_middle() {
        // Off level 1, on level 3 over bins 7..12 (wrapping is tested by the second case), with
        // half-way edges.
        let mut p = vec![1.0; 20];
        for v in &mut p[7..12] {
            *v = 3.0;
        }
        p[6] = 2.0;
        p[12] = 2.0;
        let (start, len) = super::best_arc(&p);
        assert!(start == 6 || start == 7, "{start}");
        assert!((6..=7).contains(&len), "{len}");
        p.rotate_left(10);
        let (start, len) = super::best_arc(&p);
        assert!((start + len) % 20 <= 3 && start >= 16, "{start} {len}");
    }

    #[test]
    fn the_moving_average_is_that_of_a_brute_force_sum() {
        let x: Vec<f64> = (0..50).map(|k| f64::from(k * k % 7)).collect();
        let m = moving_average(&x, 5);
        for (k, v) in m.iter().enumerate() {
            let (a, b) = (k.saturating_sub(2), (k + 3).min(50));
            let want = x[a..b].iter().sum::<f64>() / (b - a) as f64;
            assert!((v - want).abs() < 1e-12, "{k}");
        }
    }
}
