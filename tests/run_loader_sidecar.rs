//! Integration tests of `imu_attest::run` on a run's sidecar (`NAME.json` beside `NAME.csv` or
//! `NAME.csv.gz`): its fields read, every one optional, a field the program does not read noticed
//! with the field it most likely meant, and a bad sidecar refused with its line and column or its
//! field.
#![expect(
    clippy::float_cmp,
    reason = "a parser must reproduce the written values to the bit"
)]

use crate::common::loader as loader_common;
use imu_attest::run::{LoadError, load, sidecar_path};
use loader_common::{ALL, csv, gzip, opts, write};

#[test]
fn sidecar_is_read_and_unknown_fields_are_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 30, 0.0, 0.01);
    let path = write(dir.path(), "turb.csv.gz", gzip(text.as_bytes()));
    assert_eq!(sidecar_path(&path), dir.path().join("turb.json"));
    assert_eq!(
        sidecar_path(&dir.path().join("turb.csv")),
        dir.path().join("turb.json")
    );
    write(
        dir.path(),
        "turb.json",
        r#"{"format": "stand-run/1", "regime": "cruise-turbulent", "g_mps2": 9.81,
            "accel_lever_arm_m": [0.30, 0.12, 0.0], "gyro_lever_arm_m": [0, 0, -0.05],
            "angle_noise_rad": 2e-5, "notes": "free text", "operator": "kim",
            "truth": {"gyro": {"delay_s": 0.004}}}"#,
    );
    let run = load(&path, &opts()).unwrap();
    let s = &run.sidecar;
    assert!(s.found);
    assert_eq!(s.format.as_deref(), Some("stand-run/1"));
    assert_eq!(s.regime, "cruise-turbulent");
    assert_eq!(s.g_mps2, 9.81);
    assert_eq!(s.accel_lever_arm_m, [0.30, 0.12, 0.0]);
    assert_eq!(s.gyro_lever_arm_m, [0.0, 0.0, -0.05]);
    assert_eq!(s.angle_noise_rad, Some(2e-5));
    assert_eq!(s.notes.as_deref(), Some("free text"));
    // Unknown fields are ignored, each with a notice naming it; `truth` without one.
    assert_eq!(
        run.notices,
        ["sidecar field 'operator' is not one the program reads, ignored"],
        "{:?}",
        run.notices
    );
    // Every field optional.
    write(dir.path(), "turb.json", "{}");
    let run = load(&path, &opts()).unwrap();
    assert!(run.sidecar.found);
    assert_eq!(run.sidecar.regime, "turb");
    assert_eq!(run.sidecar.g_mps2, 9.80665);
}

/// A sidecar field the program does not read is noticed by name, with the field it most likely
/// meant: a misspelt lever arm (its value then zero) is not silent. `truth` (a simulated run's)
/// and the fields read are not noticed, and the known fields are read as before.
#[test]
fn unknown_sidecar_fields_are_noticed_with_the_field_meant() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 40, 0.0, 0.01);
    let path = write(dir.path(), "s.csv", text);
    write(
        dir.path(),
        "s.json",
        r#"{"regime": "r", "accel_lever_arm": [0.3, 0.1, 0.0], "G_mps2": 9.81,
            "angle_noise": 1e-5, "operator": "A. N. Other", "truth": {"x": 1},
            "gyro_lever_arm_m": [0.0, 0.0, 0.1]}"#,
    );
    let run = load(&path, &opts()).unwrap();
    let said: Vec<&String> = run
        .notices
        .iter()
        .filter(|n| n.starts_with("sidecar field"))
        .collect();
    let expected = [
        "sidecar field 'G_mps2' is not one the program reads, ignored: did you mean 'g_mps2'?",
        "sidecar field 'accel_lever_arm' is not one the program reads, ignored: did you mean \
         'accel_lever_arm_m'?",
        "sidecar field 'angle_noise' is not one the program reads, ignored: did you mean \
         'angle_noise_rad'?",
        "sidecar field 'operator' is not one the program reads, ignored",
    ];
    assert_eq!(said, expected.iter().collect::<Vec<_>>(), "{:?}", run.notices);
    assert_eq!(
        run.sidecar.accel_lever_arm_m, [0.0; 3],
        "the misspelt field is not read"
    );
    assert_eq!(run.sidecar.gyro_lever_arm_m, [0.0, 0.0, 0.1]);
    assert_eq!(run.sidecar.regime, "r");
}

#[test]
fn bad_sidecars() {
    let dir = tempfile::tempdir().unwrap();
    let run = write(dir.path(), "c.csv", csv(&ALL[..7], 20, 0.0, 0.01).0);
    let syntax = "{\n  \"regime\": \"cruise\",\n  \"g_mps2\": 9.8,,\n}";
    write(dir.path(), "c.json", syntax);
    let err = load(&run, &opts()).unwrap_err();
    assert!(
        matches!(
            err,
            LoadError::Sidecar {
                line: 3,
                column: 17,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string().ends_with("c.json:3:17: key must be a string"),
        "{err}"
    );
    write(dir.path(), "c.json", "{\"g_mps2\": \"9.81\"}");
    assert!(matches!(
        load(&run, &opts()).unwrap_err(),
        LoadError::Sidecar { line: 1, .. }
    ));
    let values = [
        (r#"{"g_mps2": -9.8}"#, "g_mps2"),
        (r#"{"g_mps2": 0}"#, "g_mps2"),
        (r#"{"accel_lever_arm_m": [0.1, 0.2]}"#, "accel_lever_arm_m"),
        (
            r#"{"gyro_lever_arm_m": [0.1, 0.2, 0.3, 0.4]}"#,
            "gyro_lever_arm_m",
        ),
        (r#"{"angle_noise_rad": -1e-5}"#, "angle_noise_rad"),
        (r#"{"regime": " "}"#, "regime"),
    ];
    for (json, bad) in values {
        write(dir.path(), "c.json", json);
        let err = load(&run, &opts()).unwrap_err();
        assert!(
            matches!(err, LoadError::SidecarValue { field, .. } if field == bad),
            "{json}: {err}"
        );
        assert!(err.to_string().contains("c.json: field"), "{err}");
    }
}
