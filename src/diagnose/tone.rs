//! Vibration tones: a sinusoid incoherent with the input shows as a line in the whole-record
//! residual spectrum. The line is located by the largest ratio of whitened residual power to its
//! running median (the local continuum), its frequency refined by golden-section search on the
//! power a sinusoid explains, and its amplitude per channel solved by least squares against the
//! exact DFT of a sampled sinusoid (a Dirichlet kernel, so leakage is modelled, not suffered).
//!
//! The explained power is measured against the local continuum, not the model's disturbance
//! level, so that broadband misfit left by another effect cannot pass for a line.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::design::{Design, WINDOW_ENBW};

/// Bins on each side of the line used for the fit.
const HALF_WINDOW: usize = 16;
/// Bins on each side for the running median of the continuum.
const MEDIAN_HALF: usize = 60;

/// A fitted tone.
#[derive(Clone, Debug, PartialEq)]
pub struct Tone {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Cosine coefficient per channel (output units).
    pub cos: [f64; 3],
    /// Sine coefficient per channel.
    pub sin: [f64; 3],
    /// `chi2` reduction against the local continuum.
    pub delta_chi2: f64,
}

impl Tone {
    /// Amplitude per channel, output units.
    #[must_use]
    pub fn amplitude(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.cos[i].hypot(self.sin[i]))
    }

    /// The tone's spectrum on every band bin, per channel.
    #[must_use]
    pub fn spectrum(&self, design: &Design) -> [Vec<Complex64>; 3] {
        let (c, s) = sinusoid_dft(design, self.frequency_hz, 0..design.n_bins());
        [0, 1, 2].map(|i| {
            c.iter()
                .zip(&s)
                .map(|(c, s)| c * self.cos[i] + s * self.sin[i])
                .collect()
        })
    }
}

/// `sum_{n<N} e^{i theta n}`.
fn dirichlet(theta: f64, n: usize) -> Complex64 {
    let half = 0.5 * theta;
    let den = half.sin();
    if den.abs() < 1e-12 {
        return Complex64::from(n as f64);
    }
    Complex64::from_polar(1.0, half * (n as f64 - 1.0)) * ((n as f64 * half).sin() / den)
}

/// DFT of `w_n e^{i theta n}` with the design's Hann taper `w_n = 1/2 - (e^{i 2 pi n / N} +
/// e^{-i 2 pi n / N}) / 4`: three shifted Dirichlet kernels.
fn hann_dirichlet(theta: f64, n: usize) -> Complex64 {
    let step = 2.0 * PI / n as f64;
    dirichlet(theta, n) * 0.5 - (dirichlet(theta + step, n) + dirichlet(theta - step, n)) * 0.25
}

/// DFTs of the tapered `cos(2 pi f n / fs)` and `sin(..)` over band bins `range`.
fn sinusoid_dft(design: &Design, f: f64, range: std::ops::Range<usize>) -> (Vec<Complex64>, Vec<Complex64>) {
    let alpha = 2.0 * PI * f / design.sample_rate_hz;
    let n = design.n_samples;
    range
        .map(|k| {
            let beta = 2.0 * PI * (design.first_bin + k) as f64 / design.fft_len as f64;
            let (p, m) = (hann_dirichlet(alpha - beta, n), hann_dirichlet(-alpha - beta, n));
            ((p + m) * 0.5, (p - m) / Complex64::new(0.0, 2.0))
        })
        .unzip()
}

/// The upper median of `v` (reordered in place); `v` must not be empty.
pub(super) fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    v.select_nth_unstable_by(mid, f64::total_cmp);
    v[mid]
}

/// Weighted least-squares sinusoid at `f` over `range`; returns coefficients and explained power.
fn explain(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    f: f64,
    range: &std::ops::Range<usize>,
) -> ([f64; 3], [f64; 3], f64) {
    let (c, s) = sinusoid_dft(design, f, range.clone());
    let (mut cos, mut sin, mut gain) = ([0.0; 3], [0.0; 3], 0.0);
    for i in 0..3 {
        let (mut a, mut b, mut d, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (m, k) in range.clone().enumerate() {
            let w = 1.0 / design.expected[i][k];
            a += w * c[m].norm_sqr();
            b += w * (c[m].conj() * s[m]).re;
            d += w * s[m].norm_sqr();
            r1 += w * (c[m].conj() * residual[i][k]).re;
            r2 += w * (s[m].conj() * residual[i][k]).re;
        }
        let det = a * d - b * b;
        if det.abs() <= f64::MIN_POSITIVE {
            continue;
        }
        cos[i] = (d * r1 - b * r2) / det;
        sin[i] = (a * r2 - b * r1) / det;
        gain += cos[i] * r1 + sin[i] * r2;
    }
    (cos, sin, gain)
}

/// The strongest line in `residual` (band bins, per channel), fitted; `None` when the band is
/// too narrow for a continuum estimate.
#[must_use]
pub fn strongest_line(design: &Design, residual: &[Vec<Complex64>; 3]) -> Option<Tone> {
    let n = design.n_bins();
    if n < 2 * MEDIAN_HALF + 1 {
        return None;
    }
    let power: Vec<f64> = (0..n)
        .map(|k| {
            (0..3)
                .map(|i| residual[i][k].norm_sqr() / design.expected[i][k])
                .sum()
        })
        .collect();
    let continuum = |k: usize| {
        let lo = k.saturating_sub(MEDIAN_HALF).min(n - 2 * MEDIAN_HALF - 1);
        median(&mut power[lo..=lo + 2 * MEDIAN_HALF].to_vec())
    };
    // The largest ratio to the continuum among the ten strongest bins.
    let mut strongest: Vec<usize> = (0..n).collect();
    strongest.sort_by(|&a, &b| power[b].total_cmp(&power[a]));
    let peak = strongest
        .iter()
        .take(10)
        .copied()
        .max_by(|&a, &b| (power[a] / continuum(a)).total_cmp(&(power[b] / continuum(b))))?;
    // The continuum of three channels' whitened power has median ~ 3 * 0.89 under the model.
    let background = (continuum(peak) / (3.0 * 0.891)).max(1.0);
    let range = peak.saturating_sub(HALF_WINDOW)..(peak + HALF_WINDOW + 1).min(n);
    let df = design.sample_rate_hz / design.fft_len as f64;
    let f_peak = design.frequency_hz[peak];
    let (mut lo, mut hi) = (f_peak - 1.5 * df, f_peak + 1.5 * df);
    let golden = 0.5 * (5.0_f64.sqrt() - 1.0);
    let gain = |f: f64| explain(design, residual, f, &range).2;
    let (mut a, mut b) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
    let (mut ga, mut gb) = (gain(a), gain(b));
    for _ in 0..40 {
        if ga > gb {
            hi = b;
            (b, gb) = (a, ga);
            a = hi - golden * (hi - lo);
            ga = gain(a);
        } else {
            lo = a;
            (a, ga) = (b, gb);
            b = lo + golden * (hi - lo);
            gb = gain(b);
        }
    }
    let frequency_hz = 0.5 * (lo + hi);
    let (cos, sin, explained) = explain(design, residual, frequency_hz, &range);
    Some(Tone {
        frequency_hz,
        cos,
        sin,
        delta_chi2: 2.0 * explained / background / WINDOW_ENBW,
    })
}
