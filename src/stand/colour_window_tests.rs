use super::*;
use crate::rng::Rng;

/// No split regressors (`colour_split`): the window's own fit.
const NO_SPLIT: Vector4<Complex64> = Vector4::new(
    Complex64::new(0.0, 0.0),
    Complex64::new(0.0, 0.0),
    Complex64::new(0.0, 0.0),
    Complex64::new(0.0, 0.0),
);

fn random_bins(rng: &mut Rng, n: usize) -> Vec<(Vector3<Complex64>, Vector3<Complex64>)> {
    let mut c = || Complex64::new(rng.normal(), rng.normal());
    (0..n)
        .map(|_| (Vector3::new(c(), c(), c()), Vector3::new(c(), c(), c())))
        .collect()
}

/// Moving the origin after summing equals summing about the new origin (brute force).
#[test]
fn moving_the_origin_is_exact() {
    let mut rng = Rng::new(7);
    let bins = random_bins(&mut rng, 40);
    let (mut far, mut near) = (Sums::zero(), Sums::zero());
    for (k, (y, w)) in bins.iter().enumerate() {
        let v = Vector4::new(y[0] * 0.5, w[1], y[2] - w[0], w[2] * 2.0);
        far.add(y, w, &v, k as f64 - 3.0);
        near.add(y, w, &v, (k as f64 - 25.0) / 8.0);
    }
    let moved = far.about(3.0 - 25.0, 1.0 / 8.0);
    let pairs = moved.yw.iter().zip(&near.yw).chain(moved.ww.iter().zip(&near.ww));
    for (a, b) in pairs {
        assert!((a - b).norm() <= 1e-12 * b.norm().max(1.0), "{a} vs {b}");
    }
    for (a, b) in moved.wv.iter().zip(&near.wv) {
        assert!((a - b).norm() <= 1e-12 * b.norm().max(1.0), "{a} vs {b}");
    }
}

/// A witness whose transfer turns across the window is explained but for the turn's
/// curvature (a constant transfer would leave much more); with a transfer exactly a line and
/// independent noise added to the angles, what is left is that noise's power (the
/// `M / (M - 6)` correction makes it unbiased: the mean over many windows within 3 %, where
/// the three regressors' `M / (M - 3)` would be 7 % low).
#[test]
fn a_transfer_turning_across_the_window_is_explained_and_the_noise_is_measured() {
    let mut rng = Rng::new(11);
    let n = 48;
    let half = 24.0;
    let mut exact_left = Vec::new();
    let mut noisy_left = Vec::new();
    for _ in 0..200 {
        let bins = random_bins(&mut rng, n);
        let (mut exact, mut noisy) = (Sums::zero(), Sums::zero());
        for (k, (noise, w)) in bins.iter().enumerate() {
            let u = (k as f64 - 23.5) / half;
            // Phase turning by 1 rad across the window, gain 2, cross-coupled.
            let turn = Complex64::from_polar(2.0, 0.5 * u);
            let y = Vector3::new(turn * w[0], turn * w[1] + w[0] * 0.3, turn * w[2]);
            exact.add(&y, w, &NO_SPLIT, u);
            // A transfer exactly a line in frequency, and noise of known power.
            let line = Complex64::new(1.5, 0.4 * u);
            noisy.add(&(w * line + noise * Complex64::from(0.1)), w, &NO_SPLIT, u);
        }
        let all = Dof {
            equivalent: n as f64,
            independent: n as f64,
        };
        let (total, left) = unexplained(&exact, n as f64, all, 1.0);
        let left = left.expect("the window says something");
        exact_left.push(left[0].max(left[1]).max(left[2]) / total[0]);
        noisy_left.push(unexplained(&noisy, n as f64, all, 1.0).1.expect("says")[1]);
    }
    let worst = exact_left.iter().copied().fold(0.0_f64, f64::max);
    // A line leaves the turn's curvature, the variance of (0.5 u)^2 / 2 over the window,
    // 1.4e-3 of the power on average; a constant would leave the variance of 0.5 u, 8e-2.
    assert!(worst < 5e-3, "a line leaves {worst} of the power unexplained");
    let mean = noisy_left.iter().sum::<f64>() / noisy_left.len() as f64;
    // Each complex noise component has variance 2 x 0.01.
    assert!(
        (mean / 0.02 - 1.0).abs() < 0.03,
        "mean unexplained {mean}, noise 0.02"
    );
}

/// The sliding sums equal each window's sums taken afresh from its bins (brute force):
/// cells added and removed, origins moved and the window cut at the spectrum's ends.
#[test]
fn sliding_windows_equal_each_window_summed_afresh() {
    let mut rng = Rng::new(5);
    let bins: usize = 3001;
    let mut c = || Complex64::new(rng.normal(), rng.normal());
    let mut spectra = || [(); 3].map(|()| (0..bins).map(|_| c()).collect::<Vec<_>>());
    let (mut y, w) = (spectra(), spectra());
    let v = [(); 4].map(|()| (0..bins).map(|_| c()).collect::<Vec<_>>());
    // Each angle holds a part of its split regressors, so that the split is fitted and its sums
    // are compared too.
    for (k, (i, _)) in crate::stand::colour_split::SPLIT.iter().enumerate() {
        for (a, b) in y[*i].iter_mut().zip(&v[k]) {
            *a += b * 0.7;
        }
    }
    let windows = Windows {
        bins_per_hz: 24.0,
        smoothing: (0.25, 0.05),
        min_half: 18,
        cell: 4,
        per_bin: Dof {
            equivalent: 0.6,
            independent: 0.5,
        },
        power_norm: 1.0,
        witness_floor: None,
    };
    let slid = slide(&y, &w, &v, &windows);
    let cells = bins.div_ceil(4);
    assert_eq!(slid.len(), cells);
    for (c, (total, left)) in slid.iter().enumerate() {
        let centre = (c * 4 + 2) as f64;
        let half_bins = daniell_half_width((0.25, 0.05), centre / 24.0, 24.0).max(18);
        let half = half_bins.div_ceil(4);
        let range = c.saturating_sub(half) * 4..((c + half + 1).min(cells) * 4).min(bins);
        let mut sums = Sums::zero();
        for k in range.clone() {
            let u = (k as f64 - centre) / half_bins as f64;
            sums.add(&bin(&y, k), &bin(&w, k), &split_bin(&v, k), u);
        }
        let count = range.len() as f64;
        let dof = Dof {
            equivalent: 0.6 * count,
            independent: 0.5 * count,
        };
        let (want_total, want_left) = unexplained(&sums, count, dof, 1.0);
        let left = left.expect("says");
        let want_left = want_left.expect("says");
        for a in 0..3 {
            assert!((total[a] / want_total[a] - 1.0).abs() < 1e-9, "cell {c}");
            assert!(
                (left[a] / want_left[a] - 1.0).abs() < 1e-7,
                "cell {c}: {left:?} {want_left:?}"
            );
        }
    }
}

/// Through the real windows on a Hann-windowed record, angles of white noise that the
/// (independent) witness cannot explain: counting the Hann bins' correlation, the level reads
/// the noise's per-sample variance (within 3 %); counting the window's `2n/3` equivalent
/// samples, as the model does (module docs), 3-6 % low. Either way noise alone seldom buys a
/// slope (which would take the level a further `3 / M` down).
#[test]
fn a_hann_windowed_white_noise_reads_its_variance() {
    let mut rng = Rng::new(9);
    let (n, rate) = (12_000, 500.0);
    let mut fft = crate::fourier::RecordFft::new(n, rate);
    let mut record = |sigma: f64| {
        [(); 3].map(|()| {
            let x: Vec<f64> = (0..n).map(|_| sigma * rng.normal()).collect();
            fft.forward(&super::super::witness_delay::hann_windowed(&x, n))
        })
    };
    let (y, w) = (record(2.0), record(1.0));
    let no_split = [(); 4].map(|()| vec![Complex64::default(); y[0].len()]);
    let independent = 1.0 / (35.0 / 18.0);
    let mean_left = |equivalent: f64| {
        let windows = Windows {
            bins_per_hz: n as f64 / rate,
            smoothing: (0.25, 0.05),
            min_half: 18,
            cell: 4,
            per_bin: Dof {
                equivalent,
                independent,
            },
            power_norm: 3.0 * n as f64 / 8.0,
            witness_floor: None,
        };
        let said = slide(&y, &w, &no_split, &windows);
        // Away from DC and Nyquist, where a bin is real.
        let inner = &said[10..said.len() - 10];
        inner
            .iter()
            .map(|(_, l)| l.expect("says").iter().sum::<f64>() / 3.0)
            .sum::<f64>()
            / inner.len() as f64
            / 4.0
    };
    let right = mean_left(independent);
    let as_samples = mean_left(2.0 / 3.0);
    assert!((right - 1.0).abs() < 0.03, "{right}");
    assert!((0.94..0.975).contains(&as_samples), "{as_samples}");
}

/// Too few bins for six regressors: nothing is said.
#[test]
fn too_few_bins_say_nothing() {
    let mut rng = Rng::new(3);
    let mut sums = Sums::zero();
    for (k, (y, w)) in random_bins(&mut rng, 7).iter().enumerate() {
        sums.add(y, w, &NO_SPLIT, k as f64 / 7.0);
    }
    assert!(
        unexplained(
            &sums,
            7.0,
            Dof {
                equivalent: 7.0,
                independent: 7.0
            },
            1.0
        )
        .1
        .is_none()
    );
}

/// Angles that hold a part of their split regressors (`colour_split`) beside a witness whose
/// transfer is a line: the split is fitted and what is left is the noise's power, the
/// `M / (M - 6 - q)` correction counting the split's regressors (the mean over many windows
/// within 3 %; without the split the part would be left, 25 times the noise). Angles without such
/// a part keep the window's own fit in all but a few windows of a thousand.
#[test]
fn a_split_part_is_explained_and_noise_alone_keeps_the_window_s_fit() {
    let mut rng = Rng::new(13);
    let n = 48;
    let all = Dof {
        equivalent: n as f64,
        independent: n as f64,
    };
    let (mut with_part, mut changed, windows) = (Vec::new(), 0, 1000);
    for _ in 0..windows {
        let bins = random_bins(&mut rng, n);
        let mut c = || Complex64::new(rng.normal(), rng.normal());
        let v: Vec<Vector4<Complex64>> = (0..n).map(|_| Vector4::new(c(), c(), c(), c())).collect();
        let (mut part, mut plain, mut alone) = (Sums::zero(), Sums::zero(), Sums::zero());
        for (k, ((noise, w), v)) in bins.iter().zip(&v).enumerate() {
            let u = (k as f64 - 23.5) / 24.0;
            let line = w * Complex64::new(1.5, 0.4 * u) + noise * Complex64::from(0.1);
            // Yaw's split regressor is `v[2]` (`SPLIT`).
            let y = line + Vector3::new(Complex64::default(), v[2] * 0.5, Complex64::default());
            part.add(&y, w, v, u);
            plain.add(&line, w, v, u);
            alone.add(&line, w, &NO_SPLIT, u);
        }
        with_part.push(unexplained(&part, n as f64, all, 1.0).1.expect("says")[1]);
        let (a, b) = (
            unexplained(&plain, n as f64, all, 1.0).1.expect("says"),
            unexplained(&alone, n as f64, all, 1.0).1.expect("says"),
        );
        changed += (0..3).filter(|&i| (a[i] - b[i]).abs() > 1e-12 * b[i]).count();
    }
    let mean = with_part.iter().sum::<f64>() / with_part.len() as f64;
    assert!(
        (mean / 0.02 - 1.0).abs() < 0.03,
        "mean unexplained {mean}, noise 0.02"
    );
    assert!(
        changed <= 3 * windows / 200,
        "{changed} axes of {} changed",
        3 * windows
    );
}
