//! Vibration tones: a sinusoid incoherent with the input shows as a line in the whole-record
//! residual spectrum. The line is located by the largest ratio of whitened residual power to its
//! running median (the local continuum), its frequency refined by golden-section search on the
//! power a sinusoid explains, and its amplitude per channel solved by least squares against the
//! exact DFT of a sampled sinusoid (a Dirichlet kernel, so leakage is modelled, not suffered).
//!
//! The explained power is measured against the local background (the three channels' covariance
//! around the line, never below the model's disturbance level inside the band), not the model's
//! disturbance level alone, so that broadband misfit left by another effect cannot pass for a line.
//!
//! The three channels are fitted together against their background's correlation (a random peak
//! of motion every channel sees, above the reference's band limit, is one draw, not three), and
//! a line must stand above its neighbourhood away from the edges of the searched range.
//!
//! No tone is named where the inputs carry a line of their own ([`INPUT_LINE`]: a stand
//! programme's sine): a residual line there is coherent with the input, and a misfit of the model
//! at that frequency and a vibration there cannot be told apart.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

use std::sync::Arc;

use super::design::{Design, U, WINDOW_ENBW, band_spectrum, hann};
use super::gate::{Gate, estimate_gate};
use crate::fourier::RecordFft;

/// The real parameters a constant tone adds: its frequency, and a cosine and a sine per channel.
pub(super) const TONE_PARAMETERS: usize = 7;
/// Bins on each side of the line used for the fit.
pub(super) const HALF_WINDOW: usize = 16;
/// Bins at either end of a searched range where no line is looked for ([`HALF_WINDOW`]).
pub(super) const EDGE_MARGIN_BINS: usize = HALF_WINDOW;
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
    /// `chi2` reduction against the local background's covariance (`ChannelFit::evidence`).
    pub delta_chi2: f64,
    /// When the tone is on (`None`: throughout).
    pub gate: Option<Gate>,
    /// The gated tone's cosine and sine spectra on the band bins (with a gate).
    pub basis: Option<Arc<[Vec<Complex64>; 2]>>,
    /// Whether it was found above the fit's band (on the state's upper outputs).
    pub upper: bool,
    /// Per channel, the standard deviation of the amplitude per unit of the taper's variance
    /// factor: `sqrt(level_i / (2 G_i))`, `level_i` the channel's own local continuum (in units
    /// of its expected level) and `G_i` the basis's weighted energy per unit amplitude. Each
    /// channel's own: the channels' noise differs (an accelerometer's vertical and lateral
    /// channels carry the lever-arm motion the forward one does not), and one figure for all
    /// three, from their joint evidence, was ten times too small on the noisier ones.
    pub unit_std: [f64; 3],
    /// Per channel, what the tone explains against that channel's own continuum (untapered
    /// units, the channels counted apart): their sum, taken for the channels' correlation, sets
    /// the frequency's deviation.
    pub channel_chi2: [f64; 3],
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
        let (c, s) = match &self.basis {
            Some(b) => (b[0].clone(), b[1].clone()),
            None => sinusoid_dft(design, self.frequency_hz, 0..design.n_bins()),
        };
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
pub(super) fn sinusoid_dft(
    design: &Design,
    f: f64,
    range: std::ops::Range<usize>,
) -> (Vec<Complex64>, Vec<Complex64>) {
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
    let fit = fit_channels(design, residual, (&c, &s), range);
    (fit.cos, fit.sin, fit.explained())
}

/// Channel `i`'s weighted Gram matrix `[a, b; b, d]` of the basis `(c, s)` over `range` and its
/// projections `r1, r2` of the residual, weights `1 / expected`.
pub(super) fn projections(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    (c, s): (&[Complex64], &[Complex64]),
    range: &std::ops::Range<usize>,
    i: usize,
) -> [f64; 5] {
    let mut out = [0.0; 5];
    for (m, k) in range.clone().enumerate() {
        let w = 1.0 / design.expected[i][k];
        out[0] += w * c[m].norm_sqr();
        out[1] += w * (c[m].conj() * s[m]).re;
        out[2] += w * s[m].norm_sqr();
        out[3] += w * (c[m].conj() * residual[i][k]).re;
        out[4] += w * (s[m].conj() * residual[i][k]).re;
    }
    out
}

/// The basis `(c, s)` fitted by weighted least squares on each channel over `range`.
struct ChannelFit {
    /// Cosine and sine coefficients per channel.
    cos: [f64; 3],
    sin: [f64; 3],
    /// Each channel's two projections whitened by its own Gram matrix (Cholesky): per quadrature,
    /// a 3-vector over the channels; `|y_i|^2` is channel `i`'s explained power.
    whitened: [Vector3<f64>; 2],
    /// Each channel's basis energy per unit amplitude, the Gram matrix's mean diagonal.
    energy: [f64; 3],
}

impl ChannelFit {
    /// Per channel, the amplitude's unit deviation and the power explained against the channel's
    /// own `levels` (see [`Tone::unit_std`], [`Tone::channel_chi2`]).
    fn per_channel(&self, levels: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let unit = [0, 1, 2].map(|i| (levels[i] / (2.0 * self.energy[i]).max(f64::MIN_POSITIVE)).sqrt());
        let chi2 = [0, 1, 2].map(|i| {
            2.0 * (self.whitened[0][i].powi(2) + self.whitened[1][i].powi(2))
                / levels[i].max(f64::MIN_POSITIVE)
        });
        (unit, chi2)
    }

    /// The power explained, the channels counted as independent.
    fn explained(&self) -> f64 {
        self.whitened.iter().map(Vector3::norm_squared).sum()
    }

    /// The line's evidence, a chi2 against the channels' background covariance `cov`
    /// ([`channel_covariance`]): `sum y^T cov^-1 y` over the two quadratures, `y` the channels'
    /// whitened projections (the channels counted apart when `cov` is diagonal). Weighing the
    /// projections by the inverse of the channels' correlation and dividing by their mean level
    /// (as was done) turned a random peak of the motion every channel carries (the common
    /// direction, with each channel's own scale) out of that direction wherever the levels
    /// differ, into the nearly collinear channels' weakest direction, and multiplied it by up to
    /// the ridge's thousand: four false accelerometer tones at 43-45 Hz on a `--stand real` run,
    /// chi2 157-342. Each channel scaled by its own median level inside that inverse was not
    /// enough: a median and the correlation's mean differ by a few percent between channels, and
    /// at a peak of the common motion that few percent, turned into the weakest direction, still
    /// scored 259 (README, 29 Nov). So the scales are the covariance's own.
    fn evidence(&self, cov: &Matrix3<f64>) -> f64 {
        let inverse = cov.try_inverse().unwrap_or_else(Matrix3::identity);
        self.whitened.iter().map(|y| y.dot(&(inverse * y))).sum()
    }
}

/// Weighted least squares of the basis `(c, s)` (spectra over `range`) per channel.
fn fit_channels(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    (c, s): (&[Complex64], &[Complex64]),
    range: &std::ops::Range<usize>,
) -> ChannelFit {
    let mut fit = ChannelFit {
        cos: [0.0; 3],
        sin: [0.0; 3],
        whitened: [Vector3::zeros(), Vector3::zeros()],
        energy: [0.0; 3],
    };
    for i in 0..3 {
        let [a, b, d, r1, r2] = projections(design, residual, (c, s), range, i);
        let det = a * d - b * b;
        if det.abs() <= f64::MIN_POSITIVE || a <= f64::MIN_POSITIVE {
            continue;
        }
        fit.energy[i] = 0.5 * (a + d);
        fit.cos[i] = (d * r1 - b * r2) / det;
        fit.sin[i] = (a * r2 - b * r1) / det;
        let (l11, l21) = (a.sqrt(), b / a.sqrt());
        let l22 = (d - l21 * l21).max(f64::MIN_POSITIVE).sqrt();
        fit.whitened[0][i] = r1 / l11;
        fit.whitened[1][i] = (r2 - l21 * r1 / l11) / l22;
    }
    fit
}

/// The covariance of the channels' whitened residual `r(i, k)` around bin `peak`, in units of the
/// design's expected level: over the continuum's window ([`MEDIAN_HALF`] bins each side), the
/// line's own [`HALF_WINDOW`] bins each side left out (`Re` of the cross-periodograms, the sum of
/// the two quadratures' covariances: hence the 2 in the evidence's chi2); the correlations
/// shrunk by a ridge of 1e-3, which keeps it invertible; inside the fit's band each channel's variance never below the expected level (the model's
/// disturbance: a line is never measured against less; above the band, [`Design::line_search`]
/// without groups, the expected level is only the range's median and the local level is the
/// level). Above the reference's band limit the residual is the platform motion the angles no
/// longer carry, the same in every channel: a random peak of it is in all three at once, and
/// counted as three independent channels it would pass for a tone.
pub(super) fn channel_covariance(
    design: &Design,
    peak: usize,
    r: impl Fn(usize, usize) -> Complex64,
) -> Matrix3<f64> {
    const RIDGE: f64 = 1e-3;
    let n = design.n_bins();
    let lo = peak.saturating_sub(MEDIAN_HALF);
    let hi = (peak + MEDIAN_HALF + 1).min(n);
    let mut sum = Matrix3::<f64>::zeros();
    let mut count = 0.0_f64;
    for k in (lo..hi).filter(|k| k.abs_diff(peak) > HALF_WINDOW) {
        let w = [0, 1, 2].map(|i| r(i, k) / design.expected[i][k].sqrt());
        for i in 0..3 {
            for j in 0..3 {
                sum[(i, j)] += (w[i] * w[j].conj()).re;
            }
        }
        count += 1.0;
    }
    let floor = if design.groups.is_empty() {
        f64::MIN_POSITIVE
    } else {
        1.0
    };
    Matrix3::from_fn(|i, j| {
        let c = sum[(i, j)] / count.max(1.0);
        if i == j { c.max(floor) } else { c * (1.0 - RIDGE) }
    })
}

/// The strongest line in `residual` (band bins, per channel), fitted; `None` when the band is
/// too narrow for a continuum estimate.
#[must_use]
pub fn strongest_line(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    outputs: &[Vec<Complex64>; 3],
) -> Option<Tone> {
    let n = design.n_bins();
    let peaks = searched_peaks(n)?;
    let power: Vec<f64> = (0..n)
        .map(|k| {
            (0..3)
                .map(|i| residual[i][k].norm_sqr() / design.expected[i][k])
                .sum()
        })
        .collect();
    let continuum = continuum(&power);
    // The largest ratios of a line's three bins (a tapered line spreads over them) to the
    // continuum, anywhere in the band: the strongest bins may all be broadband misfit.
    let ratio = |k: usize| (power[k - 1] + power[k] + power[k + 1]) / continuum[k];
    // A line needs its neighbourhood on both sides (its frequency fit, its continuum): within
    // HALF_WINDOW bins of either end of the searched range it cannot be told from the edge of a
    // rising residual (on `--stand real` runs, where the reference's band limit ends the inputs,
    // the residual's ratio to the continuum climbs to the search's top edge).
    let mut order: Vec<usize> = peaks.collect();
    order.sort_by(|&a, &b| ratio(b).total_cmp(&ratio(a)));
    let mut tried: Vec<usize> = Vec::new();
    // A line of the inputs too (a stand programme's sine) leaves a line in the residual for any
    // misfit of the model there, coherent with the input: a tone's regressor at that frequency is
    // the input's own, and a vibration could not be told from that misfit (a sine programme's
    // 7.2 Hz pitch sine on a weakly excited accelerometer: a false tone). Such a peak is passed
    // over, its neighbourhood with it, without counting as a try: a programme of many sines
    // (and their harmonics and sums) would otherwise use every try up.
    let mut input_lines: Vec<usize> = Vec::new();
    for peak in order {
        if tried.len() == MAX_TRIES {
            break;
        }
        if tried
            .iter()
            .chain(&input_lines)
            .any(|&t| t.abs_diff(peak) <= HALF_WINDOW)
        {
            continue;
        }
        if input_line(design, peak) {
            input_lines.push(peak);
            continue;
        }
        tried.push(peak);
        // A line stands above its neighbourhood: a residual that climbs toward the edge of the
        // search has its largest ratio where the window is cut, not at a peak.
        // (The line's own main lobe, two bins each side, may hold the larger ratio by a hair.)
        if (peak - HALF_WINDOW + 1..peak + HALF_WINDOW)
            .filter(|k| k.abs_diff(peak) > 2)
            .any(|k| ratio(k) > ratio(peak))
        {
            continue;
        }
        // A line of the residual that the outputs do not carry is the inputs': a line of the
        // angle measurement or of its processing (on simulated clean runs, 56 Hz in the
        // accelerometer's residual, above the band), not a tone of the sensor.
        let range = peak.saturating_sub(HALF_WINDOW)..(peak + HALF_WINDOW + 1).min(n);
        let frequency_hz = line_frequency(design, residual, peak, &range);
        let in_residual = explain(design, residual, frequency_hz, &range).2;
        let in_outputs = explain(design, outputs, frequency_hz, &range).2;
        if in_outputs >= OUTPUT_SHARE * in_residual {
            return Some(line_at(design, residual, peak, frequency_hz));
        }
    }
    None
}

/// The band bins where [`strongest_line`] looks for a line among `n`: all but [`HALF_WINDOW`] at
/// either end (a line needs its neighbourhood on both sides), and none when the range is too
/// narrow for the continuum's window (`2 MEDIAN_HALF + 1` bins).
pub(super) fn searched_peaks(n: usize) -> Option<std::ops::Range<usize>> {
    (n > 2 * MEDIAN_HALF).then_some(HALF_WINDOW..n - HALF_WINDOW)
}

/// How many of the strongest lines are tried before the search gives up.
const MAX_TRIES: usize = 5;
/// Share of a residual line's power the outputs must carry for it to be the sensor's.
const OUTPUT_SHARE: f64 = 0.5;

/// How far above its local continuum an input axis's power must stand, over a line's three bins,
/// for the inputs to carry a line there: 20 dB. Where the window's median is the continuum's
/// (`ln 2` of its mean), the motion's broadband spectrum reaches it by chance with a probability
/// of about `e^-69` at a given bin (three bins' power above 208 times one bin's mean: even fully
/// correlated, one exponential above 69 of its means); the median, itself estimated over at
/// least `2 HALF_WINDOW + 1` bins, moves that little. A stand programme's sine stands 40-80 dB
/// above.
const INPUT_LINE: f64 = 100.0;

/// Whether an input axis carries a line at band bin `peak`: its power over the line's three
/// bins at least [`INPUT_LINE`] times its median over a window centred on the peak (three bins'
/// worth; up to [`MEDIAN_HALF`] bins each side, fewer near the band's ends, so that a steep
/// spectrum's median is its level at the peak). `false` where the design holds no inputs, or
/// within [`HALF_WINDOW`] bins of the band's ends (too few bins for a median: no line is looked
/// for there either).
fn input_line(design: &Design, peak: usize) -> bool {
    let n = design.n_bins();
    if design.z.len() < U + 3 || peak < HALF_WINDOW || peak + HALF_WINDOW >= n {
        return false;
    }
    let half = MEDIAN_HALF.min(peak).min(n - 1 - peak);
    design.z[U..U + 3].iter().any(|u| {
        let line: f64 = u[peak - 1..=peak + 1].iter().map(Complex64::norm_sqr).sum();
        let mut around: Vec<f64> = u[peak - half..=peak + half]
            .iter()
            .map(Complex64::norm_sqr)
            .collect();
        line > INPUT_LINE * 3.0 * median(&mut around)
    })
}

/// The frequencies, Hz, of the inputs' own lines among the bins the search looks at
/// ([`searched_peaks`], [`input_line`]): where no tone is named. One per line (the bin of most
/// input power within [`HALF_WINDOW`] bins), ascending.
#[must_use]
pub(super) fn input_lines_hz(design: &Design) -> Vec<f64> {
    let n = design.n_bins();
    let Some(peaks) = searched_peaks(n) else {
        return Vec::new();
    };
    if design.z.len() < U + 3 {
        return Vec::new();
    }
    let power: Vec<f64> = (0..n)
        .map(|k| design.z[U..U + 3].iter().map(|u| u[k].norm_sqr()).sum())
        .collect();
    let mut lines: Vec<usize> = Vec::new();
    // A line's bin is a local maximum of the inputs' power: only those are tested.
    for k in peaks.filter(|&k| power[k] >= power[k - 1] && power[k] >= power[k + 1]) {
        if !input_line(design, k) {
            continue;
        }
        match lines.last_mut() {
            Some(last) if k - *last <= HALF_WINDOW => {
                if power[k] > power[*last] {
                    *last = k;
                }
            }
            _ => lines.push(k),
        }
    }
    lines.into_iter().map(|k| design.frequency_hz[k]).collect()
}

/// The frequency of the line at band bin `peak`: where a sinusoid explains most of the
/// residual over `range`, by golden-section search within 1.5 bins of the peak.
fn line_frequency(
    design: &Design,
    residual: &[Vec<Complex64>; 3],
    peak: usize,
    range: &std::ops::Range<usize>,
) -> f64 {
    let df = design.sample_rate_hz / design.fft_len as f64;
    let f_peak = design.frequency_hz[peak];
    let (mut lo, mut hi) = (f_peak - 1.5 * df, f_peak + 1.5 * df);
    let golden = 0.5 * (5.0_f64.sqrt() - 1.0);
    let gain = |f: f64| explain(design, residual, f, range).2;
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
    0.5 * (lo + hi)
}

/// The line at band bin `peak` and `frequency_hz` fitted (gated if it comes and goes), its
/// evidence against the background's covariance there ([`channel_covariance`]).
fn line_at(design: &Design, residual: &[Vec<Complex64>; 3], peak: usize, frequency_hz: f64) -> Tone {
    let n = design.n_bins();
    let range = peak.saturating_sub(HALF_WINDOW)..(peak + HALF_WINDOW + 1).min(n);
    let (c, s) = sinusoid_dft(design, frequency_hz, range.clone());
    let fit = fit_channels(design, residual, (&c, &s), &range);
    let plain = |i: usize, k: usize| residual[i][k];
    let delta_chi2 = 2.0 * fit.evidence(&channel_covariance(design, peak, plain)) / WINDOW_ENBW;
    let (unit_std, channel_chi2) = fit.per_channel(channel_levels(design, peak, plain));
    let constant = Tone {
        frequency_hz,
        cos: fit.cos,
        sin: fit.sin,
        delta_chi2,
        gate: None,
        basis: None,
        upper: false,
        unit_std,
        channel_chi2,
    };
    let Some(gate) = estimate_gate(design, residual, peak, frequency_hz) else {
        return constant;
    };
    // On and off: the gated sinusoid fitted on the whole band (its sidebands included).
    let basis = gated_basis(design, frequency_hz, &gate);
    let all = 0..n;
    let fit = fit_channels(design, residual, (&basis[0], &basis[1]), &all);
    let (cos, sin) = (fit.cos, fit.sin);
    // A gated tone's sidebands fill the bins around its line, so the channels' background there
    // is measured on the residual without it.
    let without = |i: usize, k: usize| residual[i][k] - basis[0][k] * cos[i] - basis[1][k] * sin[i];
    let explained = fit.evidence(&channel_covariance(design, peak, without));
    let (unit_std, channel_chi2) = fit.per_channel(channel_levels(design, peak, without));
    Tone {
        frequency_hz,
        cos,
        sin,
        delta_chi2: 2.0 * explained / WINDOW_ENBW,
        gate: Some(gate),
        basis: Some(Arc::new(basis)),
        upper: false,
        unit_std,
        channel_chi2,
    }
}

/// Each channel's own disturbance level around band bin `peak`, in units of its expected level:
/// the median of `|r_i(k)|^2 / expected` over the continuum's window ([`MEDIAN_HALF`] bins each
/// side, shifted inwards at the ends) over `ln 2` (the median of an exponential), never below
/// the expected level inside the fit's band (there the expected level is the model's disturbance,
/// and a line is never measured against less; above it, [`Design::line_search`] without groups,
/// the expected level is only the range's median, and the local level is the level). `r(i, k)` is the
/// residual the level is read from (without a gated tone's sidebands).
fn channel_levels(design: &Design, peak: usize, r: impl Fn(usize, usize) -> Complex64) -> [f64; 3] {
    let n = design.n_bins();
    let lo = peak
        .saturating_sub(MEDIAN_HALF)
        .min(n.saturating_sub(2 * MEDIAN_HALF + 1));
    let hi = (lo + 2 * MEDIAN_HALF).min(n - 1);
    [0, 1, 2].map(|i| {
        let mut p: Vec<f64> = (lo..=hi)
            .map(|k| r(i, k).norm_sqr() / design.expected[i][k])
            .collect();
        let level = median(&mut p) / std::f64::consts::LN_2;
        if design.groups.is_empty() {
            level.max(f64::MIN_POSITIVE)
        } else {
            level.max(1.0)
        }
    })
}

/// The running median of `power` over [`MEDIAN_HALF`] bins each side (shifted inwards at the
/// band's ends), evaluated every eighth bin and interpolated between: it changes slowly.
fn continuum(power: &[f64]) -> Vec<f64> {
    const STRIDE: usize = 8;
    let n = power.len();
    let at = |k: usize| {
        let lo = k.saturating_sub(MEDIAN_HALF).min(n - 2 * MEDIAN_HALF - 1);
        median(&mut power[lo..=lo + 2 * MEDIAN_HALF].to_vec())
    };
    let knots: Vec<(usize, f64)> = (0..n)
        .step_by(STRIDE)
        .chain(std::iter::once(n - 1))
        .map(|k| (k, at(k)))
        .collect();
    (0..n)
        .map(|k| {
            let j = (k / STRIDE).min(knots.len() - 2);
            let ((a, va), (b, vb)) = (knots[j], knots[j + 1]);
            if b == a {
                va
            } else {
                va + (vb - va) * (k - a) as f64 / (b - a) as f64
            }
        })
        .collect()
}

/// Spectra of the gated, tapered `cos(2 pi f t)` and `sin(2 pi f t)` on the design's band bins.
fn gated_basis(design: &Design, f: f64, gate: &Gate) -> [Vec<Complex64>; 2] {
    let fs = design.sample_rate_hz;
    let mut fft = RecordFft::new(design.fft_len, fs);
    let taper = hann(design.n_samples);
    let band = design.first_bin..=design.first_bin + design.n_bins() - 1;
    let w = 2.0 * PI * f;
    let wave = |phase: f64| -> Vec<f64> {
        (0..design.n_samples)
            .map(|k| {
                let t = k as f64 / fs;
                if gate.is_on(t) { (w * t + phase).cos() } else { 0.0 }
            })
            .collect()
    };
    [
        band_spectrum(&mut fft, &taper, &wave(0.0), band.clone()),
        band_spectrum(&mut fft, &taper, &wave(-0.5 * PI), band),
    ]
}

#[cfg(test)]
#[path = "tone_tests.rs"]
mod tests;
