//! Aligning a block's outputs with its inputs by whole samples before the Welch estimate.
//!
//! A Welch estimate cuts the inputs and the outputs at the same instants. Where the outputs lag
//! the inputs by `d` samples (a logging or transport latency between the stand's clock and the
//! sensors', a late angle sensor), each segment of the outputs holds the inputs of a window moved
//! by `d`: the cross-spectrum loses `1 - r(d)` of its level (`r` the window's normalised
//! autocorrelation, [`super::selfcheck::overlap_loss`]) and is smeared across neighbouring bins by
//! the delay's phase turn within the window's kernel. The gain reads low and the misfit grows: on
//! our simulator's runs with the angles 100-200 ms late, `K` 0.26-0.52 % off (3.8 of its
//! deviations) with the delay itself right.
//!
//! So the block's spectra are estimated a second time with the outputs moved by the lag `l` (whole
//! samples) the first estimate shows, and the delay's phase is given back: with the outputs' copy
//! `x_l(t) = x(t + l)`, `S_xu = S_(x_l u) e^(-i 2 pi f l / fs)` at the frequency `f` each bin is
//! compared at (a native bin's inputs' power centroid, `structural::align`; the bin's centre
//! elsewhere, exact for a filter on the grid). The comparison's first-order term for a column's
//! offset within its bin then holds the slope of the remaining delay only
//! (`StructuralSettings::aligned_s`): the aligned estimate is not smeared by the rest (given the
//! whole slope, the real-run-like runs 100 ms late had chi2/dof 3.5 where 1.1 was due). Every
//! consumer of the spectra sees the block's whole delay as before, with no overlap loss beyond the
//! remaining lag. The inputs' and outputs' copies are both cut to their common length (`|l|`
//! samples fewer), the stretches' times are the inputs'; an alignment that lowers the outputs'
//! coherence with the inputs where they are coherent is dropped ([`coherence_gain`]).
//!
//! **The lag** is the peak of `sum_ij |h_ij(l)|^2` over `|l| <= ` [`ALIGN_REACH_S`] (the identifier's
//! widest delay search), `h(l) = sum_k w_k H1(f_k) e^(i 2 pi k l / M)` the coherence-weighted
//! impulse response of the `H1 = S_xu (S_uu + e I)^-1` estimate on the padded grid (`e` a
//! [`REGULARISATION`] share of the inputs' mean power) of `M` points (`w_k`
//! the bin's mean multiple coherence, squared: noise bins count little). `H1` takes the inputs'
//! own cross-spectra out, and the squared magnitude over every pair is blind to the axes' order
//! and signs (a triad mounted turned still peaks at its delay). A lag is applied only where it
//! matters and is clear: its overlap loss at the settings' segment above [`MIN_OVERLAP_LOSS`], and
//! the peak at least [`PEAK_OVER_ZERO`] times the score at lag 0 (a narrow-band input, whose
//! envelope is flat over the reach, is left as it is). Units: samples for lags, Hz for
//! frequencies. Non-finite spectra or no coherent bin give no lag.

use nalgebra::Matrix3;
use num_complex::Complex64;
use realfft::RealFftPlanner;

use super::band::coherence_of;
use super::selfcheck::overlap_loss;
use super::stretches::STRETCH_DELAY_REACH_S;
use crate::spectral::SpectralMatrix;

/// The farthest lag looked for, s: the identifier's widest delay search
/// ([`super::structural::gain_delay::DELAY_REACH_S`]), so an alignment never takes the spectra
/// where the fit cannot follow.
pub const ALIGN_REACH_S: f64 = STRETCH_DELAY_REACH_S;

/// Smallest overlap loss at the settings' segment for which the outputs are moved: `1e-5` is a
/// thousandth of a percent on the gain, 5 samples on a segment of 4096 (10 ms at 500 Hz); the
/// sensors' own delays of a few samples are left as they are (their spectra unchanged to the bit).
pub const MIN_OVERLAP_LOSS: f64 = 1e-5;

/// The share of the inputs' mean power added to each direction's before `S_uu` is inverted for
/// the impulse response: a direction weaker than this is all but left out of it.
pub const REGULARISATION: f64 = 0.01;

/// How many times the score at lag 0 the peak must reach for a lag to be applied. A broad-band
/// input of coherent bandwidth `B` has a peak `1 / B` wide: its score at a lag of `0.75 / B` from
/// the peak is below a tenth of the peak's.
pub const PEAK_OVER_ZERO: f64 = 4.0;

/// The lag, in whole samples, by which the outputs lag the inputs in these one-sided spectra on
/// a grid of `2 (bins - 1)` points, or 0 when none is to be applied (module docs); `window` is the
/// settings' Welch window (its length the segment).
#[must_use]
pub fn alignment_lag(
    s_uu: &[Matrix3<Complex64>],
    s_xu: &[Matrix3<Complex64>],
    s_xx: &[Matrix3<Complex64>],
    window: &[f64],
    sample_rate_hz: f64,
) -> i64 {
    let bins = s_uu.len().min(s_xu.len()).min(s_xx.len());
    if bins < 3 || !sample_rate_hz.is_finite() {
        return 0;
    }
    let Some(score) = score(s_uu, s_xu, s_xx, bins) else {
        return 0;
    };
    let len = score.len();
    let reach = ((ALIGN_REACH_S * sample_rate_hz).floor() as usize).min(len / 2 - 1);
    let lag_of = |i: usize| {
        if i <= len / 2 {
            i as i64
        } else {
            i as i64 - len as i64
        }
    };
    let Some(peak) = (0..=reach)
        .chain(len - reach..len)
        .max_by(|&a, &b| score[a].total_cmp(&score[b]))
    else {
        return 0;
    };
    let lag = lag_of(peak);
    let clear = score[peak] >= PEAK_OVER_ZERO * score[0] && score[peak] > 0.0;
    let matters = overlap_loss(window, lag.unsigned_abs() as f64) > MIN_OVERLAP_LOSS;
    if clear && matters { lag } else { 0 }
}

/// The smallest mean multiple coherence of a bin [`coherence_gain`] compares: below, a bin's
/// coherence is mostly its estimate's noise, which the two estimates' different segments move by
/// more than an alignment does.
pub const COHERENT: f64 = 0.5;

/// What aligning the outputs did to their coherence with the inputs, in two 6x6 matrices of
/// `[u; x]` on one grid (`first` before, `moved` after): the sum over the bins between DC and
/// Nyquist where `first`'s mean multiple coherence is at least [`COHERENT`] of the change in its
/// square. A right alignment raises it (the segments' overlap loss gone), a wrong one lowers it.
/// 0 for no such bin or different grids.
#[must_use]
pub fn coherence_gain(first: &SpectralMatrix, moved: &SpectralMatrix) -> f64 {
    let bins = first.n_bins();
    if bins < 3 || moved.n_bins() != bins || first.n_channels < 6 || moved.n_channels < 6 {
        return 0.0;
    }
    let mean = |m: &SpectralMatrix, f: usize| {
        let part = |r0: usize, c0: usize| Matrix3::from_fn(|i, j| m[(f, r0 + i, c0 + j)]);
        coherence_of(&part(0, 0), &part(3, 0), &part(3, 3))
            .iter()
            .sum::<f64>()
            / 3.0
    };
    (1..bins - 1)
        .filter_map(|f| {
            let before = mean(first, f);
            (before >= COHERENT).then(|| mean(moved, f).powi(2) - before.powi(2))
        })
        .sum()
}

/// `sum_ij |h_ij(l)|^2` at every lag `l` of the grid (index `l mod M`), or `None` for no coherent
/// bin or a non-finite score.
fn score(
    s_uu: &[Matrix3<Complex64>],
    s_xu: &[Matrix3<Complex64>],
    s_xx: &[Matrix3<Complex64>],
    bins: usize,
) -> Option<Vec<f64>> {
    let len = 2 * (bins - 1);
    // The weighted `H1` per bin, DC and Nyquist left out (a one-sided sum's analytic signal).
    let mut weighted = vec![Matrix3::<Complex64>::zeros(); bins];
    let mut any = false;
    for k in 1..bins - 1 {
        let coherence = coherence_of(&s_uu[k], &s_xu[k], &s_xx[k]);
        let w = (coherence.iter().sum::<f64>() / 3.0).powi(2);
        // Regularised: a weak input direction (an accelerometer's, along its lever arm) would
        // put its noise-amplified column above every other.
        let power = (s_uu[k] + s_uu[k].adjoint()) * Complex64::from(0.5);
        let floor = REGULARISATION * power.trace().re / 3.0;
        let Some(inverse) = (power + Matrix3::identity() * Complex64::from(floor)).try_inverse() else {
            continue;
        };
        let h = s_xu[k] * inverse * Complex64::from(w);
        if w > 0.0 && h.iter().all(|z| z.is_finite()) {
            weighted[k] = h;
            any = true;
        }
    }
    if !any {
        return None;
    }
    // `2 Re sum_k X_k e^(i theta)` and `2 Im ...` by two real inverse transforms (of `X` and of
    // `-i X`): `|h|^2` is a quarter of their squares' sum.
    let inverse = RealFftPlanner::<f64>::new().plan_fft_inverse(len);
    let mut spectrum = inverse.make_input_vec();
    let mut out = inverse.make_output_vec();
    let mut total = vec![0.0; len];
    for i in 0..3 {
        for j in 0..3 {
            for turn in [Complex64::new(1.0, 0.0), Complex64::new(0.0, -1.0)] {
                for (k, s) in spectrum.iter_mut().enumerate() {
                    *s = weighted[k][(i, j)] * turn;
                }
                inverse.process(&mut spectrum, &mut out).ok()?;
                for (t, v) in total.iter_mut().zip(&out) {
                    *t += 0.25 * v * v;
                }
            }
        }
    }
    total.iter().all(|v| v.is_finite()).then_some(total)
}

/// `s_xu` of outputs moved earlier by `lag` samples given back its delay, bin by bin on a grid of
/// `M = 2 (bins - 1)` points: times `e^(-i 2 pi k lag / M)` at a bin compared at its centre
/// (`at(k)` `None`), times `e^(-i 2 pi f_c lag / fs)` at a bin compared at its inputs' power
/// centroid `f_c` (`at(k) = Some(f_c)`, `structural::align`): there the aligned estimate is the
/// response at `f_c` with the remaining delay's smear only, and the comparison is told so
/// (`ResponseEstimate::aligned_s`).
pub fn restore_delay(
    s_xu: &mut [Matrix3<Complex64>],
    lag: i64,
    sample_rate_hz: f64,
    at: impl Fn(usize) -> Option<f64>,
) {
    if lag == 0 || s_xu.len() < 2 {
        return;
    }
    let len = 2 * (s_xu.len() - 1);
    let two_pi = 2.0 * std::f64::consts::PI;
    for (k, s) in s_xu.iter_mut().enumerate() {
        let turns = match at(k).filter(|f| f.is_finite()) {
            Some(fc) => fc * lag as f64 / sample_rate_hz,
            None => ((k as i64 * lag).rem_euclid(len as i64)) as f64 / len as f64,
        };
        *s *= Complex64::from_polar(1.0, -two_pi * turns);
    }
}

/// The inputs' and outputs' copies aligned by `lag` (outputs moved earlier by `lag` samples,
/// both cut to their common length) and the inputs' first sample: `channels` are the three
/// inputs then the three outputs. `lag` must be shorter than the channels.
#[must_use]
pub fn aligned<'a>(channels: &[&'a [f64]], lag: i64) -> (Vec<&'a [f64]>, usize) {
    let n = channels.first().map_or(0, |c| c.len());
    let shift = (lag.unsigned_abs() as usize).min(n);
    let (input_start, output_start) = if lag >= 0 { (0, shift) } else { (shift, 0) };
    let cut = channels
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let start = if i < 3 { input_start } else { output_start };
            &c[start..start + n - shift]
        })
        .collect();
    (cut, input_start)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::{WelchPlanner, WelchSettings, Window};

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = crate::rng::Rng::new(seed);
        // Low-passed white noise: a motion-like spectrum, coherent to a fifth of Nyquist.
        let mut y = 0.0;
        (0..n)
            .map(|_| {
                y = 0.8 * y + rng.normal();
                y
            })
            .collect()
    }

    /// Inputs `u`, outputs the inputs turned (an axis permutation with a sign) and moved by `d`
    /// samples (later for positive `d`) plus a little noise; the spectra on a 4x grid.
    fn spectra(d: i64, seed: u64) -> (Vec<[Matrix3<Complex64>; 3]>, Vec<f64>) {
        let (n, margin) = (60_000_usize, 200_usize);
        let u: Vec<Vec<f64>> = (0..3).map(|i| noise(n + 2 * margin, seed + i)).collect();
        let e: Vec<Vec<f64>> = (0..3).map(|i| noise(n, seed + 10 + i)).collect();
        let inputs: Vec<Vec<f64>> = (0..3).map(|c| u[c][margin..margin + n].to_vec()).collect();
        let outputs: Vec<Vec<f64>> = [(1, 1.0), (0, -1.0), (2, 1.0)]
            .iter()
            .enumerate()
            .map(|(r, &(c, sign))| {
                (0..n)
                    .map(|t| sign * u[c][(margin + t).saturating_add_signed(-d as isize)] + 0.05 * e[r][t])
                    .collect()
            })
            .collect();
        let channels: Vec<&[f64]> = inputs.iter().chain(&outputs).map(Vec::as_slice).collect();
        let settings = WelchSettings {
            segment_len: 1024,
            window: Window::Hann,
            fft_len: Some(4096),
            ..WelchSettings::default()
        };
        let m = WelchPlanner::new()
            .welch_matrix(&channels, 500.0, &settings)
            .expect("welch");
        let block = |f: usize, r0: usize, c0: usize| Matrix3::from_fn(|i, j| m[(f, r0 + i, c0 + j)]);
        let per_bin = (0..m.n_bins())
            .map(|f| [block(f, 0, 0), block(f, 3, 0), block(f, 3, 3)])
            .collect();
        (per_bin, Window::Hann.coefficients(1024))
    }

    fn lag(d: i64, seed: u64) -> i64 {
        let (bins, window) = spectra(d, seed);
        let part = |p: usize| bins.iter().map(|b| b[p]).collect::<Vec<_>>();
        alignment_lag(&part(0), &part(1), &part(2), &window, 500.0)
    }

    #[test]
    fn the_lag_is_the_delay_for_turned_axes_and_none_for_a_short_one() {
        for seed in [1, 7] {
            assert_eq!(lag(50, seed), 50, "seed {seed}");
            assert_eq!(lag(140, seed), 140, "seed {seed}");
            assert_eq!(lag(-75, seed), -75, "seed {seed}");
            // One sample: no loss to speak of, the spectra kept as they are.
            assert_eq!(lag(1, seed), 0, "seed {seed}");
        }
    }
}
