//! `welch_matrix` against a naive oracle: a direct O(N^2) DFT per segment and a product per pair,
//! written straight from the definition in the module docs (zero-padded to `fft_len` when set).
//! The oracle is first checked on sinusoids whose density is known in closed form.

use crate::common;

use common::{correlated_channels, settings, views};
use imu_attest::spectral::{Detrend, SpectralMatrix, WelchPlanner, WelchSettings, Window};
use num_complex::Complex64;
use std::f64::consts::TAU;

/// The definition, with nothing shared with the implementation but `Window` and `Detrend`.
fn oracle(channels: &[&[f64]], fs: f64, s: &WelchSettings) -> SpectralMatrix {
    let (n, big_n) = (channels.len(), s.segment_len);
    let noverlap = (s.overlap * big_n as f64).round() as usize;
    let step = big_n - noverlap;
    let w = s.window.coefficients(big_n);
    let sum_w2: f64 = w.iter().map(|v| v * v).sum();
    let nfft = s.nfft();
    let n_bins = nfft / 2 + 1;
    let mut data = vec![Complex64::default(); n_bins * n * n];
    let mut n_seg = 0;
    let mut start = 0;
    while start + big_n <= channels[0].len() {
        let spectra: Vec<Vec<Complex64>> = channels
            .iter()
            .map(|x| {
                let mut v = x[start..start + big_n].to_vec();
                s.detrend.apply(&mut v);
                (0..n_bins)
                    .map(|k| {
                        (0..big_n)
                            .map(|t| {
                                let angle = -TAU * ((k * t) % nfft) as f64 / nfft as f64;
                                Complex64::from_polar(v[t] * w[t], angle)
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect();
        for k in 0..n_bins {
            for i in 0..n {
                for j in 0..n {
                    data[(k * n + i) * n + j] += spectra[i][k] * spectra[j][k].conj();
                }
            }
        }
        n_seg += 1;
        start += step;
    }
    for (k, bin) in data.chunks_exact_mut(n * n).enumerate() {
        let one_sided = if k == 0 || k == nfft / 2 { 1.0 } else { 2.0 };
        for v in bin {
            *v *= one_sided / (fs * sum_w2 * f64::from(n_seg));
        }
    }
    let freqs = (0..n_bins).map(|k| k as f64 * fs / nfft as f64).collect();
    SpectralMatrix::from_parts(fs, nfft, n, n_seg as usize, freqs, data).expect("oracle shape")
}

/// The largest difference between `a` and `b` over all bins and elements, each bin's difference
/// relative to that bin's largest |b|, floored at `1e-12` of the largest |b| overall.
fn max_rel_diff(a: &SpectralMatrix, b: &SpectralMatrix) -> f64 {
    assert_eq!(
        (a.n_bins(), a.n_channels),
        (b.n_bins(), b.n_channels),
        "shapes differ"
    );
    let bin_max = |f: usize| b.bin(f).iter().map(|v| v.norm()).fold(0.0, f64::max);
    let floor = 1e-12 * (0..b.n_bins()).map(bin_max).fold(0.0, f64::max);
    (0..b.n_bins())
        .map(|f| {
            let scale = bin_max(f).max(floor);
            a.bin(f)
                .iter()
                .zip(b.bin(f))
                .map(|(x, y)| (x - y).norm() / scale)
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

#[test]
fn oracle_gives_the_closed_form_density_of_a_bin_centred_sinusoid() {
    // x = A cos(2 pi k0 t / N): rectangular window puts X[k0] = A N / 2, so
    // S(k0) = 2 / (fs N) (A N / 2)^2 = A^2 N / (2 fs), 0 elsewhere, integral A^2 / 2.
    // Hann (sum w = N/2, sum w^2 = 3N/8): S(k0) = A^2 N / (3 fs), S(k0 +- 1) = A^2 N / (12 fs).
    let (a, fs, big_n, k0) = (1.7, 50.0, 32, 5);
    let x: Vec<f64> = (0..4 * big_n)
        .map(|t| a * (TAU * (k0 * t) as f64 / big_n as f64).cos())
        .collect();
    let nf = big_n as f64;
    let rect = oracle(
        &[&x],
        fs,
        &settings(big_n, 0.0, Window::Rectangular, Detrend::None),
    );
    let hann = oracle(&[&x], fs, &settings(big_n, 0.5, Window::Hann, Detrend::None));
    assert_eq!((rect.n_averages, hann.n_averages), (4, 7));
    for k in 0..rect.n_bins() {
        let want_rect = if k == k0 { a * a * nf / (2.0 * fs) } else { 0.0 };
        let want_hann = match k.abs_diff(k0) {
            0 => a * a * nf / (3.0 * fs),
            1 => a * a * nf / (12.0 * fs),
            _ => 0.0,
        };
        assert!(
            (rect.psd(0)[k] - want_rect).abs() < 1e-12,
            "rect bin {k}: {}",
            rect.psd(0)[k]
        );
        assert!(
            (hann.psd(0)[k] - want_hann).abs() < 1e-12,
            "hann bin {k}: {}",
            hann.psd(0)[k]
        );
    }
    let power: f64 = rect.psd(0).iter().sum::<f64>() * rect.df_hz();
    assert!((power - a * a / 2.0).abs() < 1e-12, "power {power}");
    // The implementation agrees with the closed form too.
    let fast =
        WelchPlanner::new().welch_matrix(&[&x], fs, &settings(big_n, 0.5, Window::Hann, Detrend::None));
    assert!(max_rel_diff(&fast.unwrap(), &hann) < 1e-12);
}

#[test]
fn welch_matches_the_oracle_on_awkward_sizes() {
    let cases = [
        (8, 0.5, Window::Hann, Detrend::Mean, 64),
        (8, 0.0, Window::Rectangular, Detrend::None, 8),
        (10, 0.3, Window::Hamming, Detrend::Linear, 97),
        (64, 0.75, Window::BlackmanHarris, Detrend::Mean, 333),
        (250, 0.5, Window::Hann, Detrend::Linear, 1001),
        (250, 0.0, Window::Hamming, Detrend::None, 749),
    ];
    let mut planner = WelchPlanner::new();
    for (seed, &(seg, overlap, window, detrend, len)) in cases.iter().enumerate() {
        let channels = correlated_channels(seed as u64 + 100, 3, len);
        let s = settings(seg, overlap, window, detrend);
        let fast = planner.welch_matrix(&views(&channels), 123.0, &s).unwrap();
        let slow = oracle(&views(&channels), 123.0, &s);
        assert_eq!(fast.n_averages, slow.n_averages, "{s:?}");
        assert_eq!(fast.frequency_hz, slow.frequency_hz, "{s:?}");
        let diff = max_rel_diff(&fast, &slow);
        assert!(
            diff < 1e-12,
            "{s:?}, {len} samples: differs from the oracle by {diff:e}"
        );
    }
}

/// Zero-padding beyond twice the segment goes through the summed cross-correlation (see
/// `spectral::welch`): it must still equal the padded definition, on grids that are and are not
/// whole multiples of the transform length, and keep auto-spectra real and non-negative.
#[test]
fn padded_welch_matches_the_oracle() {
    let cases = [
        (8, 0.5, Window::Hann, Detrend::Mean, 64, 32),
        (8, 0.5, Window::Hann, Detrend::None, 70, 24),
        (10, 0.3, Window::Hamming, Detrend::Linear, 97, 40),
        (10, 0.0, Window::Rectangular, Detrend::Mean, 60, 30),
        (64, 0.75, Window::BlackmanHarris, Detrend::Mean, 333, 256),
        (250, 0.5, Window::Hann, Detrend::Linear, 1001, 1000),
    ];
    let mut planner = WelchPlanner::new();
    for (seed, &(seg, overlap, window, detrend, len, fft_len)) in cases.iter().enumerate() {
        let channels = correlated_channels(seed as u64 + 200, 3, len);
        let s = WelchSettings {
            fft_len: Some(fft_len),
            ..settings(seg, overlap, window, detrend)
        };
        let fast = planner.welch_matrix(&views(&channels), 123.0, &s).unwrap();
        let slow = oracle(&views(&channels), 123.0, &s);
        assert_eq!(fast.frequency_hz, slow.frequency_hz, "{s:?}");
        let diff = max_rel_diff(&fast, &slow);
        assert!(
            diff < 1e-12,
            "{s:?}, {len} samples: differs from the oracle by {diff:e}"
        );
        for i in 0..3 {
            for k in 0..fast.n_bins() {
                let v = fast[(k, i, i)];
                assert!(v.re >= 0.0 && v.im == 0.0, "{s:?}: S_{i}{i} at bin {k} is {v}");
            }
        }
    }
}
