use super::*;
use crate::ident::spectra::BlockSpectra;
use num_complex::Complex64;

/// A left-out model of `level` rad^2/Hz per axis over 0.05-100 Hz (one band).
fn flat(level: [f64; 3]) -> ErrorPsd {
    ErrorPsd {
        frequency_hz: vec![2.0],
        edges_hz: vec![0.05, 100.0],
        psd: vec![level],
    }
}

fn at_rest(psd: ErrorPsd) -> LeftOutNoise {
    let zero = [0.0; 4];
    LeftOutNoise::for_gyro(psd, [&zero, &zero, &zero])
}

/// Spectra with bins at 1..=n Hz and the input matrix `s_uu(f)`.
fn spectra(n: usize, s_uu: impl Fn(f64) -> Matrix3<Complex64>) -> BlockSpectra {
    let mut s = crate::ident::witness_noise::tests_support::spectra(1.0, 1.0);
    s.frequency_hz = (0..=n).map(|k| k as f64).collect();
    s.s_uu = s.frequency_hz.iter().map(|&f| s_uu(f)).collect();
    s
}

/// At rest `E` is the axis map `[roll, yaw, pitch] -> [x, y, z]`, the identity; turned by a
/// roll of 90 degrees, a yaw rate is seen about the body's `-z`.
#[test]
fn the_euler_to_body_map_follows_the_mean_attitude() {
    let e = at_rest(flat([0.0; 3])).to_inputs[1];
    assert!((e - Matrix3::identity()).abs().max() < 1e-15, "{e}");
    let roll = [std::f64::consts::FRAC_PI_2; 2];
    let zero = [0.0; 2];
    let e = LeftOutNoise::for_gyro(flat([0.0; 3]), [&roll, &zero, &zero]).to_inputs[1];
    assert!((e[(2, 1)] + 1.0).abs() < 1e-12 && e[(1, 1)].abs() < 1e-12, "{e}");
}

/// An accelerometer at rest, level, at `r`: the tilt of gravity `A` (a roll turns `g` into `-z`,
/// a pitch into `x`, a yaw does nothing) and the lever arm's `B` columns `e_j x r` (Euler
/// accelerations are body ones at rest), closed forms; the noise reaches the inputs through
/// `A - w^2 B`.
#[test]
fn an_accelerometer_takes_the_noise_through_gravity_and_its_lever_arm() {
    let zero = [0.0; 3];
    let (r, g) = ([0.3, 0.12, -0.05], 9.81);
    let m = LeftOutNoise::for_accel(flat([1e-9, 0.0, 0.0]), [&zero, &zero, &zero], r, g);
    let [a, c, b] = m.to_inputs;
    let want_a = Matrix3::new(0.0, 0.0, g, 0.0, 0.0, 0.0, -g, 0.0, 0.0);
    assert!((a - want_a).abs().max() < 1e-6, "{a}");
    assert_eq!(c, Matrix3::zeros());
    let rv = nalgebra::Vector3::from(r);
    for j in 0..3 {
        let want = nalgebra::Vector3::ith(j, 1.0).cross(&rv);
        assert!((b.column(j) - want).abs().max() < 1e-12, "{b}");
    }
    // Roll noise alone, at 2 Hz: dN_u = t t^T 1e-9 with t the roll column of A - w^2 B.
    let w2 = (2.0 * std::f64::consts::PI * 2.0).powi(2);
    let t = a.column(0) - b.column(0) * w2;
    let want = t * t.transpose() * 1e-9;
    let got = m.in_inputs(2.0).expect("in band");
    assert!(
        (got - want).abs().max() < 1e-9 * want.abs().max(),
        "{got} vs {want}"
    );
}

/// Uncoupled inputs of density `S` at every bin, a diagonal `K`, the same left-out level `n` on
/// every axis and coherence: each gain reads low by the bins' mean of `w^2 n / S`, the closed
/// form `K_ii n (2 pi)^2 mean(f^2) / S`; the off-diagonal elements do not move.
#[test]
fn uncoupled_inputs_shift_each_gain_by_the_mean_share() {
    let s = 2.5e-3;
    let sp = spectra(10, |_| Matrix3::from_diagonal_element(Complex64::from(s)));
    let n = 1e-9;
    let band: Vec<usize> = (1..=10).collect();
    let coherence = vec![[0.9; 3]; 11];
    let k = [[1.01, 0.0, 0.0], [0.0, 0.99, 0.0], [0.0, 0.0, 1.0]];
    let shift = gain_shift(&sp, &coherence, &band, &k, &at_rest(flat([n; 3])));
    let mean_f2 = (1..=10).map(|f| f64::from(f * f)).sum::<f64>() / 10.0;
    let share = n * (2.0 * std::f64::consts::PI).powi(2) * mean_f2 / s;
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { -k[i][i] * share } else { 0.0 };
            assert!(
                (shift[i][j] - want).abs() < 1e-12 * share.max(1.0),
                "{i}{j}: {} vs {want}",
                shift[i][j]
            );
        }
    }
}

/// Coupled inputs (roll and yaw correlated 0.9, as a turbulent cruise's) with noise left out of
/// roll alone: against the brute-force first-order `K dN S^-1` of one bin, and the cross gain
/// `K[x][y]` moves though `K` is the identity (by `-dN_x (S^-1)_xy`).
#[test]
fn coupled_inputs_move_the_cross_gains() {
    let (a, rho) = (1e-2, 0.9);
    let s_uu = Matrix3::new(a, rho * a, 0.0, rho * a, a, 0.0, 0.0, 0.0, a).map(Complex64::from);
    let sp = spectra(1, |_| s_uu);
    let n = 1e-8;
    let k = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let shift = gain_shift(&sp, &[[0.5; 3]; 2], &[1], &k, &at_rest(flat([n, 0.0, 0.0])));
    let dn = (2.0 * std::f64::consts::PI).powi(2) * n;
    let inv = s_uu.map(|c| c.re).try_inverse().unwrap();
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == 0 { -dn * inv[(0, j)] } else { 0.0 };
            assert!(
                (shift[i][j] - want).abs() < 1e-9 * dn * inv.abs().max(),
                "{i}{j}: {} vs {want}",
                shift[i][j]
            );
        }
    }
    assert!(shift[0][1] > 0.5 * shift[0][0].abs(), "{shift:?}");
}

/// Two bins each moving one axis only (each `S_uu` singular on its own): the shift is the
/// weighted sums' closed form `-K (sum dN) (sum S_uu)^-1`, which a per-bin inverse could not give.
#[test]
fn the_bins_are_summed_before_the_inverse() {
    let sp = spectra(2, |f| {
        let mut m = Matrix3::zeros();
        m[(0, 0)] = Complex64::from(if f < 1.5 { 4e-2 } else { 1e-2 });
        m[(1, 1)] = Complex64::from(if f < 1.5 { 0.0 } else { 3e-2 });
        m[(2, 2)] = Complex64::from(if f < 1.5 { 0.0 } else { 2e-2 });
        m
    });
    let k = [[1.0, 0.002, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let n = 1e-9;
    let shift = gain_shift(&sp, &[[0.8; 3]; 3], &[1, 2], &k, &at_rest(flat([n; 3])));
    let w2 = |f: f64| (2.0 * std::f64::consts::PI * f).powi(2);
    let dn = Matrix3::from_diagonal_element(n * (w2(1.0) + w2(2.0)));
    let s = Matrix3::from_diagonal(&nalgebra::Vector3::new(5e-2, 3e-2, 2e-2));
    let want = -Matrix3::from_fn(|i, j| k[i][j]) * dn * s.try_inverse().unwrap();
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (shift[i][j] - want[(i, j)]).abs() < 1e-12 * want.abs().max(),
                "{i}{j}: {shift:?} vs {want}"
            );
        }
    }
}

/// Bins outside the left-out model's bands, with a NaN coherence or a singular `S_uu` give no
/// shift; the widening adds `|dK| / sqrt(3)` in quadrature.
#[test]
fn nothing_known_shifts_nothing_and_the_widening_is_uniform() {
    let sp = spectra(3, |f| {
        if f > 2.5 {
            Matrix3::zeros()
        } else {
            Matrix3::from_diagonal_element(Complex64::from(1e-2))
        }
    });
    let k = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let outside = ErrorPsd {
        frequency_hz: vec![50.0],
        edges_hz: vec![40.0, 60.0],
        psd: vec![[1e-6; 3]],
    };
    assert_eq!(
        gain_shift(&sp, &[[0.9; 3]; 4], &[1, 2], &k, &at_rest(outside)),
        [[0.0; 3]; 3]
    );
    let nan = [[f64::NAN; 3]; 4];
    assert_eq!(
        gain_shift(&sp, &nan, &[1, 2], &k, &at_rest(flat([1e-6; 3]))),
        [[0.0; 3]; 3]
    );
    assert_eq!(
        gain_shift(&sp, &[[0.9; 3]; 4], &[3], &k, &at_rest(flat([1e-6; 3]))),
        [[0.0; 3]; 3]
    );

    let mut fit = crate::ident::witness_noise::tests_support::fit(k, 1e-4);
    let shift = [[3e-4, 0.0, 0.0], [0.0; 3], [0.0, 0.0, -6e-4]];
    widen_for_left_out_noise(&mut fit, &shift);
    assert!((fit.k_std[0][0] - 1e-4_f64.hypot(3e-4 / 3.0_f64.sqrt())).abs() < 1e-18);
    assert!((fit.k_std[1][1] - 1e-4).abs() < 1e-18);
    assert!((fit.k_std[2][2] - 1e-4_f64.hypot(6e-4 / 3.0_f64.sqrt())).abs() < 1e-18);
}

/// Through the whole identification: inputs that carry a white noise beside the motion (what
/// the observer leaves in them when its model keeps the floor), with that noise as the left-out
/// model (`A = I`: the inputs are the angles' units), fitted with and without it. The gains the
/// noisy inputs give differ from the clean ones by the shift the model file states, within a
/// tenth of the largest shift (measured: 5 % at most, the largest 0.023): the fit's own weights and
/// reweighting are what the closed form approximates, first order and all. The inputs are coupled (the second and third mix the
/// first's and second's motions), so the cross gains move too, and the shift is several hundred
/// of the clean fit's deviations: a wrong sign, a per-bin inverse or a missing `K` would fail.
#[test]
fn the_stated_shift_is_what_noise_in_the_inputs_does_to_the_fit() {
    use crate::block::Block;
    use crate::ident::band::BandSetting;
    use crate::ident::factorisation::{FactorisationSettings, factorise_from};
    use crate::ident::identify::identify_block_from;
    use crate::ident::settings::{BlockOrders, Estimate, OrderSetting, Settings};
    use crate::ident::signals::BlockSignals;
    use crate::ident::spectra::block_spectra;
    use crate::rng::Rng;
    use crate::spectral::{WelchPlanner, WelchSettings};
    use std::sync::Arc;

    let (rate, n, delay, sigma) = (200.0, 60_000, 3, 0.15);
    let k = Matrix3::new(1.002, 0.003, -0.001, -0.002, 0.997, 0.001, 0.004, -0.002, 1.001);
    let mut rng = Rng::new(41);
    let white: Vec<[f64; 3]> = (0..n + 2)
        .map(|_| [rng.normal(), rng.normal(), rng.normal()])
        .collect();
    let mix = |t: usize, i: usize| white[t + 2][i] + 0.5 * white[t + 1][i] - 0.2 * white[t][i];
    let motion: [Vec<f64>; 3] = [
        (0..n).map(|t| mix(t, 0)).collect(),
        (0..n).map(|t| 0.6 * mix(t, 0) + 0.8 * mix(t, 1)).collect(),
        (0..n).map(|t| 0.3 * mix(t, 1) + 0.9 * mix(t, 2)).collect(),
    ];
    let output: [Vec<f64>; 3] = std::array::from_fn(|i| {
        (0..n)
            .map(|t| {
                let late = t.saturating_sub(delay);
                (0..3).map(|j| k[(i, j)] * motion[j][late]).sum::<f64>() + 0.02 * rng.normal()
            })
            .collect()
    });
    let noisy: [Vec<f64>; 3] =
        std::array::from_fn(|j| motion[j].iter().map(|u| u + sigma * rng.normal()).collect());
    let settings = Settings {
        band_hz: BandSetting::Fixed([1.0, 80.0]),
        order: BlockOrders::both(OrderSetting::Fixed(0)),
        ..Settings::default()
    };
    let fit = |input: [Vec<f64>; 3], left_out: Option<LeftOutNoise>| {
        let signals = BlockSignals {
            block: Block::Gyro,
            input,
            output: output.clone(),
        };
        let mut sp = block_spectra(
            &mut WelchPlanner::new(),
            &signals,
            rate,
            &WelchSettings::default(),
        )
        .expect("spectra");
        sp.left_out_noise = left_out.map(Arc::new);
        let f =
            factorise_from(&sp, &FactorisationSettings::default(), None, Estimate::H1).expect("factorised");
        identify_block_from(Block::Gyro, Arc::new(sp), Arc::new(f), &settings, None).expect("identified")
    };
    let clean = fit(motion.clone(), None);
    assert!(clean.k_shift_left_out_angle_noise.is_none());
    // The noise's one-sided density, rad^2/Hz, over the whole grid.
    let level = 2.0 * sigma * sigma / rate;
    let left_out = LeftOutNoise {
        psd: ErrorPsd {
            frequency_hz: vec![50.0],
            edges_hz: vec![0.0, 100.0],
            psd: vec![[level; 3]],
        },
        to_inputs: [Matrix3::identity(), Matrix3::zeros(), Matrix3::zeros()],
    };
    let with_noise = fit(noisy, Some(left_out));
    let shift = with_noise.k_shift_left_out_angle_noise.expect("a left-out model");
    let moved = |i: usize, j: usize| with_noise.structural.k[i][j] - clean.structural.k[i][j];
    let largest = shift.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    let clean_std = clean
        .structural
        .k_std
        .iter()
        .flatten()
        .fold(0.0_f64, |m, v| m.max(*v));
    assert!(
        largest > 100.0 * clean_std,
        "shift {largest:e} vs deviation {clean_std:e}"
    );
    for i in 0..3 {
        assert!(shift[i][i] < 0.0, "the gains read low: {shift:?}");
        for j in 0..3 {
            assert!(
                (moved(i, j) - shift[i][j]).abs() < 0.1 * largest,
                "K[{i}][{j}] moved {:e}, stated {:e} ({shift:?})",
                moved(i, j),
                shift[i][j]
            );
        }
    }
    // The cross gains move where the inputs are coupled: the first row's second element.
    assert!(shift[0][1].abs() > 0.1 * largest, "{shift:?}");
}
