//! The witness's own noise: the gyro's white floor, seen through the witness, taken out of what
//! the witness leaves unexplained ([`super::colour`]).
//!
//! The witness `w` measures the motion `u` through the gyro's response `B` with the gyro's own
//! noise `e`: `w = B u + e`. What the witness leaves unexplained of the angles `y = u + n`,
//! `N_c = S_yy - S_yw S_ww^-1 S_wy`, is then the angles' noise `n` and the gyro's noise as the
//! fit sees it, `S_yw ((S_ww - S_e)^-1 - S_ww^-1) S_wy` (for one witness axis exactly
//! `S_u S_e / S_ww`: the excess over what a noiseless witness would leave); that part is taken
//! out (`super::colour_window`, each axis's `S_e` at most half its `S_ww`: where the witness is
//! mostly its own noise it says little, and the excess's factor `S_ww / (S_ww - S_e)` would grow
//! without bound). Where the gyro's response is flat the part is small and falls with frequency
//! in rate units (`super::colour`'s drift rule takes its low-frequency part out). Where the
//! gyro's own filter cuts its signal inside the band and its noise enters after it (a sensing
//! element's bandwidth before the read-out's noise), it grows as `1 / |B|^2`: the unexplained
//! part rose as the signal fell, it was taken for angle noise, and the observer shrank both
//! blocks' inputs by the gyro's noise-to-signal ratio there (above a gyro's mount resonance too).
//! Measured (30 Nov, a 20 Hz second-order Butterworth on both blocks, `simulate
//! --sensor-filter-hz 20`, 12 runs, seeds 8401-8406, cruise and approach): the gyro's response
//! estimate read 0.6 % high at 20-25 Hz and 10 % at 35-40 Hz, and every order-2 fit put zeros
//! leading or lagging beside a delay 0.4-1.0 ms off (delay z rms 8.8 gyro, 11.5 accelerometer);
//! the same accelerometer without a gyro in the run (white angle-noise model) read its delay
//! within 3 us. With the floor out: the response flat within 1 % to 40 Hz, delay z rms 1.0 and
//! 0.6, no zeros said (with a 15 Hz filter and white gyro noise: 11.4 and 24.3 before, 1.8 and
//! 0.7 after; the first-order form `c S_e c^H`, `c = S_yw S_ww^-1`, left 2.2 and 2.2).
//!
//! Only inside the band searched (to 40 Hz, [`super::colour::BOUND_BAND_HZ`], at most `0.4 fs`),
//! where the blocks are fitted. Above it the witness is mostly its own noise and taking its part
//! out lowered the model to the angles' white floor there: the observer passed the angles' noise
//! above the band into the inputs, and a nonlinear regressor (an accelerometer's `k2`, `u |u|`)
//! folded it into the band: on four `--stand real` runs (seeds 62-65, 120 s) the stated `k2`
//! limits fell by up to half (the regressor's power, not the motion's) while the evidence of a
//! `k2` injected at 1.5 times them was named or said on 4 of 12 channels (10 of 12 before); with
//! the band's top, the limits are the old ones within 0.1 %.
//!
//! The floor: per witness axis, in rate units, the median periodogram level of the witness's
//! Euler rates between 0.70 and 0.95 of Nyquist (where a stand's motion has no power; the
//! identifier reads a gyro's white floor there too, `ident::witness_noise`), over `ln 2` (the
//! median of an exponential variable), then carried to angle units by the witness's trapezoid
//! integration, `|H(f)|^2 = (cot(pi f / fs) / (2 fs))^2`. A gyro whose noise is filtered with its
//! signal has a lower floor there than in the band: less is taken out, the side the model errs on
//! without it. A floor the motion reaches (a record sampled barely above the motion's band) is
//! too high: the unexplained part is clamped at the white floor of the angles, as before.
//!
//! Units: rate floors in (rad/s)^2 per sample (periodogram levels of the Hann-windowed record,
//! `sum w^2` normalised), angle floors in rad^2 per sample. A record without bins between 0.70 and
//! 0.95 of Nyquist, or with non-finite levels there, has no floor (`None`: nothing taken out).

use std::f64::consts::PI;

use super::witness_delay::hann_windowed;
use crate::fourier::RecordFft;

/// The gyro's white floor as the witness carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct WitnessFloor {
    /// Per witness axis, the Euler rates' white level, (rad/s)^2 per sample.
    pub rate_level: [f64; 3],
    /// The record's sample rate, Hz.
    pub sample_rate_hz: f64,
    /// The highest frequency it is taken out at, Hz: the band searched's top.
    pub top_hz: f64,
}

impl WitnessFloor {
    /// The floor of the witness's Euler `rates` (one stretch), on `fft`'s grid, the Hann
    /// window's `sum w^2` being `power_norm`.
    pub(super) fn of_rates(rates: &[Vec<f64>; 3], fft: &mut RecordFft, power_norm: f64) -> Option<Self> {
        let rate = fft.sample_rate_hz();
        let nyquist = 0.5 * rate;
        let top: Vec<usize> = (0..fft.n_bins())
            .filter(|&k| (0.70 * nyquist..=0.95 * nyquist).contains(&fft.frequency_hz(k)))
            .collect();
        if top.is_empty() || power_norm <= 0.0 {
            return None;
        }
        let mut levels = [0.0; 3];
        for (level, r) in levels.iter_mut().zip(rates) {
            let spectrum = fft.forward(&hann_windowed(r, fft.len()));
            let mut at_top: Vec<f64> = top.iter().map(|&k| spectrum[k].norm_sqr()).collect();
            at_top.sort_by(f64::total_cmp);
            *level = at_top[at_top.len() / 2] / std::f64::consts::LN_2 / power_norm;
        }
        levels.iter().all(|v| v.is_finite()).then_some(Self {
            rate_level: levels,
            sample_rate_hz: rate,
            top_hz: super::colour::BOUND_BAND_HZ[1].min(0.4 * rate),
        })
    }

    /// The floor in the witness's angle units at `f_hz` (through its trapezoid integration).
    pub(super) fn in_angle_units(&self, f_hz: f64) -> [f64; 3] {
        let fs = self.sample_rate_hz;
        let x = PI * f_hz / fs;
        let gain = if x > 0.0 {
            0.5 / (fs * x.tan())
        } else {
            f64::INFINITY
        };
        self.rate_level.map(|v| v * gain * gain)
    }
}

#[cfg(test)]
#[path = "witness_floor_tests.rs"]
mod tests;
