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
//!   Above it the angles are noise, and a fit there is errors in variables.
//!
//! Units: rad, s, Hz. The default is a perfect stand (none of them), which keeps every existing
//! run's bytes unchanged.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::synth::{Grid, first_order_lowpass};
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
        }
    }

    /// Whether any imperfection is on.
    #[must_use]
    pub fn any(&self) -> bool {
        self.coloured_noise_rad > 0.0 || self.latency_s != 0.0 || self.band_limit_hz.is_some()
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
    if imperfect.coloured_noise_rad > 0.0 {
        let corner = imperfect.coloured_corner_hz.max(1e-3);
        let noise = grid.shape(&grid.white(rng), |f| first_order_lowpass(f, corner));
        let scale = imperfect.coloured_noise_rad / grid.mean_square(&noise).sqrt().max(f64::MIN_POSITIVE);
        spectrum.iter_mut().zip(&noise).for_each(|(s, n)| *s += n * scale);
    }
    grid.fft.inverse(spectrum)
}
