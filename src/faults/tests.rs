use super::glitch::{Glitch, find_glitches};
use super::hold::{HELD_RUN, find_clipping, find_held};
use super::*;
use crate::rng::Rng;

/// A smooth motion plus white noise of 1e-3, seeded.
fn signal(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|i| {
            let t = i as f64 / 500.0;
            0.3 * (2.0 * t).sin() + 0.1 * (7.3 * t + 1.0).sin() + 1e-3 * rng.normal()
        })
        .collect()
}

#[test]
fn clean_signals_have_no_fault() {
    for seed in 0..5 {
        let x = signal(seed, 20_000);
        assert_eq!(find_glitches(&x), Vec::new(), "seed {seed}");
        assert_eq!(find_held(&x, &[]), None);
        assert!(find_clipping(&x).is_empty());
    }
}

#[test]
fn glitches_of_one_to_three_samples_are_found_where_they_are() {
    for k in 1..=3 {
        for (start, size) in [(5000, 0.05), (12_345, -0.5), (3, 0.2)] {
            let mut x = signal(k as u64, 20_000);
            x[start..start + k].iter_mut().for_each(|v| *v += size);
            let found = find_glitches(&x);
            if start < 2 {
                continue;
            }
            assert_eq!(found.len(), 1, "k {k} at {start}: {found:?}");
            let Glitch {
                start: s,
                samples,
                size: got,
            } = found[0];
            assert_eq!((s, samples), (start, k), "{found:?}");
            assert!((got - size).abs() < 0.01 * size.abs() + 5e-3, "{got} vs {size}");
        }
    }
}

#[test]
fn steps_ringing_bursts_and_small_outliers_are_not_glitches() {
    let mut step = signal(7, 20_000);
    step[8000..].iter_mut().for_each(|v| *v += 0.05);
    assert_eq!(find_glitches(&step), Vec::new());
    // A tap: a spike followed by a decaying ringing over 20 samples.
    let mut tap = signal(8, 20_000);
    for j in 0..20 {
        tap[9000 + j] += 0.4 * (-(j as f64) / 6.0).exp() * (1.9 * j as f64).cos();
    }
    assert_eq!(find_glitches(&tap), Vec::new());
    // 8 noise deviations: within what the threshold tolerates.
    let mut small = signal(9, 20_000);
    small[4000] += 8e-3;
    assert_eq!(find_glitches(&small), Vec::new());
}

#[test]
fn quantised_slow_channels_repeat_by_chance_but_held_samples_are_found() {
    // A slow angle quantised at 1e-4 with noise of 6 quanta: repeats by chance, nothing held.
    let q = 1e-4;
    let mut rng = Rng::new(3);
    let slow: Vec<f64> = (0..30_000)
        .map(|i| ((0.02 * (f64::from(i) / 500.0).sin() + 6e-4 * rng.normal()) / q).round() * q)
        .collect();
    assert!(
        slow.windows(2)
            .filter(|w| w[0].to_bits() == w[1].to_bits())
            .count()
            > 500
    );
    assert_eq!(find_held(&slow, &[]), None);
    // Every 100th sample held: 1 %.
    let mut held = signal(4, 30_000);
    for i in (50..held.len()).step_by(100) {
        held[i] = held[i - 1];
    }
    let h = find_held(&held, &[]).expect("held samples found");
    assert_eq!((h.held, h.runs, h.longest, h.first), (300, 300, 1, 50));
    // One run of 5 repeats on its own.
    let mut run = signal(5, 30_000);
    for i in 7001..7006 {
        run[i] = run[7000];
    }
    let h = find_held(&run, &[]).expect("a run of 5");
    assert_eq!((h.longest, h.first), (5, 7001));
}

#[test]
fn flat_tops_at_an_extreme_are_clipping() {
    let x = signal(6, 20_000);
    let level = 0.37;
    let clipped: Vec<f64> = x.iter().map(|v| v.min(level)).collect();
    let first = x
        .iter()
        .position(|v| *v >= level)
        .expect("the signal exceeds the level");
    let clips = find_clipping(&clipped);
    assert_eq!(clips.len(), 1, "{clips:?}");
    assert!(clips[0].at_max && clips[0].flat_tops >= 2 && clips[0].first == first);
    // A channel toggling between three levels sits at its extremes legitimately.
    let toggling: Vec<f64> = (0..5000).map(|i| f64::from((i / 7 % 3) as u8) * 1e-3).collect();
    assert!(find_clipping(&toggling).is_empty());
}

#[test]
fn faults_serialise_with_a_kind_and_read_as_a_sentence() {
    let fault = RecordingFault::Glitch {
        channel: Channel::Gx,
        time_s: 12.5,
        sample: 6250,
        samples: 1,
        size: 50.0,
    };
    let json = serde_json::to_value(&fault).expect("serialisable");
    assert_eq!(json["kind"], "glitch");
    assert_eq!(json["channel"], "gx");
    assert_eq!(
        fault.to_string(),
        "glitch in gx at t = 12.5000 s (line 6252, 1 sample): +5.0000e1 rad/s off its neighbours"
    );
}

/// A channel that holds samples or clips spoils a witness, as `detect` reports it (a dead start
/// long enough to be reported too); a clean one, a quantised slow one repeating by chance and one
/// with a glitch do not. A gyro channel's words say what it costs the other block; an
/// accelerometer's do not.
#[test]
fn held_or_clipped_channels_are_no_witness_and_a_gyros_words_say_so() {
    let holds_or_clips = |x: &[f64]| {
        let time: Vec<f64> = (0..x.len()).map(|i| i as f64 / 500.0).collect();
        detect_channel(Channel::Gx, &time, x)
            .iter()
            .any(RecordingFault::spoils_recording)
    };
    let clean = signal(7, 20_000);
    assert!(!holds_or_clips(&clean));
    let q = 1e-4;
    let mut rng = Rng::new(3);
    let slow: Vec<f64> = (0..30_000)
        .map(|i| ((0.02 * (f64::from(i) / 500.0).sin() + 6e-4 * rng.normal()) / q).round() * q)
        .collect();
    assert!(!holds_or_clips(&slow));
    let mut dead_ends = clean.clone();
    let n = dead_ends.len();
    for i in 1..700 {
        dead_ends[i] = dead_ends[0];
        dead_ends[n - 1 - i] = dead_ends[n - 1];
    }
    assert!(
        find_held(&dead_ends, &[]).is_some(),
        "the dead start is held samples to `detect`"
    );
    assert!(holds_or_clips(&dead_ends));
    let mut glitched = clean.clone();
    glitched[9000] += 0.5;
    assert!(!holds_or_clips(&glitched));
    let mut held = clean.clone();
    for i in (50..held.len()).step_by(100) {
        held[i] = held[i - 1];
    }
    assert!(holds_or_clips(&held));
    let clipped: Vec<f64> = clean.iter().map(|v| v.min(0.37)).collect();
    assert!(holds_or_clips(&clipped));
    let words = |channel| {
        RecordingFault::HeldSamples {
            channel,
            held: 300,
            expected: 0.0,
            runs: 300,
            longest: 1,
            first_time_s: 0.1,
        }
        .to_string()
    };
    assert!(words(Channel::Gy).ends_with(
        "results using gy are unreliable; the gyro is then no witness of the angles' noise, taken white for every block"
    ));
    assert!(words(Channel::Ay).ends_with("results using ay are unreliable"));
}

/// A quantised angle turning every two seconds (0.25 Hz, 0.1 rad, quantum 2e-5, noise 3e-6 rad,
/// 400 Hz, as a slow stand's encoder) stays within one quantum for several samples at each turn and
/// then steps by one: runs of 5 and more repeats by chance, not held samples. A logger holding
/// the same channel for 6 samples where it moves is still found.
#[test]
fn runs_of_repeats_at_the_motion_s_turns_are_chance() {
    let q = 2e-5;
    let mut rng = Rng::new(21);
    let turning: Vec<f64> = (0..48_000)
        .map(|i| {
            let t = f64::from(i) / 400.0;
            ((0.1 * (0.5 * std::f64::consts::PI * t).sin() + 3e-6 * rng.normal()) / q).round() * q
        })
        .collect();
    let mut run = 0;
    let mut longest = 0;
    for w in turning.windows(2) {
        run = if w[0].to_bits() == w[1].to_bits() {
            run + 1
        } else {
            0
        };
        longest = longest.max(run);
    }
    assert!(longest >= HELD_RUN, "the case: runs of {longest}");
    assert_eq!(find_held(&turning, &[]), None);
    // Held where the channel moves (a quarter period from a turn): the release steps by the run.
    let mut held = turning.clone();
    for i in 10_101..10_107 {
        held[i] = held[10_100];
    }
    let h = find_held(&held, &[]).expect("a held run where the channel moves");
    assert!(h.longest >= 6, "{h:?}");
}
