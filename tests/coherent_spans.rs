//! A recording whose outputs, from some time on, are of another motion than its angles (a
//! splice: 30 s of the gyro's samples lost, the rest moved up) has no usable band as a whole; the
//! refusal says over which part of the record the outputs are coherent all the same, a part that
//! holds no spliced sample. A record whose outputs are of another motion throughout is refused
//! without a part. Real recordings (BROAD, CC BY 4.0: `tests/data/real/README.md`).

use std::path::Path;

use imu_attest::ident::IdentError;
use imu_attest::ident::identify::identify_run;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, Run, load};

fn real(name: &str) -> Run {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    load(&path, &LoadOptions::default()).expect("the real run loads")
}

/// The run with its gyro's samples from `from` on replaced by those `skip` samples later, and
/// the record shortened by `skip`.
fn spliced(mut run: Run, from: usize, skip: usize) -> Run {
    let n = run.len() - skip;
    for c in run.gyro.as_mut().expect("a gyro").iter_mut() {
        c.copy_within(from + skip.., from);
        c.truncate(n);
    }
    for c in &mut run.angles {
        c.truncate(n);
    }
    run.time_s.truncate(n);
    run
}

fn refusal(run: &Run) -> (Vec<[f64; 2]>, String) {
    let Err(e) = identify_run(run, &Settings::default()) else {
        panic!("identified");
    };
    let words = e.to_string();
    let IdentError::NoUsableBand { coherent_s, .. } = e else {
        panic!("not refused for want of a band: {words}");
    };
    (coherent_s, words)
}

#[test]
fn a_spliced_recording_is_refused_with_the_part_to_analyse() {
    for name in [
        "broad07_fast_rotation",
        "broad11_slow_translation",
        "broad25_tapping",
    ] {
        let run = real(name);
        let skip = (30.0 * run.sample_rate_hz) as usize;
        let from = run.len() / 3;
        let at = run.time_s[from] - run.time_s[0];
        let (spans, words) = refusal(&spliced(run, from, skip));
        eprintln!("{name}: spliced at {at:.1} s: {spans:?}");
        assert!(!spans.is_empty(), "{name}: no coherent part said: {words}");
        assert!(
            spans.iter().all(|&[a, b]| a >= 0.0 && b <= at && a < b),
            "{name}: {spans:?}, spliced at {at}"
        );
        assert!(words.contains("a splice") && words.contains("span_s"), "{words}");
    }
}

#[test]
fn outputs_of_another_motion_throughout_are_refused_without_a_part() {
    let mut run = real("broad07_fast_rotation");
    let other = real("broad25_tapping");
    let n = run.len().min(other.len());
    let gyro = other.gyro.expect("a gyro").map(|c| c[..n].to_vec());
    run.gyro = Some(gyro);
    for c in &mut run.angles {
        c.truncate(n);
    }
    run.time_s.truncate(n);
    let (spans, words) = refusal(&run);
    assert!(spans.is_empty(), "{spans:?}: {words}");
    assert!(!words.contains("a splice"), "{words}");
}
