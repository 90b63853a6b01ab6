//! Unit tests of the diagnosis's numerical pieces against brute-force references.

use num_complex::Complex64;

use super::candidates::{Candidate, Extension};
use super::design::{Design, DesignSignals};
use super::fit::fit;
use super::structure::{Structure, Theta};
use super::tone::strongest_line;
use crate::block::Block;
use crate::effect::Effect;
use crate::fourier::{RecordFft, fast_len};
use crate::rng::Rng;

/// A record `x = K u(t - tau) + white noise`, `u` white, built by exact frequency-domain delay.
fn synthetic(
    k: [[f64; 3]; 3],
    tau: f64,
    noise: f64,
    n: usize,
    fs: f64,
    seed: u64,
) -> ([Vec<f64>; 3], [Vec<f64>; 3]) {
    let mut rng = Rng::new(seed);
    let len = fast_len(2 * n);
    let mut fft = RecordFft::new(len, fs);
    let u: [Vec<f64>; 3] = [0; 3].map(|_| (0..len).map(|_| rng.normal()).collect());
    let spectra: [Vec<Complex64>; 3] = u.each_ref().map(|x| fft.forward(x));
    let mut x: [Vec<f64>; 3] = Default::default();
    for i in 0..3 {
        let mut s = vec![Complex64::default(); fft.n_bins()];
        for (kk, v) in s.iter_mut().enumerate() {
            let f = fft.frequency_hz(kk);
            let d = Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * tau);
            *v = (0..3).map(|j| spectra[j][kk] * k[i][j]).sum::<Complex64>() * d;
        }
        let xt = fft.inverse(s);
        x[i] = xt[..n].iter().map(|v| v + noise * rng.normal()).collect();
    }
    (x, u.map(|v| v[..n].to_vec()))
}

fn design(x: &[Vec<f64>; 3], u: &[Vec<f64>; 3], fs: f64, noise: f64, aux: &[Vec<f64>]) -> Design {
    // One-sided density of white noise of variance noise^2.
    let level = 2.0 * noise * noise / fs;
    Design::new(
        &DesignSignals {
            block: Block::Gyro,
            output: x.each_ref().map(Vec::as_slice),
            input: u.each_ref().map(Vec::as_slice),
            auxiliary: &aux.iter().map(Vec::as_slice).collect::<Vec<_>>(),
            sample_rate_hz: fs,
        },
        [0.5, 40.0],
        &|_, _| level,
    )
    .unwrap()
}

#[test]
fn base_fit_recovers_gain_and_delay_and_chi2_matches_the_noise() {
    let k = [
        [1.001, 2e-3, -1e-3],
        [0.5e-3, 0.998, 1.5e-3],
        [-2e-3, 1e-3, 1.0005],
    ];
    let (fs, noise) = (200.0, 0.05);
    let (x, u) = synthetic(k, 7.3e-3, noise, 20_000, fs, 3);
    let aux: Vec<Vec<f64>> = u.to_vec();
    let d = design(&x, &u, fs, noise, &aux);
    let grams = d.grams(&d.outputs());
    let theta = Theta::delay_only(5e-3);
    let f = fit(&d, &grams, &Structure::default(), &theta, [0.5, 40.0]).unwrap();
    assert!((f.theta.tau_s - 7.3e-3).abs() < 2e-5, "tau {}", f.theta.tau_s);
    for i in 0..3 {
        for j in 0..3 {
            assert!((f.profile.beta[3 * i + j] - k[i][j]).abs() < 2e-3, "K[{i}][{j}]");
        }
    }
    // White noise of the declared level: chi2 per real degree of freedom near 1.
    let per_dof = f.chi2() / (3.0 * d.dof_per_channel());
    assert!((per_dof - 1.0).abs() < 0.05, "chi2/dof {per_dof}");
}

#[test]
fn a_hidden_tone_is_found_at_its_frequency_and_amplitude() {
    let k = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let (fs, noise) = (200.0, 0.02);
    let (mut x, u) = synthetic(k, 2e-3, noise, 20_000, fs, 4);
    let (f0, amp) = (23.456_7, [0.02, 0.01, 0.0]);
    for i in 0..3 {
        for (n, v) in x[i].iter_mut().enumerate() {
            *v += amp[i] * (2.0 * std::f64::consts::PI * f0 * n as f64 / fs + 0.3 * i as f64).sin();
        }
    }
    let d = design(&x, &u, fs, noise, u.as_ref());
    let grams = d.grams(&d.outputs());
    let theta = Theta::delay_only(2e-3);
    let f = fit(&d, &grams, &Structure::default(), &theta, [0.5, 40.0]).unwrap();
    let model = super::profile::predict(&d, &f.structure, &f.layout, &f.theta, &f.profile.beta);
    let residual = [0, 1, 2].map(|i| d.z[i].iter().zip(&model[i]).map(|(a, b)| a - b).collect());
    let tone = strongest_line(&d, &residual, &d.outputs()).unwrap();
    assert!((tone.frequency_hz - f0).abs() < 2e-4, "{}", tone.frequency_hz);
    let a = tone.amplitude();
    assert!(
        (a[0] - 0.02).abs() < 1e-3 && (a[1] - 0.01).abs() < 1e-3 && a[2] < 1e-3,
        "{a:?}"
    );
    assert!(tone.delta_chi2 > 1000.0);
}

fn lag_finding(block: Block, t: f64, sd: f64) -> super::Finding {
    super::Finding {
        block,
        effect: Effect::SensorLag,
        name: Effect::SensorLag.name_on(block),
        parameters: serde_json::json!({"T_s": t}),
        parameter_std: serde_json::json!({"T_s": sd}),
        gap_before_db: -20.0,
        gap_after_db: -25.0,
        evidence: String::new(),
        delta_chi2: 500.0,
        added_parameters: 1,
        criterion_gain: 480.0,
        halves: None,
        search_band: None,
    }
}

#[test]
fn the_same_lag_on_both_blocks_is_the_angle_measurements() {
    // 2.31 +- 0.03 and 2.45 +- 0.04 ms: 2.8 sigma apart, one lag.
    let mut f = vec![
        lag_finding(Block::Gyro, 2.31e-3, 0.03e-3),
        lag_finding(Block::Accel, 2.45e-3, 0.04e-3),
    ];
    super::workflow::name_stand_side(&mut f);
    assert!(f.iter().all(|f| f.effect == Effect::ReferenceLag), "{f:?}");
    assert_eq!(f[0].name, "gyro angle-measurement lag (stand side)");
    assert!(
        f[1].evidence.contains("or a filter both sensor blocks share")
            && f[1].evidence.contains("cannot tell the two apart"),
        "{}",
        f[1].evidence
    );
    // 3.6 and 4.4 ms, a few hundredths of a ms each: two sensors' own lags.
    let mut f = vec![
        lag_finding(Block::Gyro, 3.6e-3, 0.02e-3),
        lag_finding(Block::Accel, 4.4e-3, 0.03e-3),
    ];
    super::workflow::name_stand_side(&mut f);
    assert!(f.iter().all(|f| f.effect == Effect::SensorLag));
    // A lag on one block only is the sensor's.
    let mut f = vec![lag_finding(Block::Gyro, 2.3e-3, 0.03e-3)];
    super::workflow::name_stand_side(&mut f);
    assert_eq!(f[0].effect, Effect::SensorLag);
}

fn band_limit_finding(block: Block, order: i64, causal: bool, corner: f64, sd: f64) -> super::Finding {
    super::Finding {
        effect: Effect::ReferenceBandLimit,
        name: Effect::ReferenceBandLimit.name_on(block),
        parameters: serde_json::json!({
            "shape": if causal { "causal2" } else { "zero_phase" },
            "order": order,
            "causal": causal,
            "corner_hz": corner
        }),
        parameter_std: serde_json::json!({"corner_hz": sd}),
        ..lag_finding(block, 0.0, 0.0)
    }
}

/// `say_shared_band_limit` on a gyro's and an accelerometer's band limit: whether both findings'
/// evidence says `words`.
fn both_say(gyro: super::Finding, accel: super::Finding, words: &str) -> bool {
    let mut f = vec![gyro, accel];
    super::workflow::say_shared_band_limit(&mut f, &[Block::Gyro, Block::Accel]);
    f.iter().all(|f| f.evidence.contains(words))
}

#[test]
fn a_band_limit_says_whether_the_other_block_shows_the_same() {
    let both = [Block::Gyro, Block::Accel];
    let (same, other) = ("the same band limit on both blocks", "another shape or corner");
    // 40.2 +- 0.3 and 39.6 +- 0.4 Hz, both causal order 2: 1.2 sigma apart, one filter.
    assert!(both_say(
        band_limit_finding(Block::Gyro, 2, true, 40.2, 0.3),
        band_limit_finding(Block::Accel, 2, true, 39.6, 0.4),
        same
    ));
    // The same corners, another shape: said as approximate.
    assert!(both_say(
        band_limit_finding(Block::Gyro, 2, true, 40.2, 0.3),
        band_limit_finding(Block::Accel, 4, false, 40.2, 0.3),
        other
    ));
    // Two interpolated references (no order): the same within their deviations.
    let interpolated = |block, corner: f64| super::Finding {
        parameters: serde_json::json!({
            "shape": "interpolated", "causal": false, "corner_hz": corner,
            "reference_rate_hz": corner / crate::model::band_limit::INTERPOLATED_CORNER
        }),
        ..band_limit_finding(block, 1, false, corner, 0.3)
    };
    assert!(both_say(
        interpolated(Block::Gyro, 38.2),
        interpolated(Block::Accel, 38.4),
        same
    ));
    // An interpolated reference against an order-1 one at the same corner: another shape.
    assert!(both_say(
        interpolated(Block::Gyro, 38.2),
        band_limit_finding(Block::Accel, 1, false, 38.2, 0.3),
        other
    ));
    // Corners 10 sigma apart.
    let mut f = vec![
        band_limit_finding(Block::Gyro, 1, false, 40.0, 0.3),
        band_limit_finding(Block::Accel, 1, false, 44.0, 0.3),
    ];
    super::workflow::say_shared_band_limit(&mut f, &both);
    assert!(
        f[0].evidence.contains("44.0 Hz against 40.0 Hz"),
        "{}",
        f[0].evidence
    );
    // One block only: said not found on the other where the other was diagnosed, nothing where
    // it was not (a gyro-only recording).
    let mut f = vec![band_limit_finding(Block::Gyro, 1, false, 40.0, 0.3)];
    super::workflow::say_shared_band_limit(&mut f, &both);
    assert!(
        f[0].evidence.contains("not found on the other block"),
        "{}",
        f[0].evidence
    );
    let mut f = vec![band_limit_finding(Block::Gyro, 1, false, 40.0, 0.3)];
    super::workflow::say_shared_band_limit(&mut f, &[Block::Gyro]);
    assert!(f[0].evidence.is_empty(), "{}", f[0].evidence);
}

/// Outputs that are one broadband motion seen by all three channels at very different scales
/// (the lever-arm motion above the reference's band limit reaches an accelerometer's vertical and
/// lateral channels, hardly its forward one), plus each channel's small noise of its own.
fn collinear_record(scale: [f64; 3], own: f64, n: usize, seed: u64) -> [Vec<f64>; 3] {
    let mut rng = Rng::new(seed);
    let common: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    [0, 1, 2].map(|i| common.iter().map(|c| scale[i] * c + own * rng.normal()).collect())
}

#[test]
fn a_random_peak_of_motion_all_channels_share_is_no_tone() {
    // chi2 of the strongest line of a residual without a tone: each try is a chi2 of six degrees
    // of freedom (two quadratures, three channels), the strongest of some five thousand bins.
    // Weighed as it was (the unscaled projections by the inverse correlation, over the channels'
    // mean level) the same peaks scored in the thousands (3748 on the first seed): false tones.
    // With each channel's own noise at a fiftieth of the forward channel's motion (a real
    // accelerometer's weakest direction holds 2e-4 of the motion's power), each channel scaled
    // by its median level inside the inverse correlation still failed: the medians' few percent
    // of sampling error against the correlation's own scales, at a peak of the motion.
    let (fs, n) = (200.0, 20_000);
    let u: [Vec<f64>; 3] = collinear_record([1.0, 0.5, 0.2], 0.0, n, 99);
    let mut draws = 0;
    for own in [0.01, 0.001, 0.0002] {
        for seed in 0..16 {
            let x = collinear_record([0.05, 1.0, 0.6], own, n, seed);
            let d = design(&x, &u, fs, own, &[]);
            let outputs = d.outputs();
            let Some(tone) = strongest_line(&d, &outputs, &outputs) else {
                continue;
            };
            draws += 1;
            assert!(
                tone.delta_chi2 < 45.0,
                "own {own}, seed {seed}: chi2 {}",
                tone.delta_chi2
            );
        }
    }
    // Every draw offers its strongest peak to be weighed.
    assert_eq!(draws, 48);
}

#[test]
fn a_tone_across_the_shared_motion_is_found() {
    // The same background, and a tone in the forward channel alone (twice its level there, a
    // tenth of the motion): it lies across the shared direction, where the correlated channels
    // say most about it.
    let (fs, n, own) = (200.0, 20_000, 0.01);
    let u: [Vec<f64>; 3] = collinear_record([1.0, 0.5, 0.2], 0.0, n, 99);
    let mut x = collinear_record([0.05, 1.0, 0.6], own, n, 7);
    let f0 = 31.234;
    for (k, v) in x[0].iter_mut().enumerate() {
        *v += 0.1 * (2.0 * std::f64::consts::PI * f0 * k as f64 / fs).sin();
    }
    let d = design(&x, &u, fs, own, &[]);
    let outputs = d.outputs();
    let tone = strongest_line(&d, &outputs, &outputs).unwrap();
    assert!((tone.frequency_hz - f0).abs() < 2e-3, "{}", tone.frequency_hz);
    // Counted apart, the forward channel's evidence is against its whole level, 26 times what
    // the other two leave unexplained of it (0.05^2 + 0.01^2 against 0.01^2): the joint evidence
    // must be that much larger (a cap at the channels counted apart lost true tones; weighed as
    // it was, this one scored a ninth of it).
    let apart: f64 = tone.channel_chi2.iter().sum::<f64>() / super::design::WINDOW_ENBW;
    assert!(
        tone.delta_chi2 > 10.0 * apart,
        "chi2 {} apart {apart}",
        tone.delta_chi2
    );
}

/// A band-limit candidate of `shape` with the given evidence (the fit itself is any fit: the rule
/// reads only the shape and `delta_chi2`).
fn shape_candidate(
    base: &super::fit::Fitted,
    shape: super::band_limit::BandLimitShape,
    delta: f64,
) -> Candidate {
    let mut fitted = base.clone();
    fitted.structure.band_limit = Some(shape);
    Candidate {
        effect: Effect::ReferenceBandLimit,
        extension: Extension::Structural(Box::new(fitted)),
        delta_chi2: delta,
        added_params: 1,
    }
}

#[test]
fn a_causal_band_limit_that_beats_the_shapes_without_phase_by_less_than_ln_dof_is_set_aside() {
    use super::band_limit::{BandLimitShape, without_needless_phase};
    let (x, u) = synthetic(
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        2e-3,
        0.05,
        4000,
        200.0,
        5,
    );
    let d = design(&x, &u, 200.0, 0.05, &[]);
    let grams = d.grams(&d.outputs());
    let base = fit(
        &d,
        &grams,
        &Structure::default(),
        &Theta::delay_only(2e-3),
        [0.5, 40.0],
    )
    .unwrap();
    let (dof, best_without) = (3000.0_f64, 120.0);
    let zero_phase = BandLimitShape::SHAPES.into_iter().find(|s| !s.causal()).unwrap();
    let offered = |causal_delta: f64| {
        vec![
            shape_candidate(&base, zero_phase, best_without),
            shape_candidate(&base, zero_phase, best_without - 50.0),
            shape_candidate(&base, BandLimitShape::Causal2, causal_delta),
        ]
    };
    let causal_kept = |c: &[Candidate]| {
        c.iter()
            .any(|c| c.band_limit_shape() == Some(BandLimitShape::Causal2))
    };
    let margin = dof.ln();
    // Better than the shapes without phase, but by less than ln(dof): set aside.
    let kept = without_needless_phase(offered(best_without + margin - 0.1), dof);
    assert_eq!(kept.len(), 2);
    assert!(!causal_kept(&kept));
    // By more: kept, with the others.
    let kept = without_needless_phase(offered(best_without + margin + 0.1), dof);
    assert_eq!(kept.len(), 3);
    assert!(causal_kept(&kept));
    // Below them: kept for the candidates' table, where they come first.
    let kept = without_needless_phase(offered(best_without - 1.0), dof);
    assert_eq!(kept.len(), 3);
    // Alone (every other shape's fit failed): nothing to beat.
    let alone = without_needless_phase(vec![shape_candidate(&base, BandLimitShape::Causal2, 5.0)], dof);
    assert!(causal_kept(&alone));
    // The round's look-elsewhere cost counts every shape tried, the one set aside too.
    let set_aside = without_needless_phase(offered(best_without + 1.0), dof);
    assert_eq!(set_aside.len(), 2);
    assert_eq!(
        super::candidates::tried(&set_aside),
        super::candidates::tried(&offered(best_without + 1.0)),
    );
    assert_eq!(super::candidates::tried(&set_aside), BandLimitShape::SHAPES.len());
    // A tie with the best shape without phase: set aside (no better than it at all).
    assert_eq!(without_needless_phase(offered(best_without), dof).len(), 2);
    // Another effect's candidate counts once beside the six shapes.
    let mut mixed = set_aside;
    mixed.push(Candidate {
        effect: Effect::GSensitivity,
        extension: Extension::Structural(Box::new(base.clone())),
        delta_chi2: 3.0,
        added_params: 9,
    });
    assert_eq!(super::candidates::tried(&mixed), BandLimitShape::SHAPES.len() + 1);
    assert_eq!(super::candidates::tried(&mixed[2..]), 1);
    // A lag counts both its shapes, one of them offered or both.
    let lag = Candidate {
        effect: Effect::SensorLag,
        extension: Extension::Structural(Box::new(base.clone())),
        delta_chi2: 3.0,
        added_params: 1,
    };
    mixed.push(lag.clone());
    assert_eq!(
        super::candidates::tried(&mixed),
        BandLimitShape::SHAPES.len() + 1 + 2
    );
    mixed.push(lag);
    assert_eq!(
        super::candidates::tried(&mixed),
        BandLimitShape::SHAPES.len() + 1 + 2
    );
}
