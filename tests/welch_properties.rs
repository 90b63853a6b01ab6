//! Structural properties of `welch_matrix`: Hermitian, positive semi-definite bins, Parseval,
//! coherence and the transfer-function convention, errors, planner reuse, thread independence.

use crate::common;

use common::{correlated_channels, settings, views};
use imu_attest::rng::Rng;
use imu_attest::spectral::{
    Detrend, SpectralError, SpectralMatrix, WelchPlanner, WelchSettings, Window, welch_matrix,
};
use std::f64::consts::TAU;

#[test]
fn bins_are_hermitian_and_positive_semidefinite() {
    // Four channels, the last a combination of two others: one eigenvalue is ~0 in every bin.
    let mut channels = correlated_channels(1, 3, 3000);
    let combo: Vec<f64> = channels[0]
        .iter()
        .zip(&channels[2])
        .map(|(a, b)| 2.0 * a - 0.5 * b)
        .collect();
    channels.push(combo);
    for window in [
        Window::Rectangular,
        Window::Hann,
        Window::Hamming,
        Window::BlackmanHarris,
    ] {
        let s = welch_matrix(
            &views(&channels),
            100.0,
            &settings(128, 0.5, window, Detrend::Linear),
        )
        .unwrap();
        let max_trace = (0..s.n_bins())
            .map(|f| s.matrix(f).trace().re)
            .fold(0.0, f64::max);
        for f in 0..s.n_bins() {
            for i in 0..4 {
                assert_eq!(s[(f, i, i)].im.to_bits(), 0, "diagonal is real, +0 imaginary");
                for j in 0..4 {
                    assert_eq!(s[(f, i, j)], s[(f, j, i)].conj(), "{window:?} bin {f} ({i},{j})");
                }
            }
            let m = s.matrix(f);
            let trace = m.trace().re;
            let eig = m.symmetric_eigenvalues();
            let min = eig.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(
                min >= -1e-12 * trace,
                "{window:?} bin {f}: eigenvalue {min} vs trace {trace}"
            );
            let singular = 1e-9 * trace + 1e-12 * max_trace;
            assert!(
                min <= singular,
                "{window:?} bin {f}: the combination channel should be singular"
            );
        }
    }
}

#[test]
fn parseval_rectangular_no_overlap() {
    // sum_k S_ii(f_k) df = mean over segments of the segment's (population) variance, exactly.
    let channels = correlated_channels(2, 2, 1000); // 1000 = 15 segments of 64 + 40 dropped
    let (fs, seg) = (250.0, 64);
    let s = welch_matrix(
        &views(&channels),
        fs,
        &settings(seg, 0.0, Window::Rectangular, Detrend::Mean),
    )
    .unwrap();
    assert_eq!(s.n_averages, 15);
    for (i, x) in channels.iter().enumerate() {
        let variance = x[..15 * seg]
            .chunks_exact(seg)
            .map(|c| {
                let m = c.iter().sum::<f64>() / seg as f64;
                c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / seg as f64
            })
            .sum::<f64>()
            / 15.0;
        let integral = s.psd(i).iter().sum::<f64>() * s.df_hz();
        assert!(
            (integral - variance).abs() < 1e-12 * variance,
            "channel {i}: {integral} vs {variance}"
        );
    }
}

#[test]
fn scaled_delayed_copy_is_coherent_and_gives_the_transfer_function() {
    // y(t) = g x(t - d): coherence ~ 1, and S_yx = W S_xx with W(f) = g e^(-2 pi i f d / fs).
    let (g, d, fs, n) = (2.5, 2, 400.0, 40_000);
    let mut rng = Rng::new(3);
    let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let y: Vec<f64> = (0..n).map(|t| if t >= d { g * x[t - d] } else { 0.0 }).collect();
    let z: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let s = welch_matrix(
        &[&x, &y, &z],
        fs,
        &settings(512, 0.5, Window::Hann, Detrend::Mean),
    )
    .unwrap();
    let coh = s.coherence(1, 0);
    assert!(
        coh.iter().all(|&c| c > 0.97 && c <= 1.0),
        "min coherence {:?}",
        coh.iter().copied().reduce(f64::min)
    );
    let unrelated = s.coherence(0, 2);
    let mean = unrelated.iter().sum::<f64>() / unrelated.len() as f64;
    assert!(mean < 0.05, "independent channels: mean coherence {mean}");
    for f in 1..s.n_bins() - 1 {
        let w = s[(f, 1, 0)] / s[(f, 0, 0)];
        let want = num_complex::Complex64::from_polar(g, -TAU * s.frequency_hz[f] * d as f64 / fs);
        assert!((w - want).norm() < 0.03 * g, "bin {f}: W = {w}, want {want}");
    }
}

#[test]
fn every_bad_input_is_an_error_never_nan() {
    let good = settings(16, 0.5, Window::Hann, Detrend::Mean);
    let x = vec![1.0; 64];
    let mut p = WelchPlanner::new();
    assert_eq!(p.welch_matrix(&[], 10.0, &good), Err(SpectralError::NoChannels));
    let short = vec![0.0; 63];
    assert_eq!(
        p.welch_matrix(&[&x, &x, &short], 10.0, &good),
        Err(SpectralError::ChannelLengthMismatch {
            channel: 2,
            len: 63,
            expected: 64
        })
    );
    for fs in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = p.welch_matrix(&[&x], fs, &good).unwrap_err();
        assert!(matches!(err, SpectralError::BadSampleRate { .. }), "{fs}: {err}");
    }
    for seg in [0, 4, 15, 17] {
        let s = WelchSettings {
            segment_len: seg,
            ..good
        };
        assert_eq!(
            p.welch_matrix(&[&x], 10.0, &s),
            Err(SpectralError::BadSegmentLen { segment_len: seg })
        );
    }
    for overlap in [-0.5, 1.0, f64::NAN, 0.99] {
        let s = WelchSettings { overlap, ..good };
        let err = p.welch_matrix(&[&x], 10.0, &s).unwrap_err();
        assert!(
            matches!(err, SpectralError::BadOverlap { segment_len: 16, .. }),
            "{overlap}: {err}"
        );
    }
    let s = WelchSettings {
        segment_len: 128,
        ..good
    };
    assert_eq!(
        p.welch_matrix(&[&x], 10.0, &s),
        Err(SpectralError::TooFewSamples {
            n_samples: 64,
            segment_len: 128
        })
    );
    // The first bad sample is reported, even with a later one in the same channel.
    for (bad, at, later) in [
        (f64::NAN, 17, 40),
        (f64::INFINITY, 0, 5),
        (f64::NEG_INFINITY, 62, 63),
    ] {
        let mut y = x.clone();
        y[at] = bad;
        y[later] = f64::NAN;
        assert_eq!(
            p.welch_matrix(&[&x, &y], 10.0, &good),
            Err(SpectralError::NonFinite {
                channel: 1,
                index: at
            })
        );
    }
    // A constant signal is fine: all-zero spectra, zero coherence, no NaN.
    let s = p.welch_matrix(&[&x, &x], 10.0, &good).unwrap();
    assert!(s.as_slice().iter().all(|v| v.norm() == 0.0));
    assert!(s.coherence(0, 1).iter().all(|&c| c == 0.0));
}

#[test]
fn planner_reuse_and_thread_count_give_identical_bits() {
    let channels = correlated_channels(4, 3, 20_000);
    let s = settings(256, 0.75, Window::BlackmanHarris, Detrend::Linear);
    let mut planner = WelchPlanner::new();
    let first = planner.welch_matrix(&views(&channels), 500.0, &s).unwrap();
    assert!(first.n_averages > 100, "enough segments to fill every chunk");
    let again = planner.welch_matrix(&views(&channels), 500.0, &s).unwrap();
    assert_eq!(bits(&first), bits(&again));
    let w1 = planner.window(Window::BlackmanHarris, 256);
    assert!(
        std::sync::Arc::ptr_eq(&w1, &planner.window(Window::BlackmanHarris, 256)),
        "window cached"
    );
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let other = pool
            .install(|| welch_matrix(&views(&channels), 500.0, &s))
            .unwrap();
        assert_eq!(bits(&other), bits(&first), "{threads} threads");
    }
}

fn bits(s: &SpectralMatrix) -> Vec<(u64, u64)> {
    s.as_slice()
        .iter()
        .map(|v| (v.re.to_bits(), v.im.to_bits()))
        .collect()
}

/// Zero-padding to `fft_len` samples the same estimate on a finer grid: every `fft_len / N`-th
/// bin equals the unpadded estimate (the DFT of a padded segment at `m k` is the `N`-point DFT at
/// `k`), bins are `fs / fft_len` apart, and an odd or short `fft_len` is refused.
#[test]
fn zero_padding_refines_the_same_estimate() {
    let channels = common::correlated_channels(11, 3, 3000);
    let plain = common::settings(
        256,
        0.5,
        imu_attest::spectral::Window::Hann,
        imu_attest::spectral::Detrend::Linear,
    );
    let padded = imu_attest::spectral::WelchSettings {
        fft_len: Some(1024),
        ..plain
    };
    let mut planner = imu_attest::spectral::WelchPlanner::new();
    let a = planner
        .welch_matrix(&common::views(&channels), 50.0, &plain)
        .unwrap();
    let b = planner
        .welch_matrix(&common::views(&channels), 50.0, &padded)
        .unwrap();
    assert_eq!(b.n_bins(), 513);
    assert!((b.df_hz() - 50.0 / 1024.0).abs() < 1e-15);
    for k in 0..a.n_bins() {
        for i in 0..3 {
            for j in 0..3 {
                let (x, y) = (a.get(k, i, j).unwrap(), b.get(4 * k, i, j).unwrap());
                assert!(
                    (x - y).norm() <= 1e-12 * (1.0 + x.norm()),
                    "bin {k} ({i},{j}): {x} vs {y}"
                );
            }
        }
    }
    for bad in [255, 1023, 100] {
        let s = imu_attest::spectral::WelchSettings {
            fft_len: Some(bad),
            ..plain
        };
        assert!(
            matches!(
                s.validate(3000),
                Err(imu_attest::spectral::SpectralError::BadFftLen { .. })
            ),
            "{bad}"
        );
    }
}

/// The groups of `welch_matrix_parts` are the un-padded Welch matrices of their segments, and its
/// total is `welch_matrix`'s, from one pass over the segment transforms.
#[test]
fn parts_are_the_groups_own_welch_matrices_and_the_total_is_unchanged() {
    use imu_attest::spectral::{WelchPlanner, WelchSettings};
    let mut rng = imu_attest::rng::Rng::new(11);
    let n = 20_000;
    let channels: Vec<Vec<f64>> = (0..3)
        .map(|c| {
            let mut acc = 0.0;
            (0..n)
                .map(|k| {
                    acc = 0.9 * acc + rng.normal();
                    acc + (0.01 * k as f64 * f64::from(c + 1)).sin()
                })
                .collect()
        })
        .collect();
    let views: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
    let settings = WelchSettings {
        segment_len: 512,
        fft_len: Some(2048),
        ..WelchSettings::default()
    };
    let mut planner = WelchPlanner::new();
    let whole = planner.welch_matrix(&views, 200.0, &settings).expect("whole");
    let parts_count = 5;
    let (total, parts) = planner
        .welch_matrix_parts(&views, 200.0, &settings, parts_count)
        .expect("parts");
    let parts = parts.expect("2048 is a multiple of 512");
    let close =
        |a: num_complex::Complex64, b: num_complex::Complex64, scale: f64| (a - b).norm() <= 1e-12 * scale;
    let peak = |m: &imu_attest::spectral::SpectralMatrix| {
        (0..m.n_bins()).map(|f| m[(f, 0, 0)].re).fold(0.0, f64::max)
    };
    for f in 0..whole.n_bins() {
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    close(total[(f, i, j)], whole[(f, i, j)], peak(&whole)),
                    "total bin {f}"
                );
            }
        }
    }
    let n_segments = settings.n_segments(n);
    let step = settings.step();
    let native = WelchSettings {
        fft_len: None,
        ..settings
    };
    assert_eq!(parts.len(), parts_count);
    for (p, part) in parts.iter().enumerate() {
        let (first, last) = (p * n_segments / parts_count, (p + 1) * n_segments / parts_count);
        let (start, end) = (first * step, (last - 1) * step + settings.segment_len);
        let slices: Vec<&[f64]> = views.iter().map(|c| &c[start..end]).collect();
        let reference = planner.welch_matrix(&slices, 200.0, &native).expect("group");
        assert_eq!(part.n_bins(), reference.n_bins());
        assert_eq!(part.n_averages, reference.n_averages);
        for f in 0..part.n_bins() {
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        close(part[(f, i, j)], reference[(f, i, j)], peak(&reference)),
                        "part {p} bin {f} ({i}, {j}): {} vs {}",
                        part[(f, i, j)],
                        reference[(f, i, j)]
                    );
                }
            }
        }
    }
    assert!(planner.welch_matrix_parts(&views, 200.0, &settings, 0).is_err());
}
