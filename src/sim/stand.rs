//! Imperfections of a real stand's angle measurement, each selectable, so the identifier is tested
//! on data that do not share its assumptions (white angle noise, no latency, no band limit):
//!
//! - **coloured angle noise**: a first-order low-passed noise of the given rms and corner on each
//!   axis (optical references and encoder interpolation errors are coloured, not white);
//! - **latency**: the measured angle is the platform angle `latency_s` late. The identified delay
//!   is then relative to the late measurement (contract: the angles' own latency is taken as
//!   zero), so the block's delay comes out `latency_s` shorter;
//! - **band limit**: the measured angle carries nothing above `band_limit_hz` (a zero-phase
//!   eighth-order Butterworth magnitude, as a reference resampled by symmetric interpolation).
//!   Above it the angles are noise, and a fit there is errors in variables;
//! - **a causal filter**: the measured angle through a second-order Butterworth low-pass at
//!   `filter_hz` (an encoder's or a tracker's own filter). Unlike the band limit it has phase: the
//!   angles lag the motion by its group delay (`sqrt(2) / (2 pi filter_hz)` at low frequency) and
//!   more towards the band's top, so the block's response to them has zeros that lead (the
//!   identifier says so, `zeros_lead`);
//! - **a slower reference**: the measured angle sampled at `reference_rate_hz` and interpolated
//!   linearly onto the run's samples, as a motion-capture reference is resampled onto an IMU's
//!   (the real recordings' dataset did so from 120 Hz). Zero phase, no delay: on average it weighs
//!   the motion by `sinc^2(f / f_r)`, `1 - (pi f / f_r)^2 / 3` at low frequency, so the gain
//!   measured against it rises across the band (found by a helper's independent hand-held
//!   simulator; the identifier says so, `ident::gain_curvature`). The reference's samples are read
//!   off the run's grid by a cubic (Catmull-Rom) interpolation, whose own smoothing is of order
//!   `(f / f_s)^4`. The coloured noise is resampled with the angles; the white angle noise and
//!   the quantisation are added after, at the run's rate (an encoder's, not the reference's). A
//!   rate at or above the run's has no effect (`through_slower_reference` returns the angles as
//!   they are; the command line refuses it).
//!
//! Units: rad, s, Hz. The default is a perfect stand (none of them), which keeps every existing
//! run's bytes unchanged.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::synth::{Grid, butterworth2, first_order_lowpass};
use crate::rng::Rng;

/// The stand's angle-measurement imperfections (all off by default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StandImperfections {
    /// Rms of the coloured angle noise per axis, rad (0: none).
    pub coloured_noise_rad: f64,
    /// Corner of the coloured noise's first-order low-pass, Hz.
    pub coloured_corner_hz: f64,
    /// Latency of the angle measurement, s (0: none).
    pub latency_s: f64,
    /// Band limit of the angle measurement, Hz (`None`: none).
    pub band_limit_hz: Option<f64>,
    /// Rate of a slower reference, Hz (`None`: the angles are measured at every sample): the
    /// measured angle is sampled at this rate and interpolated linearly onto the run's samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_rate_hz: Option<f64>,
    /// Corner of a causal second-order Butterworth filter on the angle measurement, Hz (`None`:
    /// none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter_hz: Option<f64>,
}

impl StandImperfections {
    /// What a real stand (or an optical reference) typically has, for `--stand real`: coloured
    /// noise of 3e-5 rad rms below 5 Hz, 1.5 ms of latency, a band limit at 30 Hz.
    #[must_use]
    pub fn real() -> Self {
        Self {
            coloured_noise_rad: 3e-5,
            coloured_corner_hz: 5.0,
            latency_s: 1.5e-3,
            band_limit_hz: Some(30.0),
            reference_rate_hz: None,
            filter_hz: None,
        }
    }

    /// Whether any imperfection is on.
    #[must_use]
    pub fn any(&self) -> bool {
        self.coloured_noise_rad > 0.0
            || self.latency_s != 0.0
            || self.band_limit_hz.is_some()
            || self.reference_rate_hz.is_some()
            || self.filter_hz.is_some()
    }
}

/// The measured angle of one axis on the grid: `angle` (time domain, grid length) delayed and
/// band-limited as `imperfect` says, plus its coloured noise (drawn from `rng`).
pub(super) fn measured_angle(
    grid: &mut Grid,
    angle: &[f64],
    imperfect: &StandImperfections,
    rng: &mut Rng,
) -> Vec<f64> {
    if !imperfect.any() {
        return angle.to_vec();
    }
    let spectrum = grid.fft.forward(angle);
    let mut spectrum = grid.delay(&spectrum, imperfect.latency_s);
    if let Some(fb) = imperfect.band_limit_hz {
        spectrum = grid.shape(&spectrum, |f| {
            Complex64::from(1.0 / (1.0 + (f / fb).powi(16)).sqrt())
        });
    }
    if let Some(fc) = imperfect.filter_hz {
        spectrum = grid.shape(&spectrum, |f| butterworth2(f, fc));
    }
    if imperfect.coloured_noise_rad > 0.0 {
        let corner = imperfect.coloured_corner_hz.max(1e-3);
        let noise = grid.shape(&grid.white(rng), |f| first_order_lowpass(f, corner));
        let scale = imperfect.coloured_noise_rad / grid.mean_square(&noise).sqrt().max(f64::MIN_POSITIVE);
        spectrum.iter_mut().zip(&noise).for_each(|(s, n)| *s += n * scale);
    }
    let measured = grid.fft.inverse(spectrum);
    match imperfect.reference_rate_hz {
        Some(rate) => through_slower_reference(&measured, grid.fft.sample_rate_hz(), rate),
        None => measured,
    }
}

/// `x`, sampled at `fs`, as a reference at `reference_hz` sees it (module docs): read at the
/// reference's instants `j / reference_hz` (Catmull-Rom), then interpolated linearly back onto
/// `x`'s samples. Fewer than two samples, or a rate not within `(0, fs)`, return `x` as it is.
pub(super) fn through_slower_reference(x: &[f64], fs: f64, reference_hz: f64) -> Vec<f64> {
    let n = x.len();
    if n < 2 || !(reference_hz > 0.0 && reference_hz < fs) {
        return x.to_vec();
    }
    let at = |i: isize| x[i.clamp(0, n as isize - 1) as usize];
    let cubic = |p: f64| {
        let i = p.floor();
        let t = p - i;
        let i = i as isize;
        let (a, b, c, d) = (at(i - 1), at(i), at(i + 1), at(i + 2));
        b + 0.5 * t * (c - a + t * (2.0 * a - 5.0 * b + 4.0 * c - d + t * (3.0 * (b - c) + d - a)))
    };
    let step = fs / reference_hz;
    let m = ((n - 1) as f64 / step).floor() as usize + 2;
    let reference: Vec<f64> = (0..m).map(|j| cubic(j as f64 * step)).collect();
    (0..n)
        .map(|i| {
            let q = i as f64 / step;
            let j = (q.floor() as usize).min(m - 2);
            let t = q - j as f64;
            (1.0 - t) * reference[j] + t * reference[j + 1]
        })
        .collect()
}
