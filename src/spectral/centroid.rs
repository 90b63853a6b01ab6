//! The frequency at which each Welch bin's input power actually lies: the power-weighted centroid
//! of the segments' content per bin (the reassignment operator of time-frequency analysis).
//!
//! A bin of a Welch estimate does not hold the bin's centre frequency `f_k` alone: its window's
//! main lobe gathers power from `f_k +- 2 df` (Hann). For a broadband input the power is spread
//! evenly there and `W = S_xu S_uu^-1` at the bin is the model at `f_k`, to first order. For an
//! input with strong lines (a stand's sine programme) a bin beside a line holds the line's power:
//! its `W` is the model at the line's frequency, not at `f_k`. A model evaluated at `f_k` then
//! misses by `dH/df (f_line - f_k)`, which for a delay `tau` is a phase of
//! `2 pi (f_line - f_k) tau`: at a strong line, hundreds of its standard deviations (a chi2/dof of
//! 3-25 on exact runs of an independent simulator with 2-5 degree sines) and a delay biased by up
//! to 0.17 ms. Evaluating the model at the centroid removes both.
//!
//! With `h` the window and `Dh` its time derivative (s^-1), per segment and input channel
//! `X_h(k)` and `X_Dh(k)` are the transforms of `h x` and `Dh x`; the centroid is
//!
//! `f_c(k) = f_k - (1 / 2 pi) Im(sum X_Dh conj(X_h)) / sum |X_h|^2`,
//!
//! summed over the segments and the channels (one centroid per bin for the three inputs). It is
//! exact for a line (any offset inside the main lobe) and averages to `f_k` for a flat spectrum.
//! It is held within [`MAIN_LOBE_BINS`] bins of `f_k`, at or above `f_k / 2` (a drift's image from
//! the negative frequencies put a bin at 0.12 Hz at -0.02 Hz) and at or below Nyquist.
//! `Dh` is the window's circular central difference times `fs`, which is its derivative only for a
//! window closing to 0 at its ends (Hann, Blackman-Harris); for the others (rectangular, Hamming)
//! the bin centres are kept.
//!
//! Grid and units: the native grid of the segment (`k = 0..=N/2`, `f_k = k fs / N`, ascending), Hz.
//! Segments as the Welch estimate cuts them (start 0, step `N - noverlap`), detrended alike. A bin
//! with no power, or a non-finite centroid, keeps `f_k`. Empty or NaN input is refused as the
//! Welch estimate refuses it.

use super::welch::WelchPlanner;
use super::{SpectralError, WelchSettings};

/// Half the widest main lobe of the windows offered (Hann, Hamming: 2 bins; Blackman-Harris: 4),
/// in bins: a centroid farther from its bin than [`MAIN_LOBE_BINS`] bins is held there. The
/// centroid is also held at or above half its bin's frequency: near 0 Hz a bin's main lobe
/// reaches the negative frequencies, whose image of a slow drift would put it below 0 Hz.
const MAIN_LOBE_BINS: f64 = 4.0;

impl WelchPlanner {
    /// The centroid frequency of each native bin of `channels` (module docs), Hz.
    ///
    /// # Errors
    /// As [`WelchPlanner::welch_matrix`] on the same input.
    pub fn centroid_hz(
        &mut self,
        channels: &[&[f64]],
        sample_rate_hz: f64,
        settings: &WelchSettings,
    ) -> Result<Vec<f64>, SpectralError> {
        super::welch::check_input(channels, sample_rate_hz, settings)?;
        let n = settings.segment_len;
        let window = self.window(settings.window, n);
        let df = sample_rate_hz / n as f64;
        let centres = || (0..=n / 2).map(|k| k as f64 * df).collect();
        // The circular difference is the window's derivative only for a window that closes to 0
        // at its ends (Hann, Blackman-Harris); Hamming's and the rectangle's jump there.
        let peak = window.iter().copied().fold(0.0, f64::max);
        if window.first().is_none_or(|w0| w0.abs() > 1e-3 * peak) {
            return Ok(centres());
        }
        let derivative: Vec<f64> = (0..n)
            .map(|i| 0.5 * (window[(i + 1) % n] - window[(i + n - 1) % n]) * sample_rate_hz)
            .collect();
        let fft = self.real_fft(n);
        let bins = n / 2 + 1;
        let (mut plain, mut weighted) = (fft.make_input_vec(), fft.make_input_vec());
        let (mut x_h, mut x_dh) = (fft.make_output_vec(), fft.make_output_vec());
        let mut scratch = fft.make_scratch_vec();
        let (mut num, mut den) = (vec![0.0; bins], vec![0.0; bins]);
        let mut segment = vec![0.0; n];
        for s in 0..settings.n_segments(channels[0].len()) {
            let start = s * settings.step();
            for channel in channels {
                segment.copy_from_slice(&channel[start..start + n]);
                settings.detrend.apply(&mut segment);
                for i in 0..n {
                    plain[i] = segment[i] * window[i];
                    weighted[i] = segment[i] * derivative[i];
                }
                fft.process_with_scratch(&mut plain, &mut x_h, &mut scratch)
                    .and_then(|()| fft.process_with_scratch(&mut weighted, &mut x_dh, &mut scratch))
                    .map_err(|e| SpectralError::Fft(e.to_string()))?;
                for k in 0..bins {
                    num[k] += (x_dh[k] * x_h[k].conj()).im;
                    den[k] += x_h[k].norm_sqr();
                }
            }
        }
        let nyquist = 0.5 * sample_rate_hz;
        Ok((0..bins)
            .map(|k| {
                let f = k as f64 * df;
                let c = f - num[k] / den[k] / (2.0 * std::f64::consts::PI);
                if den[k] > 0.0 && c.is_finite() {
                    c.clamp(
                        (f - MAIN_LOBE_BINS * df).max(0.5 * f),
                        (f + MAIN_LOBE_BINS * df).min(nyquist).max(0.5 * f),
                    )
                } else {
                    f
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::Window;

    fn settings(n: usize, window: Window) -> WelchSettings {
        WelchSettings {
            segment_len: n,
            window,
            ..WelchSettings::default()
        }
    }

    /// A line between two bins: every bin of its main lobe is placed at the line (closed form).
    #[test]
    fn a_line_is_found_at_its_frequency_from_every_bin_of_its_main_lobe() {
        let (rate, n) = (500.0, 1024);
        let line = 10.0 * rate / n as f64 + 0.37 * rate / n as f64;
        let x: Vec<f64> = (0..20 * n)
            .map(|t| (2.0 * std::f64::consts::PI * line * t as f64 / rate + 0.4).sin())
            .collect();
        let c = WelchPlanner::new()
            .centroid_hz(&[&x], rate, &settings(n, Window::Hann))
            .unwrap();
        for k in 9..=12 {
            assert!((c[k] - line).abs() < 1e-4, "bin {k}: {} against {line}", c[k]);
        }
    }

    /// White noise: the centroids scatter about the bin centres, unbiased (the mean offset over
    /// the bins is a small fraction of its scatter's standard error).
    #[test]
    fn white_noise_leaves_the_bin_centres_on_average() {
        let (rate, n) = (500.0, 256);
        let mut rng = crate::rng::Rng::new(9);
        let x: Vec<f64> = (0..400 * n).map(|_| rng.normal()).collect();
        let c = WelchPlanner::new()
            .centroid_hz(&[&x], rate, &settings(n, Window::Hann))
            .unwrap();
        let df = rate / n as f64;
        let offsets: Vec<f64> = (5..n / 2 - 5).map(|k| (c[k] - k as f64 * df) / df).collect();
        let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
        let rms = (offsets.iter().map(|o| o * o).sum::<f64>() / offsets.len() as f64).sqrt();
        assert!(rms < 0.1, "scatter {rms} of a bin");
        assert!(
            mean.abs() < 3.0 * rms / (offsets.len() as f64).sqrt(),
            "mean {mean}, rms {rms}"
        );
    }

    /// A slow drift's power near 0 Hz reaches the first bins through the main lobe, its image from
    /// the negative frequencies too: the centroid stays at or above half the bin's frequency.
    #[test]
    fn near_zero_hertz_the_centroid_stays_positive() {
        let (rate, n) = (500.0, 1024);
        let x: Vec<f64> = (0..8 * n)
            .map(|t| {
                let s = f64::from(u32::try_from(t).unwrap()) / rate;
                1e-3 * s * s + 1e-6 * (2.0 * std::f64::consts::PI * 40.0 * s).sin()
            })
            .collect();
        let c = WelchPlanner::new()
            .centroid_hz(&[&x], rate, &settings(n, Window::Hann))
            .unwrap();
        let df = rate / n as f64;
        for (k, f) in c.iter().enumerate().skip(1).take(8) {
            let centre = k as f64 * df;
            assert!(*f >= 0.5 * centre && *f <= centre + 4.0 * df, "bin {k}: {f}");
        }
    }

    /// Windows that do not close to 0 at their ends (rectangular, Hamming) have no derivative
    /// there: the bin centres are kept (a circular difference pushed Hamming's leakage bins
    /// away from the line, by 3 bins).
    #[test]
    fn windows_open_at_their_ends_keep_the_bin_centres() {
        let x: Vec<f64> = (0..4096_u32).map(|t| (0.3 * f64::from(t)).sin()).collect();
        for window in [Window::Rectangular, Window::Hamming] {
            let c = WelchPlanner::new()
                .centroid_hz(&[&x], 100.0, &settings(256, window))
                .unwrap();
            for (k, f) in c.iter().enumerate() {
                assert!((f - k as f64 * 100.0 / 256.0).abs() < 1e-12, "{window:?} bin {k}");
            }
        }
        // Blackman-Harris closes to 0: its main lobe is placed at the line.
        let (rate, n) = (500.0, 1024);
        let line = 10.37 * rate / n as f64;
        let x: Vec<f64> = (0..20 * n)
            .map(|t| (2.0 * std::f64::consts::PI * line * t as f64 / rate).sin())
            .collect();
        let c = WelchPlanner::new()
            .centroid_hz(&[&x], rate, &settings(n, Window::BlackmanHarris))
            .unwrap();
        assert!(
            (c[10] - line).abs() < 1e-3 && (c[11] - line).abs() < 1e-3,
            "{} {}",
            c[10],
            c[11]
        );
    }
}
