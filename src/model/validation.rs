//! Validation: a block model's predicted outputs over the measured ones in time, and how much of
//! the measured motion they explain (the idea of MATLAB's `compare`), on the run the model was
//! identified on or on another run of the same unit.
//!
//! The prediction is `H u` ([`crate::noise::residual`]: the model driven by the run's input
//! estimate, applied on the whole span in the frequency domain, zero-padded). Both it and the
//! measured outputs are then low-passed at the top of the model's band (a raised-cosine roll-off
//! from `band_hz[1]` to [`ROLL_OFF`] times it, on the same transform) with their means removed:
//! above the band the model is not vouched for and the outputs are mostly sensor noise, and a
//! bias is not dynamics. Below the band nothing is filtered (a high-pass that low rings for
//! seconds; what is there, a gyro's drift, is the sensor's and shows in the residual). Dropped:
//! the first samples, where the model would need the input before the span began (the delay and
//! five time constants of the slowest pole), and at both ends the low-pass's ringing on the
//! span's edges ([`EDGE_PERIODS`] periods of the band top).
//!
//! `fit_percent_i = 100 (1 - ||y_i - yhat_i|| / ||y_i||)` over the kept samples (band-limited,
//! mean-free): 100 is a perfect prediction, 0 no better than the mean, negative worse than it.
//!
//! Units: the outputs' (rad/s, m/s^2), time in the run's time column (s), Hz. A span that keeps
//! fewer than [`MIN_KEPT`] samples, or a band top that is not a positive number, gives `None`.

use std::ops::Range;

use num_complex::Complex64;

use super::BlockModel;
use crate::block::Block;
use crate::fourier::{RecordFft, fast_len};
use crate::ident::signals::BlockSignals;
use crate::noise::residual::{predicted_spectra, settle_samples};

/// The low-pass reaches zero at this multiple of the band top.
pub const ROLL_OFF: f64 = 1.25;
/// Samples dropped at each end against the low-pass's ringing, in periods of the band top: the
/// raised cosine's impulse response decays as `t^-3` beyond about `2 / (0.25 f)`.
pub const EDGE_PERIODS: f64 = 12.0;
/// Fewest samples kept.
pub const MIN_KEPT: usize = 64;

/// A block model's prediction of a run's outputs.
#[derive(Clone, Debug)]
pub struct Validation {
    /// The block.
    pub block: Block,
    /// Time of the first kept sample, s.
    pub t0_s: f64,
    /// Sample interval, s.
    pub dt_s: f64,
    /// The model's band, Hz: both signals are low-passed at its top (module docs).
    pub band_hz: [f64; 2],
    /// Measured outputs, band-limited and mean-free.
    pub measured: [Vec<f64>; 3],
    /// The model's outputs, band-limited and mean-free.
    pub predicted: [Vec<f64>; 3],
    /// Fit per output channel, percent.
    pub fit_percent: [f64; 3],
}

/// `100 (1 - ||y - yhat|| / ||y||)`; `NaN` for an all-zero `y`.
#[must_use]
pub fn fit_percent(measured: &[f64], predicted: &[f64]) -> f64 {
    let error: f64 = measured.iter().zip(predicted).map(|(y, p)| (y - p).powi(2)).sum();
    let power: f64 = measured.iter().map(|y| y * y).sum();
    if power > 0.0 {
        100.0 * (1.0 - (error / power).sqrt())
    } else {
        f64::NAN
    }
}

/// `model`'s prediction of `signals`' outputs over `span` (sample indices), the first sample of
/// the span at `t0_s` (module docs).
#[must_use]
pub fn validate(
    model: &BlockModel,
    signals: &BlockSignals,
    span: Range<usize>,
    sample_rate_hz: f64,
    t0_s: f64,
) -> Option<Validation> {
    let cut = |c: &[Vec<f64>; 3]| c.each_ref().map(|x| x.get(span.clone()).map(<[f64]>::to_vec));
    let (Some(input), Some(output)) = (transpose(cut(&signals.input)), transpose(cut(&signals.output)))
    else {
        return None;
    };
    let len = input.iter().chain(&output).map(Vec::len).min().unwrap_or(0);
    let top = model.band_hz[1];
    if !(top.is_finite() && top > 0.0) {
        return None;
    }
    let settle = settle_samples(model.tau_s, &model.poles, sample_rate_hz, len);
    let edge = ((EDGE_PERIODS * sample_rate_hz / top).ceil() as usize).min(len / 10);
    let keep = settle + edge..len.saturating_sub(edge);
    if keep.len() < MIN_KEPT {
        return None;
    }
    let mut fft = RecordFft::new(fast_len(len + settle + 16), sample_rate_hz);
    let gain: Vec<f64> = (0..fft.n_bins())
        .map(|k| low_pass(fft.frequency_hz(k), top))
        .collect();
    let kept = |fft: &mut RecordFft, mut spectrum: Vec<Complex64>| {
        for (v, g) in spectrum.iter_mut().zip(&gain) {
            *v *= g;
        }
        let x = fft.inverse(spectrum);
        let mut x = x[keep.clone()].to_vec();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        for v in &mut x {
            *v -= mean;
        }
        x
    };
    let predicted_spectra = predicted_spectra(&mut fft, &input, len, |f| model.response(f));
    let predicted = predicted_spectra.map(|s| kept(&mut fft, s));
    let measured = output.each_ref().map(|y| {
        let mean = y[..len].iter().sum::<f64>() / len as f64;
        let centred: Vec<f64> = y[..len].iter().map(|v| v - mean).collect();
        let spectrum = fft.forward(&centred);
        kept(&mut fft, spectrum)
    });
    let fit = std::array::from_fn(|i| fit_percent(&measured[i], &predicted[i]));
    Some(Validation {
        block: signals.block,
        t0_s: t0_s + keep.start as f64 / sample_rate_hz,
        dt_s: 1.0 / sample_rate_hz,
        band_hz: model.band_hz,
        measured,
        predicted,
        fit_percent: fit,
    })
}

/// The low-pass's gain at `f` for band top `top`: 1 up to it, a raised cosine down to 0 at
/// [`ROLL_OFF`] times it.
fn low_pass(f: f64, top: f64) -> f64 {
    let x = (f - top) / ((ROLL_OFF - 1.0) * top);
    if x <= 0.0 {
        1.0
    } else if x >= 1.0 {
        0.0
    } else {
        0.5 * (1.0 + (std::f64::consts::PI * x).cos())
    }
}

fn transpose(c: [Option<Vec<f64>>; 3]) -> Option<[Vec<f64>; 3]> {
    let [a, b, c] = c;
    Some([a?, b?, c?])
}

#[cfg(test)]
#[path = "validation_tests.rs"]
mod tests;
