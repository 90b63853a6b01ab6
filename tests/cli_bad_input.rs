//! Every kind of bad run of contract section 2, through the real binary: exit status 2 and one
//! line naming the file (and the line and column where they apply).
#![expect(
    clippy::format_collect,
    reason = "small test fixtures read best as formatted rows"
)]
#![expect(
    clippy::unwrap_used,
    reason = "test helpers panic on the unexpected, like the tests"
)]

use std::io::Write;
use std::path::Path;
use std::process::Command;

const HEADER: &str = "t,roll,yaw,pitch,gx,gy,gz";

fn good_rows(n: usize) -> String {
    (0..n)
        .map(|i| format!("{},0.01,0.02,0.03,0.1,0.2,0.3\n", i as f64 * 0.01))
        .collect()
}

fn inspect(path: &Path) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_imu-attest"))
        .arg("inspect")
        .arg(path)
        .output()
        .unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn good_run_is_summarised() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "ok.csv",
        format!("{HEADER},temp_c\n{}", good_rows(40).replace('\n', ",21.5\n")).as_bytes(),
    );
    let (code, err) = inspect(&p);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("ok.csv: 40 samples, 100.000000 Hz"), "{err}");
    assert!(err.contains("temp_c"), "unknown column noticed: {err}");
    assert!(err.contains("no sidecar"), "{err}");
}

#[test]
fn every_bad_input_exits_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rows = good_rows(40);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(format!("{HEADER}\n{rows}").as_bytes()).unwrap();
    let mut gz = gz.finish().unwrap();
    gz.truncate(gz.len() / 2);
    let irregular: String = (0..40)
        .map(|i| {
            format!(
                "{},0,0,0,0,0,0\n",
                if i == 20 { 0.2015 } else { f64::from(i) * 0.01 }
            )
        })
        .collect();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "missing_column.csv",
            format!("t,roll,yaw,gx,gy,gz\n{rows}").into_bytes(),
            "pitch",
        ),
        (
            "no_block.csv",
            format!("t,roll,yaw,pitch\n{}", "0,0,0,0\n".repeat(20)).into_bytes(),
            "gx",
        ),
        (
            "partial_block.csv",
            format!("t,roll,yaw,pitch,gx,gy\n{}", "0,0,0,0,0,0\n".repeat(20)).into_bytes(),
            "gz",
        ),
        (
            "not_numeric.csv",
            format!("{HEADER}\n{}0.4,0.01,abc,0.03,0.1,0.2,0.3\n", good_rows(40)).into_bytes(),
            ":42:3",
        ),
        (
            "nan.csv",
            format!("{HEADER}\n{}0.4,0.01,0.02,NaN,0.1,0.2,0.3\n", good_rows(40)).into_bytes(),
            ":42:4",
        ),
        (
            "inf.csv",
            format!("{HEADER}\n{}0.4,0.01,0.02,0.03,inf,0.2,0.3\n", good_rows(40)).into_bytes(),
            ":42:5",
        ),
        (
            "not_increasing.csv",
            format!("{HEADER}\n{}0.385,0,0,0,0,0,0\n", good_rows(40)).into_bytes(),
            ":42",
        ),
        (
            "irregular.csv",
            format!("{HEADER}\n{irregular}").into_bytes(),
            ":22",
        ),
        (
            "too_few.csv",
            format!("{HEADER}\n{}", good_rows(5)).into_bytes(),
            "5",
        ),
        (
            "truncated.csv",
            format!("{HEADER}\n{}0.4,0.01,0.02", good_rows(40)).into_bytes(),
            "truncated",
        ),
        (
            "semicolon.csv",
            format!(
                "{}\n{}",
                HEADER.replace(',', ";"),
                good_rows(40).replace(',', ";")
            )
            .into_bytes(),
            "';'",
        ),
        (
            "duplicate.csv",
            format!(
                "t,roll,yaw,pitch,gx,gy,gz,gx\n{}",
                good_rows(40).replace('\n', ",0\n")
            )
            .into_bytes(),
            "gx",
        ),
        (
            "binary.csv",
            vec![0u8, 159, 146, 150, 0, 1, 2, 3, 10, 0, 0],
            "text",
        ),
        ("broken.csv.gz", gz, "gzip"),
    ];
    for (name, bytes, needle) in cases {
        let p = write(d, name, &bytes);
        let (code, err) = inspect(&p);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name), "{name}: the message names the file: {err}");
        assert!(err.contains(needle), "{name}: expected '{needle}' in: {err}");
    }
    // A directory, a missing file, and bad sidecars.
    let (code, err) = inspect(d);
    assert_eq!(code, Some(2), "{err}");
    let (code, err) = inspect(&d.join("absent.csv"));
    assert_eq!(code, Some(2), "{err}");
    for (sidecar, needle) in [
        ("{\"g_mps2\": -9.8}", "g_mps2"),
        ("{\"accel_lever_arm_m\": [0.1, 0.2]}", "lever"),
        ("{\"regime\": 3}", ":1:"),
        ("{\"notes\": ", "side.json"),
    ] {
        write(d, "side.csv", format!("{HEADER}\n{rows}").as_bytes());
        write(d, "side.json", sidecar.as_bytes());
        let (code, err) = inspect(&d.join("side.csv"));
        assert_eq!(code, Some(2), "{sidecar}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{sidecar}: expected '{needle}' in {err}");
    }
}

/// The cases beyond contract section 2's list (issue 7): each exits 2 with one line naming the
/// file, and the line and column where they apply.
#[test]
fn more_bad_inputs_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rows = good_rows(40);
    let long_line = format!("{HEADER}\n{}0.4,{}\n", good_rows(3), "1".repeat(2 << 20));
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "tab.csv",
            format!("{}\n{}", HEADER.replace(',', "\t"), rows.replace(',', "\t")).into_bytes(),
            &[":1:", "'\\t'", "comma-separated"],
        ),
        ("empty.csv", Vec::new(), &["empty file"]),
        ("blank_lines.csv", b"\n\n  \n".to_vec(), &["empty file"]),
        (
            "blank_inside.csv",
            format!("{HEADER}\n{}\n{}", good_rows(20), "0.5,0,0,0,0,0,0\n").into_bytes(),
            &[":22:", "blank line"],
        ),
        (
            "empty_name.csv",
            format!("t,roll,,pitch,gx,gy,gz\n{rows}").into_bytes(),
            &[":1:3", "no name"],
        ),
        (
            "extra_field.csv",
            format!("{HEADER}\n{}0.4,0,0,0,0,0,0,9\n", good_rows(40)).into_bytes(),
            &[":42:", "has 8 fields, header has 7"],
        ),
        (
            "duplicate_t.csv",
            format!("t,roll,yaw,pitch,gx,gy,gz,t\n{}", rows.replace('\n', ",0\n")).into_bytes(),
            &[":1:8 (column 't')", "duplicate column, also column 1"],
        ),
        ("long_line.csv", long_line.into_bytes(), &[":5:", "longer than"]),
        (
            "latin1.csv",
            format!(
                "{HEADER}\n{}0.4,0.01,0.02,0.03,0.1,0.2,0.3 \u{b0}\n",
                good_rows(40)
            )
            .replace('\u{b0}', "\u{1}")
            .into_bytes()
            .into_iter()
            .map(|b| if b == 1 { 0xB0 } else { b })
            .collect(),
            &[":42", "not text"],
        ),
        (
            "huge_exponent.csv",
            format!("{HEADER}\n{}0.4,0.01,1e999,0.03,0.1,0.2,0.3\n", good_rows(40)).into_bytes(),
            &[":42:3 (column 'yaw')", "not a finite number: \"1e999\""],
        ),
        (
            // A quote left open (a pair around the cell is accepted: `run_loader.rs`).
            "quoted.csv",
            format!("{HEADER}\n{}0.4,\"0.01,0.02,0.03,0.1,0.2,0.3\n", good_rows(40)).into_bytes(),
            &[":42:2 (column 'roll')", "not a number"],
        ),
        (
            "decimal_comma.csv",
            format!("{HEADER}\n{}", good_rows(40).replacen("0.01", "0,01", 1)).into_bytes(),
            &[":2:", "has 8 fields, header has 7"],
        ),
        (
            "angle_jump.csv",
            format!("{HEADER}\n{}0.4,0.01,1.52,0.03,0.1,0.2,0.3\n", good_rows(40)).into_bytes(),
            &[":42:3 (column 'yaw')", "angle jumps by 1.500 rad", "not a wrap"],
        ),
        (
            "time_span.csv",
            std::fs::read(
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("tests/data/fuzz_regressions/time_span_overflow.csv"),
            )
            .unwrap(),
            &[":2:1 (column 't')", "no finite sample rate"],
        ),
    ];
    for (name, bytes, needles) in cases {
        let p = write(d, name, &bytes);
        let (code, err) = inspect(&p);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name), "{name}: the message names the file: {err}");
        for needle in needles {
            assert!(err.contains(needle), "{name}: expected '{needle}' in: {err}");
        }
    }
    // A directory given as a run, and a sidecar that is a directory.
    let (code, err) = inspect(d);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("not a file (a directory?)"), "{err}");
    write(d, "sided.csv", format!("{HEADER}\n{rows}").as_bytes());
    std::fs::create_dir(d.join("sided.json")).unwrap();
    let (code, err) = inspect(&d.join("sided.csv"));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("sided.json: not a file"), "{err}");
    // Sidecars of the wrong types or values, each naming the field.
    for (sidecar, needles) in [
        (
            r#"{"g_mps2": "9.81"}"#,
            &["side.json:1:", "g_mps2: invalid type: string"][..],
        ),
        (r#"{"g_mps2": -9.8}"#, &["field 'g_mps2'", "positive", "-9.8"][..]),
        (
            r#"{"gyro_lever_arm_m": [0, 0]}"#,
            &["field 'gyro_lever_arm_m'", "3 numbers", "got 2"][..],
        ),
        (
            r#"{"accel_lever_arm_m": 0.3}"#,
            &["side.json:1:", "accel_lever_arm_m: invalid type"][..],
        ),
        (r#"{"angle_noise_rad": -1}"#, &["field 'angle_noise_rad'"][..]),
        ("\u{feff}[1, 2]", &["side.json:1:1", "must be a JSON object"][..]),
        // An empty array was read as a sidecar of defaults.
        ("\n []", &["side.json:2:2", "must be a JSON object"][..]),
    ] {
        write(d, "side.csv", format!("{HEADER}\n{rows}").as_bytes());
        write(d, "side.json", sidecar.as_bytes());
        let (code, err) = inspect(&d.join("side.csv"));
        assert_eq!(code, Some(2), "{sidecar}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        for needle in needles {
            assert!(err.contains(needle), "{sidecar}: expected '{needle}' in {err}");
        }
    }
}

/// Accepted oddities: a byte-order mark (removed with a notice), CRLF, no final newline.
#[test]
fn a_byte_order_mark_is_accepted_with_a_notice() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("\u{feff}{HEADER}\r\n{}", good_rows(40).replace('\n', "\r\n"));
    let p = write(dir.path(), "bom.csv", text.trim_end().as_bytes());
    let (code, err) = inspect(&p);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("bom.csv: 40 samples"), "{err}");
    assert!(err.contains("byte-order mark"), "{err}");
}

/// A run the loader accepts (16 rows) but a later stage refuses (the observer needs 64 samples;
/// a settings file makes the Welch segment fit) is the user's input: exit 2 and one line, never
/// the internal error's 1.
#[test]
fn a_run_refused_after_loading_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let run = write(
        dir.path(),
        "short.csv",
        format!("{HEADER}\n{}", good_rows(16)).as_bytes(),
    );
    let settings = write(dir.path(), "s.json", br#"{"welch": {"segment_len": 8}}"#);
    for args in [vec![], vec!["--settings", settings.to_str().unwrap()]] {
        let out = dir.path().join("m.json");
        let o = Command::new(env!("CARGO_BIN_EXE_imu-attest"))
            .arg("identify")
            .arg(&run)
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains("short.csv"), "{stderr}");
        assert!(!out.exists());
    }
}

/// Angles wrapped into (-pi, pi] load unwrapped, with a notice naming the column and the first
/// wrap's line.
#[test]
fn wrapped_angles_are_unwrapped_with_a_notice() {
    let dir = tempfile::tempdir().unwrap();
    let rows: String = (0..40)
        .map(|i| {
            let yaw = 3.0 + 0.02 * f64::from(i);
            let wrapped = if yaw > std::f64::consts::PI {
                yaw - std::f64::consts::TAU
            } else {
                yaw
            };
            format!("{},0.01,{wrapped},0.03,0.1,0.2,0.3\n", f64::from(i) * 0.01)
        })
        .collect();
    let p = write(dir.path(), "wrapped.csv", format!("{HEADER}\n{rows}").as_bytes());
    let (code, err) = inspect(&p);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("column 'yaw' wraps around a full turn 1 time (the first at line 10 of wrapped.csv)"),
        "{err}"
    );
}
