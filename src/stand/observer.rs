//! The optimal observer: estimates the platform's Euler angles, rates and accelerations from the
//! noisy, quantised angle measurements, without adding any delay.
//!
//! Method: a multichannel frequency-domain Wiener smoother over the whole record.
//! 1. Each angle has its least-squares line removed (added back at the end; its slope goes into
//!    the rates), then the record is extended at both ends by an odd (point-symmetric) reflection,
//!    which keeps value and slope continuous, tapered to zero by a half-Hann so the circular
//!    transform sees no jump. The padded length is 2-3-5 smooth.
//! 2. The 3x3 spectral matrix `S_yy` of the measurements is estimated on the record's own FFT grid
//!    by a smoothed cross-periodogram (Daniell window `max(smoothing_hz, smoothing_fraction * f)`
//!    wide).
//! 3. The measurement noise has per-axis variance `N = diag(sigma^2)` per bin. Its white floor is
//!    the declared `angle_noise_rad`, or else estimated from the periodogram's floor between 0.70
//!    and 0.95 of Nyquist (median / ln 2, the median of an exponential being ln 2 times its mean),
//!    and never below [`RESOLUTION_FLOOR`] of the largest axis's motion (numerical resolution).
//!    Given a witness of the motion (the gyro's outputs as Euler rates,
//!    [`observe_with_witness`]), the noise is coloured: per bin, the part of each angle the
//!    witness does not explain, never below the floor ([`super::colour`]). Without one it is the
//!    floor in every bin.
//! 4. The gain per bin is `H = S_uu S_yy^-1 = I - N S_yy^-1`, computed in the noise-whitened basis
//!    with eigenvalues clamped to `[0, 1]`: `H = N^1/2 V diag((1 - 1/l)_+) V^H N^-1/2`.
//!    `H` is Hermitian per bin, with `H(-f) = conj(H(f))`: a zero-phase smoother, so it cannot
//!    shift the estimate in time.
//! 5. Angles, rates and angular accelerations are `H Y`, `j w H Y` and `-w^2 H Y` transformed back.
//!
//! Why a Wiener smoother and not plain differentiation: its estimate is the conditional mean of the
//! true motion given the measurements, so regressing the blocks' outputs on it gives unbiased gains
//! (regression calibration), where noisy differentiated inputs would bias K low (errors in
//! variables), and it suppresses the `w^2`- and `w^4`-amplified angle noise where the motion has
//! no power.
//!
//! Contracts: angles in rad, sample rate in Hz; all three axes must have the same length, at least
//! [`MIN_SAMPLES`], and be finite. Empty or NaN input is an error, never NaN output.

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

use super::colour::{AngleNoise, coloured_noise};
use super::kinematics::EulerSeries;
use crate::fourier::{RecordFft, fast_len};

/// Fewest samples the observer accepts.
pub const MIN_SAMPLES: usize = 64;

/// The white floor is never below this fraction of the largest axis's motion (rms, its line removed),
/// whatever was declared or estimated: far below any angle sensor (a good encoder's noise is
/// 1e-7..1e-6 rad, a small stand motion 1e-2 rad), and at the level of the observer's own
/// artefacts on exactly computed angles (the record's extension rings at 1e-7 of the motion, which
/// is what the floor's estimate reads on such data). A declared `angle_noise_rad` of 0 with a gyro
/// as witness let the noise model give one axis no noise at all beside another's at the gyro's
/// level, and the gain `N^1/2 G N^-1/2` then carried the quiet axis into the noisy one by the
/// ratio of their noises: on an exact simulated run, a 100 Hz oscillation of 1e-3 rad in yaw and
/// an accelerometer gain of 0.02 (`observer_tests`).
pub const RESOLUTION_FLOOR: f64 = 1e-7;

/// Observer settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ObserverSettings {
    /// Standard deviation of one angle sample's measurement noise (quantisation included), rad;
    /// `None` estimates it from the data.
    pub angle_noise_rad: Option<f64>,
    /// Length of the reflected extension at each end, s.
    pub pad_s: f64,
    /// Narrowest spectral smoothing window, Hz.
    pub smoothing_hz: f64,
    /// Smoothing window as a fraction of frequency, where that is wider.
    pub smoothing_fraction: f64,
}

impl Default for ObserverSettings {
    fn default() -> Self {
        Self {
            angle_noise_rad: None,
            pad_s: 2.0,
            smoothing_hz: 0.25,
            smoothing_fraction: 0.05,
        }
    }
}

/// The noise model's shape over frequency.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseColour {
    /// The white level in every bin (no witness of the motion: a run without a gyro block).
    White,
    /// Per bin, the part of the angles the gyro's outputs do not explain, floored at the white
    /// level ([`super::colour`]).
    FromGyro,
}

/// Where the noise level came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// From the run's sidecar (`angle_noise_rad`).
    Declared,
    /// From the high-frequency floor of the measured angles.
    Estimated,
}

/// The observer's estimate of the platform motion.
#[derive(Clone, Debug)]
pub struct ObserverEstimate {
    /// Angles, Euler rates and Euler accelerations, axis order `[roll, yaw, pitch]`.
    pub euler: EulerSeries,
    /// Noise standard deviation used per axis, rad.
    pub angle_noise_rad: [f64; 3],
    /// Where that came from (the white floor).
    pub noise_source: NoiseSource,
    /// Whether the noise model is white or coloured (estimated per frequency).
    pub noise_colour: NoiseColour,
    /// The noise model per frequency: the one-sided density of the angle measurement's noise the
    /// observer assumed, rad^2/Hz per axis, in the bands of [`ErrorPsd`].
    pub angle_noise_psd: ErrorPsd,
    /// The measured angles' one-sided density (their line removed, smoothed as the observer
    /// smooths), rad^2/Hz per axis, in the same bands: against `angle_noise_psd`, the angles'
    /// signal-to-noise ratio per frequency ([`ObserverEstimate::angle_snr`]).
    pub angle_psd: ErrorPsd,
    /// The spectral density of the estimate's error, per angle axis (see [`ErrorPsd`]).
    pub error_psd: ErrorPsd,
    /// With a witness, the white level per axis that bounds the angles' noise from above (what
    /// the gyro leaves unexplained in them, over the auto band's search limits; module
    /// [`super::colour`]), rad; `None` without one.
    pub angle_noise_bound_rad: Option<[f64; 3]>,
    /// With a witness, what it left unexplained above the white floor where the model kept the
    /// floor (below a thousandth of the angles' power, module [`super::colour`]): the angles'
    /// noise may exceed `angle_noise_psd` by up to this, rad^2/Hz per axis in the same bands
    /// (`ident::left_out_noise` turns it into the gains' deviations); `None` without a witness.
    pub angle_noise_left_out_psd: Option<ErrorPsd>,
}

impl ObserverEstimate {
    /// The angles' signal-to-noise ratio per band of [`ErrorPsd`] and axis: the measured angles'
    /// density over the noise model's, less one (the noise's own share), at least 0; a band
    /// without noise is infinitely clean where the angles move, and 0 where they do not.
    /// `([low edge, high edge] Hz, [roll, yaw, pitch])`, ascending. Where it is low the angles are mostly their noise, and the inputs computed
    /// from them hold the motion only as well as the noise model is known
    /// ([`crate::diagnose::noisy_angles`]).
    #[must_use]
    pub fn angle_snr(&self) -> Vec<([f64; 2], [f64; 3])> {
        let (m, n) = (&self.angle_psd, &self.angle_noise_psd);
        m.psd
            .iter()
            .zip(&n.psd)
            .zip(m.edges_hz.windows(2))
            .map(|((s, noise), edge)| {
                let snr = [0, 1, 2].map(|i| {
                    if noise[i] > 0.0 {
                        (s[i] / noise[i] - 1.0).max(0.0)
                    } else if s[i] > 0.0 {
                        f64::INFINITY
                    } else {
                        0.0
                    }
                });
                ([edge[0], edge[1]], snr)
            })
            .collect()
    }
}

/// The one-sided spectral density of the angle estimate's error `theta_hat - theta`, rad^2/Hz,
/// per axis, averaged over bands a twentieth of a decade wide (ascending, positive frequencies).
/// For the Wiener smoother it is `H N` per bin (the part of the angle noise that passes, where
/// the motion is; the motion that is smoothed away, bounded by the noise, where it is not), with
/// `N = 2 sigma^2 / fs` the density of the **white floor**: the coloured part of the noise model
/// cannot be told from the gyro's own noise (module [`super::colour`]), and what takes this error
/// out of a block's residual (its noise terms) must not credit the block with less noise than
/// may be its own. Rates' errors are `w^2` times it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorPsd {
    /// Band centres (geometric), Hz.
    pub frequency_hz: Vec<f64>,
    /// Band edges, Hz (`frequency_hz.len() + 1` values).
    pub edges_hz: Vec<f64>,
    /// Mean density in each band, per axis, rad^2/Hz.
    pub psd: Vec<[f64; 3]>,
}

/// Bands per decade of [`ErrorPsd`].
const ERROR_BANDS_PER_DECADE: f64 = 20.0;

impl ErrorPsd {
    /// Band-averages the per-bin densities `per_bin[k]` on the grid `f_k = k df`.
    fn from_bins(per_bin: &[[f64; 3]], df: f64) -> Self {
        let mut out = Self::default();
        if per_bin.len() < 2 {
            return out;
        }
        let ratio = 10.0_f64.powf(1.0 / ERROR_BANDS_PER_DECADE);
        let mut k = 1;
        let mut lo_edge = 0.5 * df;
        out.edges_hz.push(lo_edge);
        while k < per_bin.len() {
            let hi_edge = (lo_edge * ratio).max(lo_edge + df);
            let mut sum = [0.0; 3];
            let mut count = 0.0;
            while k < per_bin.len() && (k as f64) * df < hi_edge {
                for a in 0..3 {
                    sum[a] += per_bin[k][a];
                }
                count += 1.0;
                k += 1;
            }
            if count > 0.0 {
                out.frequency_hz.push((lo_edge * hi_edge).sqrt());
                out.psd.push(sum.map(|v| v / count));
                out.edges_hz.push(hi_edge);
            } else if let Some(last) = out.edges_hz.last_mut() {
                *last = hi_edge;
            }
            lo_edge = hi_edge;
        }
        out
    }
}

/// Why the observer refused its input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ObserverError {
    /// Fewer samples than [`MIN_SAMPLES`].
    #[error("too few samples for the observer: {n} (at least {min} needed)")]
    TooShort {
        /// Samples given.
        n: usize,
        /// Minimum.
        min: usize,
    },
    /// The three angle columns differ in length.
    #[error("angle column {axis} has {len} samples, roll has {expected}")]
    LengthMismatch {
        /// Axis index (0 roll, 1 yaw, 2 pitch).
        axis: usize,
        /// Its length.
        len: usize,
        /// Roll's length.
        expected: usize,
    },
    /// A NaN or infinity among the angles.
    #[error("angle column {axis} sample {index} is not finite")]
    NonFinite {
        /// Axis index.
        axis: usize,
        /// Sample index.
        index: usize,
    },
    /// Sample rate not positive and finite.
    #[error("sample rate {rate_hz} Hz is not a positive number")]
    BadSampleRate {
        /// The rate given.
        rate_hz: f64,
    },
    /// Declared noise negative or not finite.
    #[error("angle noise {value} rad is not a non-negative number")]
    BadNoise {
        /// The value given.
        value: f64,
    },
}

/// Estimates the platform motion from measured angles `[roll, yaw, pitch]` sampled at
/// `sample_rate_hz`.
///
/// # Errors
/// Fails if the columns differ in length, have fewer than [`MIN_SAMPLES`] samples or a non-finite
/// value, or if the sample rate or declared noise is not a valid number.
pub fn observe(
    angles: [&[f64]; 3],
    sample_rate_hz: f64,
    settings: &ObserverSettings,
) -> Result<ObserverEstimate, ObserverError> {
    observe_with_witness(angles, sample_rate_hz, settings, None)
}

/// [`observe`], with the angle noise's colour estimated from `witness` when one is given: the
/// gyro block's outputs (body rates, rad/s, columns `gx, gy, gz`), the angles' length (module
/// [`super::colour`]; a gyro mounted turned is turned back first, [`super::mount`]). A witness of
/// another length or with a non-finite value is not used.
///
/// # Errors
/// As [`observe`].
pub fn observe_with_witness(
    angles: [&[f64]; 3],
    sample_rate_hz: f64,
    settings: &ObserverSettings,
    witness: Option<[&[f64]; 3]>,
) -> Result<ObserverEstimate, ObserverError> {
    validate(angles, sample_rate_hz, settings)?;
    let n = angles[0].len();
    let pad = ((settings.pad_s * sample_rate_hz).round() as usize).clamp(4, n - 1);
    let mut fft = RecordFft::new(fast_len(n + 2 * pad), sample_rate_hz);
    let taper = half_hann(pad);
    let effective_len = n as f64 + 2.0 * taper.iter().map(|w| w * w).sum::<f64>();

    let witness = witness.filter(|w| w.iter().all(|c| c.len() == n && c.iter().all(|v| v.is_finite())));
    let mut trends = [(0.0, 0.0); 3];
    let mut spectra: [Vec<Complex64>; 3] = Default::default();
    let mut residuals: [Vec<f64>; 3] = Default::default();
    for axis in 0..3 {
        let (offset, slope, residual) = remove_line(angles[axis], sample_rate_hz);
        trends[axis] = (offset, slope);
        spectra[axis] = fft.forward(&extend(&residual, pad, &taper, fft.len()));
        residuals[axis] = residual;
    }

    let (noise_var, noise_source) = match settings.angle_noise_rad {
        Some(sigma) => ([sigma * sigma; 3], NoiseSource::Declared),
        None => (estimate_noise(&spectra, effective_len), NoiseSource::Estimated),
    };
    // The largest axis's motion: relative to each axis's own, a nearly still axis would get no
    // floor beside a moving one, the imbalance the floor is there to bound.
    let floor = residuals.iter().map(|r| resolution_floor(r)).fold(0.0, f64::max);
    let noise_var = noise_var.map(|v| v.max(floor));
    let smoothed = smoothed_cross_periodogram(&spectra, effective_len, &fft, settings);
    let density = 2.0 / sample_rate_hz;
    let df = sample_rate_hz / fft.len() as f64;
    let (noise, noise_colour, angle_noise_bound_rad, angle_noise_left_out_psd) = match witness {
        Some(w) => {
            let smoothing = (settings.smoothing_hz, settings.smoothing_fraction);
            let coloured = coloured_noise(angles, w, &fft, smoothing, noise_var);
            let bound = coloured.bound_rad;
            let left_out: Vec<[f64; 3]> = coloured
                .left_out_per_bin
                .iter()
                .map(|v| v.map(|x| x * density))
                .collect();
            (
                AngleNoise::PerBin(coloured.per_bin),
                NoiseColour::FromGyro,
                bound,
                Some(ErrorPsd::from_bins(&left_out, df)),
            )
        }
        None => (AngleNoise::White(noise_var), NoiseColour::White, None, None),
    };
    let (mut estimate, error_per_bin) = wiener_gain_apply(&spectra, &smoothed, &noise, noise_var);
    let error_psd = ErrorPsd::from_bins(
        &error_per_bin
            .iter()
            .map(|e| e.map(|v| v * density))
            .collect::<Vec<_>>(),
        df,
    );
    let angle_noise_psd = ErrorPsd::from_bins(
        &(0..fft.n_bins())
            .map(|k| noise.at(k).map(|v| v * density))
            .collect::<Vec<_>>(),
        df,
    );

    let angle_psd = ErrorPsd::from_bins(
        &smoothed
            .iter()
            .map(|s| [0, 1, 2].map(|i| s[(i, i)].re * density))
            .collect::<Vec<_>>(),
        df,
    );

    let last = fft.n_bins() - 1;
    if fft.len().is_multiple_of(2) {
        for s in &mut estimate {
            s[last] = Complex64::default();
        }
    }
    let omega: Vec<f64> = (0..fft.n_bins())
        .map(|k| 2.0 * std::f64::consts::PI * fft.frequency_hz(k))
        .collect();
    let mut euler = EulerSeries::default();
    for axis in 0..3 {
        let x = &estimate[axis];
        let rate: Vec<Complex64> = x
            .iter()
            .zip(&omega)
            .map(|(v, w)| v * Complex64::new(0.0, *w))
            .collect();
        let accel: Vec<Complex64> = x.iter().zip(&omega).map(|(v, w)| v * (-w * w)).collect();
        let (offset, slope) = trends[axis];
        let window = |v: Vec<f64>| v[pad..pad + n].to_vec();
        euler.angle[axis] = window(fft.inverse(x.clone()))
            .iter()
            .enumerate()
            .map(|(i, v)| v + offset + slope * i as f64 / sample_rate_hz)
            .collect();
        euler.rate[axis] = window(fft.inverse(rate)).iter().map(|v| v + slope).collect();
        euler.accel[axis] = window(fft.inverse(accel));
    }
    Ok(ObserverEstimate {
        euler,
        angle_noise_rad: noise_var.map(f64::sqrt),
        noise_source,
        noise_colour,
        angle_noise_psd,
        angle_psd,
        error_psd,
        angle_noise_bound_rad,
        angle_noise_left_out_psd,
    })
}

fn validate(angles: [&[f64]; 3], rate: f64, settings: &ObserverSettings) -> Result<(), ObserverError> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(ObserverError::BadSampleRate { rate_hz: rate });
    }
    if let Some(sigma) = settings.angle_noise_rad
        && !(sigma.is_finite() && sigma >= 0.0)
    {
        return Err(ObserverError::BadNoise { value: sigma });
    }
    let expected = angles[0].len();
    for (axis, col) in angles.iter().enumerate() {
        if col.len() != expected {
            return Err(ObserverError::LengthMismatch {
                axis,
                len: col.len(),
                expected,
            });
        }
        if let Some(index) = col.iter().position(|v| !v.is_finite()) {
            return Err(ObserverError::NonFinite { axis, index });
        }
    }
    if expected < MIN_SAMPLES {
        return Err(ObserverError::TooShort {
            n: expected,
            min: MIN_SAMPLES,
        });
    }
    Ok(())
}

/// Least-squares line `x ~ offset + slope t`; returns it and the residual.
pub(super) fn remove_line(x: &[f64], rate: f64) -> (f64, f64, Vec<f64>) {
    let n = x.len() as f64;
    let t_mean = (n - 1.0) / 2.0 / rate;
    let x_mean = x.iter().sum::<f64>() / n;
    let (mut sxt, mut stt) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        let dt = i as f64 / rate - t_mean;
        sxt += dt * (v - x_mean);
        stt += dt * dt;
    }
    let slope = if stt > 0.0 { sxt / stt } else { 0.0 };
    let offset = x_mean - slope * t_mean;
    let residual = x
        .iter()
        .enumerate()
        .map(|(i, v)| v - offset - slope * i as f64 / rate)
        .collect();
    (offset, slope, residual)
}

/// The white floor's least variance on an axis whose angles, their line removed, are `residual`:
/// [`RESOLUTION_FLOOR`] of their rms, squared.
fn resolution_floor(residual: &[f64]) -> f64 {
    let mean_square = residual.iter().map(|v| v * v).sum::<f64>() / residual.len().max(1) as f64;
    RESOLUTION_FLOOR * RESOLUTION_FLOOR * mean_square
}

/// Weights rising from near 0 (far end of a pad) to near 1 (next to the data), flat at both ends.
fn half_hann(pad: usize) -> Vec<f64> {
    (0..pad)
        .map(|j| 0.5 - 0.5 * (std::f64::consts::PI * (j + 1) as f64 / (pad + 1) as f64).cos())
        .collect()
}

/// `[tapered left reflection | data | tapered right reflection | zeros]`, `total` samples.
fn extend(r: &[f64], pad: usize, taper: &[f64], total: usize) -> Vec<f64> {
    let n = r.len();
    let mut e = vec![0.0; total];
    e[pad..pad + n].copy_from_slice(r);
    for k in 1..=pad {
        let w = taper[pad - k];
        e[pad - k] = w * (2.0 * r[0] - r[k]);
        e[pad + n - 1 + k] = w * (2.0 * r[n - 1] - r[n - 1 - k]);
    }
    e
}

fn estimate_noise(spectra: &[Vec<Complex64>; 3], effective_len: f64) -> [f64; 3] {
    spectra.each_ref().map(|s| {
        let (lo, hi) = ((s.len() as f64 * 0.70) as usize, (s.len() as f64 * 0.95) as usize);
        let mut p: Vec<f64> = s[lo..hi.max(lo + 1)]
            .iter()
            .map(|v| v.norm_sqr() / effective_len)
            .collect();
        let mid = p.len() / 2;
        let (_, median, _) = p.select_nth_unstable_by(mid, f64::total_cmp);
        *median / std::f64::consts::LN_2
    })
}

/// Half-width in bins of the Daniell window at `f_hz`, `max(smoothing_hz, smoothing_fraction f)`
/// wide (`(smoothing_hz, smoothing_fraction)`), at least one bin each side.
pub(super) fn daniell_half_width(
    (smoothing_hz, smoothing_fraction): (f64, f64),
    f_hz: f64,
    bins_per_hz: f64,
) -> usize {
    let width = smoothing_hz.max(smoothing_fraction * f_hz);
    ((width * bins_per_hz / 2.0) as usize).max(1)
}

/// Daniell-smoothed cross-periodogram `Y Y^H / L_eff` per bin, via prefix sums.
fn smoothed_cross_periodogram(
    spectra: &[Vec<Complex64>; 3],
    effective_len: f64,
    fft: &RecordFft,
    settings: &ObserverSettings,
) -> Vec<Matrix3<Complex64>> {
    let bins = fft.n_bins();
    let mut prefix = Vec::with_capacity(bins + 1);
    let mut acc = Matrix3::<Complex64>::zeros();
    prefix.push(acc);
    for k in 0..bins {
        let y = Vector3::new(spectra[0][k], spectra[1][k], spectra[2][k]);
        acc += y * y.adjoint() / Complex64::from(effective_len);
        prefix.push(acc);
    }
    let bins_per_hz = fft.len() as f64 / fft.sample_rate_hz();
    (0..bins)
        .map(|k| {
            let half = daniell_half_width(
                (settings.smoothing_hz, settings.smoothing_fraction),
                fft.frequency_hz(k),
                bins_per_hz,
            );
            let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(bins));
            (prefix[hi] - prefix[lo]) / Complex64::from((hi - lo) as f64)
        })
        .collect()
}

/// Applies `H = N^1/2 V diag((1 - 1/l)_+) V^H N^-1/2` per bin to the measured spectra (`N` the
/// noise model's level in that bin); also returns the diagonal of `H N_white` per bin
/// (per-sample variance units), the part of the white floor that passes ([`ErrorPsd`]).
fn wiener_gain_apply(
    spectra: &[Vec<Complex64>; 3],
    smoothed: &[Matrix3<Complex64>],
    noise: &AngleNoise,
    white: [f64; 3],
) -> ([Vec<Complex64>; 3], Vec<[f64; 3]>) {
    let white_diag = Matrix3::from_diagonal(&Vector3::from(white).map(Complex64::from));
    let floor = smoothed.iter().map(|s| s.trace().re).fold(0.0, f64::max) * 1e-30;
    let mut out: [Vec<Complex64>; 3] = Default::default();
    for o in &mut out {
        o.reserve(smoothed.len());
    }
    let mut error = Vec::with_capacity(smoothed.len());
    for (k, s) in smoothed.iter().enumerate() {
        let sd = noise.at(k).map(|v| v.max(floor).max(f64::MIN_POSITIVE).sqrt());
        let n_half = Matrix3::from_diagonal(&Vector3::from(sd).map(Complex64::from));
        let n_half_inv = Matrix3::from_diagonal(&Vector3::from(sd.map(f64::recip)).map(Complex64::from));
        let whitened = n_half_inv * s * n_half_inv;
        let eig = whitened.symmetric_eigen();
        let gains = eig.eigenvalues.map(|l| {
            if l > 1.0 {
                Complex64::from(1.0 - 1.0 / l)
            } else {
                Complex64::default()
            }
        });
        let h = n_half
            * eig.eigenvectors
            * Matrix3::from_diagonal(&gains)
            * eig.eigenvectors.adjoint()
            * n_half_inv;
        let x = h * Vector3::new(spectra[0][k], spectra[1][k], spectra[2][k]);
        for axis in 0..3 {
            out[axis].push(x[axis]);
        }
        let e = h * white_diag;
        error.push([e[(0, 0)].re, e[(1, 1)].re, e[(2, 2)].re]);
    }
    (out, error)
}

#[cfg(test)]
#[path = "observer_tests.rs"]
mod tests;
