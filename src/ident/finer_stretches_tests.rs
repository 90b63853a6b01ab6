//! The stationarity check of a record too short for stretches at the settings' segment: its
//! stretches on a shorter segment ([`super::stretches::finer_segment_len`]).

use super::signals::BlockSignals;
use super::spectra::block_spectra;
use super::stretches::{MIN_STRETCHES, finer_segment_len, stationarity};
use crate::block::Block;
use crate::rng::Rng;
use crate::spectral::{WelchPlanner, WelchSettings};

fn settings(segment_len: usize) -> WelchSettings {
    WelchSettings {
        segment_len,
        ..WelchSettings::default()
    }
}

/// Samples holding `n` half-overlapping segments of `len`.
fn samples(len: usize, n: usize) -> usize {
    len + (n - 1) * len / 2
}

#[test]
fn the_finer_segment_is_the_longest_that_gives_enough_stretches() {
    // 17 segments of 4096 give 2 stretches; 35 of 2048 give 5.
    assert_eq!(finer_segment_len(&settings(4096), samples(4096, 17)), Some(2048));
    // 7 of 4096: 2048 gives 15 (2 stretches), 1024 gives 31 (5).
    assert_eq!(finer_segment_len(&settings(4096), samples(4096, 7)), Some(1024));
    // Enough at the settings' own segment: none.
    assert_eq!(finer_segment_len(&settings(4096), samples(4096, 24)), None);
    // Too short even at a quarter of the segment: none (3 segments of 4096: 1024 gives 15).
    assert_eq!(finer_segment_len(&settings(4096), samples(4096, 3)), None);
    // Never below 256 samples.
    assert_eq!(finer_segment_len(&settings(512), samples(512, 7)), None);
}

/// A gyro-like block `x = g(t) u + noise` on white inputs, the gain `g` stepping from 1 to
/// `1 + step` half-way through a record of `n_segments` segments of 4096 at 500 Hz.
fn stepped_record(n_segments: usize, step: f64, seed: u64) -> super::spectra::BlockSpectra {
    let n = samples(4096, n_segments);
    let mut rng = Rng::new(seed);
    let input: [Vec<f64>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng.normal()).collect());
    let output: [Vec<f64>; 3] = std::array::from_fn(|i| {
        (0..n)
            .map(|t| {
                let g = if t < n / 2 { 1.0 } else { 1.0 + step };
                g * input[i][t] + 0.001 * rng.normal()
            })
            .collect()
    });
    let signals = BlockSignals {
        block: Block::Gyro,
        input,
        output,
    };
    block_spectra(&mut WelchPlanner::new(), &signals, 500.0, &settings(4096)).expect("spectra")
}

#[test]
fn a_short_record_gets_its_stationarity_from_shorter_segments() {
    let spectra = stepped_record(17, 0.01, 7);
    assert!(
        spectra.stretches.len() < MIN_STRETCHES,
        "{}",
        spectra.stretches.len()
    );
    let st = stationarity(&spectra, [1.0, 100.0]).expect("a stationarity from the finer stretches");
    assert_eq!(st.segment_len, Some(2048));
    assert!(st.stretches.len() >= MIN_STRETCHES);
    // The gain's step shows in the stretches' spread: 5 stretches, 2.5 each side of the step,
    // their sd about half the step, over sqrt(5): about 0.2 %; the noise alone (1e-3 of the signal)
    // gives about 1e-5.
    for i in 0..3 {
        let spread = st.k_spread_std[i][i];
        assert!((0.001..0.004).contains(&spread), "K[{i}][{i}] spread {spread}");
        // The whole record's gain is the average: the stretches straddle it.
        let (lo, hi) = st.stretches.iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
            (lo.min(s.k[i][i]), hi.max(s.k[i][i]))
        });
        assert!(lo < 1.002 && hi > 1.008, "{lo} .. {hi}");
    }
    // No step: a spread at the noise's level.
    let steady = stationarity(&stepped_record(17, 0.0, 7), [1.0, 100.0]).expect("stationarity");
    assert!(steady.k_spread_std[0][0] < 1e-4, "{}", steady.k_spread_std[0][0]);
    assert!(steady.tau_spread_std_s < 1e-5, "{}", steady.tau_spread_std_s);
}

#[test]
fn a_record_long_enough_keeps_the_settings_segment() {
    let spectra = stepped_record(30, 0.0, 3);
    assert!(spectra.finer_stretches.is_none());
    let st = stationarity(&spectra, [1.0, 100.0]).expect("stationarity");
    assert_eq!(st.segment_len, None);
    assert_eq!(st.stretches.len(), spectra.stretches.len());
}
