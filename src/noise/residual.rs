//! The disturbance of a block in time: `r = x - H u`, the measured outputs minus the identified
//! model driven by the input estimate (the stand's motion taken out, so the noise terms are the
//! sensor's and not the motion's).
//!
//! `H u` is applied in the frequency domain on the whole record, the input's mean removed and
//! zero-padded so that the circular convolution is a linear one; the first samples, where the
//! model would need the input before the record began (the delay and the settling of the model's
//! slowest pole), are dropped. The outputs' means are removed too (a bias is not noise here).
//! What the input estimate carries besides the motion (the reference's angle noise, through the
//! observer) reaches the residual through `H`: on a gyro it shows at the shortest averaging
//! times as a white-phase (quantisation-like) term.

use nalgebra::Matrix3;
use num_complex::Complex64;

use crate::fourier::{RecordFft, fast_len};

/// Longest start transient dropped, as a fraction of the record.
const MAX_SETTLE_FRACTION: f64 = 0.1;

/// Samples dropped at the start: the delay plus five time constants of the slowest pole, and
/// eight samples of margin, at most a tenth of the record.
#[must_use]
pub fn settle_samples(tau_s: f64, poles: &[[f64; 2]], sample_rate_hz: f64, len: usize) -> usize {
    let slowest = poles
        .iter()
        .map(|p| p[0].abs())
        .filter(|r| *r > 0.0 && r.is_finite())
        .fold(f64::INFINITY, f64::min);
    let time_constant = if slowest.is_finite() { 1.0 / slowest } else { 0.0 };
    let seconds = tau_s.abs() + 5.0 * time_constant;
    let wanted = (seconds * sample_rate_hz).ceil() + 8.0;
    let cap = (len as f64 * MAX_SETTLE_FRACTION).floor();
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "clamped to [0, len]"
    )]
    let samples = wanted.min(cap).max(0.0) as usize;
    samples
}

/// `x - H u` on the record, its first `settle` samples dropped and its means removed. `response`
/// gives `H(f)` (output i over input j) at a frequency in Hz; non-finite values count as 0.
#[must_use]
pub fn residual(
    input: &[Vec<f64>; 3],
    output: &[Vec<f64>; 3],
    sample_rate_hz: f64,
    settle: usize,
    response: impl Fn(f64) -> Matrix3<Complex64>,
) -> [Vec<f64>; 3] {
    let len = input.iter().chain(output).map(Vec::len).min().unwrap_or(0);
    if len <= settle + 1 {
        return [Vec::new(), Vec::new(), Vec::new()];
    }
    let mut fft = RecordFft::new(fast_len(len + settle + 16), sample_rate_hz);
    let mut predicted = predicted_spectra(&mut fft, input, len, response);
    std::array::from_fn(|i| {
        let model = fft.inverse(std::mem::take(&mut predicted[i]));
        let mut r: Vec<f64> = output[i][settle..len]
            .iter()
            .zip(&model[settle..len])
            .map(|(x, m)| x - m)
            .collect();
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        for v in &mut r {
            *v -= mean;
        }
        r
    })
}

/// The spectra of `H u` on `fft`'s grid (zero-padded): the first `len` samples of each input,
/// mean removed, transformed and multiplied by `response` (non-finite products count as 0).
pub(crate) fn predicted_spectra(
    fft: &mut RecordFft,
    input: &[Vec<f64>; 3],
    len: usize,
    response: impl Fn(f64) -> Matrix3<Complex64>,
) -> [Vec<Complex64>; 3] {
    let spectra: [Vec<Complex64>; 3] = std::array::from_fn(|j| {
        let mean = input[j][..len].iter().sum::<f64>() / len as f64;
        let centred: Vec<f64> = input[j][..len].iter().map(|v| v - mean).collect();
        fft.forward(&centred)
    });
    let bins = fft.n_bins();
    let mut predicted: [Vec<Complex64>; 3] = std::array::from_fn(|_| vec![Complex64::default(); bins]);
    for k in 0..bins {
        let h = response(fft.frequency_hz(k));
        for (i, p) in predicted.iter_mut().enumerate() {
            let v: Complex64 = (0..3).map(|j| h[(i, j)] * spectra[j][k]).sum();
            p[k] = if v.is_finite() { v } else { Complex64::default() };
        }
    }
    predicted
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ident::structural::rational_response;
    use crate::rng::Rng;

    #[test]
    fn a_known_delayed_gain_leaves_exactly_the_added_noise() {
        // x = K u(t - 3 samples) + n: the residual is n (means removed) after the transient.
        let fs = 100.0;
        let mut rng = Rng::new(5);
        let len = 4000;
        let u: [Vec<f64>; 3] = std::array::from_fn(|_| {
            let mut acc = 0.0;
            (0..len)
                .map(|_| {
                    acc = 0.95 * acc + rng.normal();
                    acc + 2.0
                })
                .collect()
        });
        let k = [[1.01, 0.002, -0.001], [0.0, 0.99, 0.003], [0.004, 0.0, 1.0]];
        let noise: [Vec<f64>; 3] = std::array::from_fn(|_| (0..len).map(|_| 1e-3 * rng.normal()).collect());
        let x: [Vec<f64>; 3] = std::array::from_fn(|i| {
            (0..len)
                .map(|n| {
                    let lagged = |j: usize| if n >= 3 { u[j][n - 3] } else { 2.0 };
                    (0..3).map(|j| k[i][j] * lagged(j)).sum::<f64>() + noise[i][n] + 0.5
                })
                .collect()
        });
        let settle = settle_samples(0.03, &[], fs, len);
        assert_eq!(settle, 11);
        let r = residual(&u, &x, fs, settle, |f| rational_response(&[k], &[], 0.03, f));
        for i in 0..3 {
            let n_mean = noise[i][settle..].iter().sum::<f64>() / (len - settle) as f64;
            for (got, want) in r[i].iter().zip(&noise[i][settle..]) {
                assert!((got - (want - n_mean)).abs() < 1e-9, "{got} vs {want}");
            }
        }
    }

    #[test]
    fn the_transient_follows_the_slowest_pole_and_is_capped() {
        assert_eq!(
            settle_samples(0.0, &[[-2.0, 0.0], [-50.0, 3.0]], 100.0, 100_000),
            258
        );
        assert_eq!(settle_samples(0.0, &[[-0.001, 0.0]], 100.0, 1000), 100);
        let empty = residual(
            &[vec![1.0; 5], vec![1.0; 5], vec![1.0; 5]],
            &[vec![1.0; 5], vec![1.0; 5], vec![1.0; 5]],
            10.0,
            5,
            |_| Matrix3::zeros(),
        );
        assert!(empty.iter().all(Vec::is_empty));
    }
}
