//! Robustness of `imu_attest::run`: random damage to a run's CSV (plain or gzip, loaded in blocks
//! of any size) or to its sidecar never panics, and a run accepted despite it holds only finite,
//! equal-length columns.

use crate::common::loader as loader_common;
use imu_attest::rng::Rng;
use imu_attest::run::{LoadError, Run, load};
use loader_common::{ALL, chunked, csv, gzip, opts, write};

/// `bytes` with one random flip, insertion or deletion.
fn mutate(rng: &mut Rng, bytes: &mut Vec<u8>) {
    let at = (rng.next_u64() % (bytes.len() as u64 + 1)) as usize;
    let byte = [
        b',', b'\n', b'\r', b'.', b'e', b'-', b'+', b' ', b'"', b'[', b'{', b'}', b':', 0, 0xFF, b'n',
    ][(rng.next_u64() % 16) as usize];
    match rng.next_u64() % 3 {
        0 if at < bytes.len() => bytes[at] ^= 1 << (rng.next_u64() % 8),
        1 => bytes.insert(
            at,
            if rng.uniform() < 0.5 {
                byte
            } else {
                rng.next_u64() as u8
            },
        ),
        _ if at < bytes.len() => {
            bytes.remove(at);
        }
        _ => bytes.push(byte),
    }
}

/// Loads must return, never panic, and an accepted run must hold only finite, equal-length columns.
fn assert_sane(result: Result<Run, LoadError>) -> bool {
    let Ok(run) = result else { return false };
    let n = run.len();
    let columns = run
        .angles
        .iter()
        .chain(run.gyro.iter().flatten())
        .chain(run.accel.iter().flatten());
    assert!(
        columns
            .chain(std::iter::once(&run.time_s))
            .all(|c| c.len() == n && c.iter().all(|v| v.is_finite()))
    );
    assert!(n >= 16 && run.sample_rate_hz.is_finite() && run.sample_rate_hz > 0.0);
    true
}

#[test]
fn random_damage_to_the_csv_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 24, 3.0, 0.01);
    let mut rng = Rng::new(20_251_121);
    let mut accepted = 0;
    for k in 0..2000 {
        let mut bytes = text.clone().into_bytes();
        for _ in 0..=(rng.next_u64() % 3) {
            mutate(&mut rng, &mut bytes);
        }
        let gz = k % 10 == 0;
        let bytes = if gz && k % 20 == 0 {
            gzip(&bytes)
        } else if gz {
            mutated_gzip(&mut rng, &text)
        } else {
            bytes
        };
        let path = write(dir.path(), "m.csv", &bytes);
        let chunk_bytes = [8 << 20, 64, 7][k % 3];
        accepted += usize::from(assert_sane(load(&path, &chunked(chunk_bytes))));
    }
    // Damage that keeps a valid run (a flipped digit) must still load: the test exercises both paths.
    assert!((20..1900).contains(&accepted), "{accepted} of 2000 accepted");
}

/// A gzip of `text` with a damaged compressed stream.
fn mutated_gzip(rng: &mut Rng, text: &str) -> Vec<u8> {
    let mut gz = gzip(text.as_bytes());
    mutate(rng, &mut gz);
    gz
}

#[test]
fn random_damage_to_the_sidecar_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let run = write(dir.path(), "s.csv", csv(&ALL, 20, 0.0, 0.01).0);
    let json = r#"{"format": "stand-run/1", "regime": "cruise", "g_mps2": 9.80665,
        "accel_lever_arm_m": [0.30, 0.12, 0.0], "gyro_lever_arm_m": [0.0, 0.0, 0.0],
        "angle_noise_rad": 2e-5, "notes": "free text"}"#;
    let mut rng = Rng::new(7);
    let mut outcomes = [0_usize; 3];
    for _ in 0..2000 {
        let mut bytes = json.as_bytes().to_vec();
        for _ in 0..=(rng.next_u64() % 3) {
            mutate(&mut rng, &mut bytes);
        }
        write(dir.path(), "s.json", &bytes);
        match load(&run, &opts()) {
            Ok(run) => {
                assert!(run.sidecar.g_mps2.is_finite() && run.sidecar.g_mps2 > 0.0);
                assert!(run.sidecar.accel_lever_arm_m.iter().all(|v| v.is_finite()));
                outcomes[0] += 1;
            }
            Err(LoadError::Sidecar { line, column, .. }) => {
                assert!(line >= 1 && column <= bytes.len() + 1, "{line}:{column}");
                outcomes[1] += 1;
            }
            Err(LoadError::SidecarValue { .. }) => outcomes[2] += 1,
            Err(other) => panic!("unexpected {other}"),
        }
    }
    assert!(outcomes.iter().all(|&n| n > 0), "{outcomes:?}");
}
