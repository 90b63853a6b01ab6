use super::{input_line, input_lines_hz, strongest_line};
use crate::block::Block;
use crate::diagnose::design::Design;
use crate::rng::Rng;

/// Slices of three owned channels.
fn views(x: &[Vec<f64>; 3]) -> [&[f64]; 3] {
    x.each_ref().map(Vec::as_slice)
}

/// Three channels of unit white noise with a tone of amplitude `a` at `f` Hz where `on(t)`.
fn record(fs: f64, seconds: f64, f: f64, a: f64, on: &dyn Fn(f64) -> bool) -> [Vec<f64>; 3] {
    let mut rng = Rng::new(7);
    let n = (fs * seconds) as usize;
    [0.3, 1.1, 2.0].map(|phase: f64| {
        (0..n)
            .map(|k| {
                let t = k as f64 / fs;
                let tone = if on(t) {
                    a * (std::f64::consts::TAU * f * t + phase).sin()
                } else {
                    0.0
                };
                tone + rng.normal()
            })
            .collect()
    })
}

#[test]
fn a_pulsed_tone_is_found_with_its_gate_and_its_whole_evidence() {
    let (fs, seconds, f, a) = (500.0, 120.0, 30.0, 0.12);
    let pulsed = |t: f64| t.rem_euclid(5.0) < 2.0;
    let out = record(fs, seconds, f, a, &pulsed);
    let zero = [
        vec![0.0; out[0].len()],
        vec![0.0; out[0].len()],
        vec![0.0; out[0].len()],
    ];
    let mut design =
        Design::line_search(Block::Gyro, views(&out), views(&zero), fs, [5.0, 100.0]).expect("design");
    let residual = design.set_line_level([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 0.0);
    let tone = strongest_line(&design, &residual, &design.outputs()).expect("a line");
    assert!((tone.frequency_hz - f).abs() < 1e-3, "{}", tone.frequency_hz);
    let gate = tone.gate.as_ref().expect("gated");
    assert!((gate.on_fraction - 0.4).abs() < 0.06, "{}", gate.on_fraction);
    // chi2 of the tone where on, in tapered units: N A^2 / (2 sigma^2) per channel, times
    // the on-time's share of the tapered record's power (0.4), over the taper's bandwidth.
    let n = fs * seconds;
    let want = 3.0 * n * a * a / 2.0 * 0.4 / 1.5;
    assert!(
        tone.delta_chi2 > 0.7 * want && tone.delta_chi2 < 1.3 * want,
        "{} vs {want}",
        tone.delta_chi2
    );
    for (est, truth) in tone.amplitude().iter().zip([a; 3]) {
        assert!((est - truth).abs() < 0.15 * truth, "{est} vs {truth}");
    }
}

/// Three input axes of unit white noise, with a sine of amplitude `a` at `f` Hz on the second.
fn inputs(seed: u64, n: usize, fs: f64, f: f64, a: f64) -> [Vec<f64>; 3] {
    let mut rng = Rng::new(seed);
    [0.0, a, 0.0].map(|amp| {
        (0..n)
            .map(|k| amp * (std::f64::consts::TAU * f * k as f64 / fs).sin() + rng.normal())
            .collect()
    })
}

#[test]
fn no_tone_is_named_at_a_line_of_the_inputs() {
    let (fs, seconds, f, a) = (500.0, 120.0, 30.0, 0.12);
    let out = record(fs, seconds, f, a, &|_| true);
    let n = out[0].len();
    let unit = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for seed in 1..=4 {
        // Broadband inputs: the outputs' tone is found, and no bin of the band is taken for
        // an input line (about 57 000 bins per seed).
        let broadband = inputs(seed, n, fs, f, 0.0);
        let mut design = Design::line_search(Block::Gyro, views(&out), views(&broadband), fs, [5.0, 100.0])
            .expect("design");
        let flagged = (0..design.n_bins()).filter(|&k| input_line(&design, k)).count();
        assert_eq!(flagged, 0, "seed {seed}");
        assert!(input_lines_hz(&design).is_empty(), "seed {seed}");
        let residual = design.set_line_level(unit, 0.0);
        let tone = strongest_line(&design, &residual, &design.outputs()).expect("a line");
        assert!((tone.frequency_hz - f).abs() < 1e-3, "{}", tone.frequency_hz);
        // A sine of the inputs at the tone's frequency (a stand programme's, 26 dB above the
        // continuum at 1/5 of the tone's amplitude): not named there.
        let programme = inputs(seed, n, fs, f, 0.2);
        let mut design = Design::line_search(Block::Gyro, views(&out), views(&programme), fs, [5.0, 100.0])
            .expect("design");
        let residual = design.set_line_level(unit, 0.0);
        let at = design.frequency_hz.iter().position(|&h| h >= f).expect("bin");
        assert!(input_line(&design, at), "seed {seed}");
        // Listed once, at its frequency.
        let lines = input_lines_hz(&design);
        assert_eq!(lines.len(), 1, "seed {seed}: {lines:?}");
        assert!((lines[0] - f).abs() < 0.02, "seed {seed}: {lines:?}");
        let line = strongest_line(&design, &residual, &design.outputs());
        assert!(
            line.as_ref().is_none_or(|t| (t.frequency_hz - f).abs() > 1.0),
            "seed {seed}: {:?}",
            line.map(|t| t.frequency_hz)
        );
    }
}

/// A programme of six sines, each leaving a misfit line in the residual stronger than a real
/// tone: the six are passed over without using the search's tries, and the tone is named.
#[test]
fn input_lines_do_not_use_up_the_search_s_tries() {
    let (fs, seconds, f, a) = (500.0, 120.0, 30.0, 0.12);
    let programme = [12.0, 18.0, 24.0, 40.0, 46.0, 52.0];
    let mut out = record(fs, seconds, f, a, &|_| true);
    let n = out[0].len();
    let mut input = inputs(3, n, fs, f, 0.0);
    for (k, (x, u)) in out[1].iter_mut().zip(input[1].iter_mut()).enumerate() {
        let t = k as f64 / fs;
        let sines: f64 = programme
            .iter()
            .map(|p| (std::f64::consts::TAU * p * t).sin())
            .sum();
        *u += 0.5 * sines;
        *x += 0.3 * sines;
    }
    let mut design =
        Design::line_search(Block::Gyro, views(&out), views(&input), fs, [5.0, 100.0]).expect("design");
    let residual = design.set_line_level([[0.0; 3]; 3], 0.0);
    assert_eq!(
        input_lines_hz(&design).len(),
        programme.len(),
        "{:?}",
        input_lines_hz(&design)
    );
    let tone = strongest_line(&design, &residual, &design.outputs()).expect("the tone");
    assert!((tone.frequency_hz - f).abs() < 1e-3, "{}", tone.frequency_hz);
}
