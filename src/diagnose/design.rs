//! The diagnosis's data: whole-record spectra of a block's output `x`, its input `u`, the
//! quadratic regressors `u_i |u_i|` and the block's auxiliary regressors (the specific force at
//! the gyro block; the specific force's sensitivity to the accelerometer's lever arm), on the
//! analysis band's bins, plus the disturbance level each output bin is expected to have.
//!
//! Conventions: unnormalised DFT of the mean-removed record tapered by a Hann window over the
//! whole record (`w_n = (1 - cos(2 pi n / N)) / 2`) and zero-padded to `fft_len`
//! (`X_k = sum_n w_n x_n e^{-2 pi i k n / fft_len}`), one-sided bins `f_k = k fs / fft_len` inside
//! the band, ascending. For a disturbance of one-sided density `S(f)` the expected periodogram
//! level is `E|X_k|^2 = (3/8) N fs S(f_k) / 2` (`sum w^2 = 3N/8`), which is what
//! [`Design::expected`] holds. The taper matters: without it the strong low-frequency motion
//! leaks through the rectangular window's `1/f` sidelobes into bins where the model's phase
//! differs, and the model seems to miss power it does not miss. Neighbouring bins of the tapered
//! record are correlated; [`WINDOW_ENBW`] (1.5 bins) converts sums over bins into degrees of
//! freedom.
//!
//! Consecutive bins are pooled in groups (Daniell smoothing) for the fits of the structural
//! effects: within a group (about 0.05 Hz wide) every model factor is constant to well under a
//! per cent, so a group's Gram matrix `Z_g[r][s] = sum_k conj(z_r(k)) z_s(k)` carries all the fit
//! needs. The grouped sums are exact sums of squares: no information is lost for factors that are
//! constant within the group.

use std::sync::Arc;

use nalgebra::DMatrix;
use num_complex::Complex64;

use crate::block::Block;
use crate::fourier::{RecordFft, fast_len};

/// Index of the first output channel in [`Design::z`].
pub const X: usize = 0;
/// Index of the first input channel.
pub const U: usize = 3;
/// Index of the first quadratic regressor `u_i |u_i|`.
pub const Q: usize = 6;
/// Index of the first auxiliary regressor: gyro `f_j` at the block (3), accelerometer
/// `d f_i / d r_l` at `AUX + 3 i + l` (9).
pub const AUX: usize = 9;

/// Equivalent noise bandwidth of the Hann window, bins: a sum of whitened `|e_k|^2` over the band
/// carries `2 / WINDOW_ENBW` real degrees of freedom per bin.
pub const WINDOW_ENBW: f64 = 1.5;

/// Target number of groups in the band.
const TARGET_GROUPS: usize = 800;

/// One block's whole-record spectra on the band.
#[derive(Clone, Debug)]
pub struct Design {
    /// Which block.
    pub block: Block,
    /// Samples in the record.
    pub n_samples: usize,
    /// DFT length (the record zero-padded to a fast length).
    pub fft_len: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Index of the first band bin on the DFT grid.
    pub first_bin: usize,
    /// Frequency of each band bin, Hz.
    pub frequency_hz: Vec<f64>,
    /// Spectra per channel (outputs as measured, then regressors), each over the band bins.
    pub z: Vec<Vec<Complex64>>,
    /// Expected disturbance periodogram level per output channel and band bin.
    pub expected: [Vec<f64>; 3],
    /// Bin ranges of the groups.
    pub groups: Vec<std::ops::Range<usize>>,
    /// Centre frequency of each group, Hz.
    pub group_hz: Vec<f64>,
    /// Mean expected level per output channel and group.
    pub group_expected: [Vec<f64>; 3],
    /// The measured outputs in time, as recorded (for re-timing them: [`Design::clock_corrected`]).
    pub record: Arc<[Vec<f64>; 3]>,
}

/// Time-domain signals the design is built from, all the same length.
pub struct DesignSignals<'a> {
    /// Which block.
    pub block: Block,
    /// Measured outputs.
    pub output: [&'a [f64]; 3],
    /// Inputs computed from the measured angles.
    pub input: [&'a [f64]; 3],
    /// Auxiliary regressors (3 for the gyro block, 9 for the accelerometer block).
    pub auxiliary: &'a [&'a [f64]],
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

impl Design {
    /// Builds the design over `band_hz`; `expected_psd(i, f)` is the one-sided disturbance density
    /// the model expects on output `i` at `f` (units^2/Hz). Returns `None` when the band holds
    /// fewer than 16 bins of the record (the record is too short for a diagnosis).
    pub fn new(
        signals: &DesignSignals<'_>,
        band_hz: [f64; 2],
        expected_psd: &dyn Fn(usize, f64) -> f64,
    ) -> Option<Self> {
        let n = signals.output[0].len();
        let fs = signals.sample_rate_hz;
        let (mut fft, band) = record_band(n, fs, band_hz, 16)?;
        let (fft_len, first_bin, df) = (fft.len(), *band.start(), fs / fft.len() as f64);
        let taper = hann(n);
        let mut spectrum = |x: &[f64]| band_spectrum(&mut fft, &taper, x, band.clone());
        let mut z: Vec<Vec<Complex64>> = Vec::new();
        z.extend(signals.output.iter().map(|x| spectrum(x)));
        z.extend(signals.input.iter().map(|u| spectrum(u)));
        for u in signals.input {
            let q: Vec<f64> = u.iter().map(|v| v * v.abs()).collect();
            z.push(spectrum(&q));
        }
        z.extend(signals.auxiliary.iter().map(|a| spectrum(a)));
        let frequency_hz: Vec<f64> = band.clone().map(|k| k as f64 * df).collect();
        let level = 0.375 * n as f64 * fs / 2.0;
        let expected = [0, 1, 2].map(|i| {
            frequency_hz
                .iter()
                .map(|&f| (expected_psd(i, f) * level).max(f64::MIN_POSITIVE))
                .collect::<Vec<f64>>()
        });
        let width = frequency_hz.len().div_ceil(TARGET_GROUPS).max(1);
        let groups: Vec<_> = (0..frequency_hz.len())
            .step_by(width)
            .map(|a| a..(a + width).min(frequency_hz.len()))
            .collect();
        let group_hz = groups
            .iter()
            .map(|g| 0.5 * (frequency_hz[g.start] + frequency_hz[g.end - 1]))
            .collect();
        let group_expected = expected.each_ref().map(|e| {
            groups
                .iter()
                .map(|g| e[g.clone()].iter().sum::<f64>() / g.len() as f64)
                .collect()
        });
        Some(Self {
            block: signals.block,
            n_samples: n,
            fft_len,
            sample_rate_hz: fs,
            first_bin,
            frequency_hz,
            z,
            expected,
            groups,
            group_hz,
            group_expected,
            record: Arc::new(signals.output.map(<[f64]>::to_vec)),
        })
    }

    /// The design with the outputs re-timed for a block clock running at `1 + drift` against the
    /// stand's: the output the stand's clock puts at `t` was stamped `t_c + (t - t_c)(1 + drift)`
    /// by the block, `t_c` the record's middle (so the mean delay is unchanged). Sample positions
    /// fall between samples; [`crate::interp::sinc`] interpolates them. Everything but the
    /// outputs' spectra is kept.
    #[must_use]
    pub fn clock_corrected(&self, drift: f64) -> Self {
        let n = self.n_samples;
        let mut fft = RecordFft::new(self.fft_len, self.sample_rate_hz);
        let taper = hann(n);
        let band = self.first_bin..=self.first_bin + self.n_bins() - 1;
        let centre = 0.5 * (n as f64 - 1.0);
        let mut next = self.clone();
        // Content well below Nyquist (the band's top under a tenth of the rate) is re-timed by
        // the 8-point Lagrange polynomial (error under 3e-5 there), eight times cheaper than the
        // 64-tap sinc that records sampled close to their band need.
        let fs = self.sample_rate_hz;
        let smooth = self.frequency_hz.last().is_some_and(|&top| top <= 0.1 * fs);
        for (i, x) in self.record.iter().enumerate() {
            let retimed: Vec<f64> = (0..n)
                .map(|k| {
                    let pos = centre + (k as f64 - centre) * (1.0 + drift);
                    if smooth {
                        crate::interp::lagrange(x, fs, pos / fs)
                    } else {
                        crate::interp::sinc(x, pos)
                    }
                })
                .collect();
            next.z[X + i] = band_spectrum(&mut fft, &taper, &retimed, band.clone());
        }
        next
    }

    /// Number of band bins.
    #[must_use]
    pub fn n_bins(&self) -> usize {
        self.frequency_hz.len()
    }

    /// Real degrees of freedom per output channel: two per independent complex bin (the
    /// zero-padding makes `fft_len / n_samples` bins per independent one, the taper
    /// [`WINDOW_ENBW`] more).
    #[must_use]
    pub fn dof_per_channel(&self) -> f64 {
        2.0 * self.n_bins() as f64 * self.n_samples as f64 / self.fft_len as f64 / WINDOW_ENBW
    }

    /// Group Gram matrices of `z` with the outputs replaced by `outputs` (the measured outputs
    /// minus any fitted tones).
    #[must_use]
    pub fn grams(&self, outputs: &[Vec<Complex64>; 3]) -> Vec<DMatrix<Complex64>> {
        let d = self.z.len();
        let column = |c: usize| if c < U { &outputs[c] } else { &self.z[c] };
        self.groups
            .iter()
            .map(|g| {
                let mut m = DMatrix::<Complex64>::zeros(d, d);
                for r in 0..d {
                    let zr = &column(r)[g.clone()];
                    for s in r..d {
                        let zs = &column(s)[g.clone()];
                        let v: Complex64 = zr.iter().zip(zs).map(|(a, b)| a.conj() * b).sum();
                        m[(r, s)] = v;
                        m[(s, r)] = v.conj();
                    }
                }
                m
            })
            .collect()
    }

    /// The outputs' and inputs' whole-record spectra over `band_hz`, for the line search
    /// beyond the fit's band (`z` holds the outputs at [`X`] and the inputs at [`U`]; no other
    /// regressors, no groups). The expected level is set by [`Design::set_line_level`] once the
    /// model's part is known. `None` when the range holds fewer than 256 bins.
    #[must_use]
    pub fn line_search(
        block: Block,
        output: [&[f64]; 3],
        input: [&[f64]; 3],
        sample_rate_hz: f64,
        band_hz: [f64; 2],
    ) -> Option<Self> {
        let n = output[0].len();
        let fs = sample_rate_hz;
        let (mut fft, band) = record_band(n, fs, band_hz, 256)?;
        let (fft_len, first_bin, df) = (fft.len(), *band.start(), fs / fft.len() as f64);
        let taper = hann(n);
        let z: Vec<Vec<Complex64>> = output
            .into_iter()
            .chain(input)
            .map(|x| band_spectrum(&mut fft, &taper, x, band.clone()))
            .collect();
        let bins = z[0].len();
        Some(Self {
            block,
            n_samples: n,
            fft_len,
            sample_rate_hz: fs,
            first_bin,
            frequency_hz: band.map(|k| k as f64 * df).collect(),
            z,
            expected: [vec![1.0; bins], vec![1.0; bins], vec![1.0; bins]],
            groups: Vec::new(),
            group_hz: Vec::new(),
            group_expected: [Vec::new(), Vec::new(), Vec::new()],
            record: Arc::new(output.map(<[f64]>::to_vec)),
        })
    }

    /// The line search's residual, outputs minus `K e^(-tau s)` times the inputs, and its
    /// expected level set to each channel's median periodogram of it.
    pub fn set_line_level(&mut self, k: [[f64; 3]; 3], tau_s: f64) -> [Vec<Complex64>; 3] {
        let residual = [0, 1, 2].map(|i| {
            self.frequency_hz
                .iter()
                .enumerate()
                .map(|(b, &f)| {
                    let delay = Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * tau_s);
                    let model: Complex64 = (0..3).map(|j| self.z[U + j][b] * k[i][j]).sum();
                    self.z[X + i][b] - delay * model
                })
                .collect::<Vec<_>>()
        });
        for (i, r) in residual.iter().enumerate() {
            let mut p: Vec<f64> = r.iter().map(Complex64::norm_sqr).collect();
            let level = super::tone::median(&mut p).max(f64::MIN_POSITIVE);
            self.expected[i] = vec![level; r.len()];
        }
        residual
    }

    /// The outputs' spectra (as measured, or re-timed by [`Design::clock_corrected`]).
    #[must_use]
    pub fn outputs(&self) -> [Vec<Complex64>; 3] {
        [0, 1, 2].map(|i| self.z[X + i].clone())
    }
}

/// The DFT plans of a record of `n` samples at `fs` (zero-padded to a fast length) and its bins
/// inside `band_hz`; `None` when fewer than `min_bins` bins fall inside.
fn record_band(
    n: usize,
    fs: f64,
    band_hz: [f64; 2],
    min_bins: usize,
) -> Option<(RecordFft, std::ops::RangeInclusive<usize>)> {
    let fft = RecordFft::new(fast_len(n), fs);
    let df = fs / fft.len() as f64;
    let first_bin = ((band_hz[0] / df).ceil() as usize).max(1);
    let last_bin = ((band_hz[1] / df).floor() as usize).min(fft.n_bins() - 1);
    (last_bin >= first_bin + min_bins).then_some((fft, first_bin..=last_bin))
}

/// The periodic Hann taper over `n` samples, `w_k = (1 - cos(2 pi k / n)) / 2`.
pub(super) fn hann(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
        .collect()
}

/// The band bins of the DFT of `x` mean-removed and tapered.
pub(super) fn band_spectrum(
    fft: &mut RecordFft,
    taper: &[f64],
    x: &[f64],
    band: std::ops::RangeInclusive<usize>,
) -> Vec<Complex64> {
    let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
    let centred: Vec<f64> = x.iter().zip(taper).map(|(v, w)| (v - mean) * w).collect();
    fft.forward(&centred)[band].to_vec()
}
