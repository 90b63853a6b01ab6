//! Integration tests of `imu_attest::run`: good files load to the exact values written, bad files
//! give the right `LoadError` variant with the right line and column, and nothing panics.
#![expect(
    clippy::unwrap_used,
    reason = "test helpers: a failed setup step should panic"
)]
#![expect(
    clippy::float_cmp,
    reason = "a parser must reproduce the written values to the bit"
)]

use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use imu_attest::rng::Rng;
use imu_attest::run::{
    Block, LoadError, LoadOptions, LoadProgress, Run, load, load_with_progress, sidecar_path,
};
use sha2::{Digest as _, Sha256};

const ALL: [&str; 10] = ["t", "roll", "yaw", "pitch", "gx", "gy", "gz", "ax", "ay", "az"];

/// A CSV text with `columns`, `n` rows, `t = t0 + i dt`, plus the values its cells parse to.
fn csv(columns: &[&str], n: usize, t0: f64, dt: f64) -> (String, Vec<Vec<f64>>) {
    let mut text = columns.join(",") + "\n";
    let mut values = vec![Vec::with_capacity(n); columns.len()];
    for i in 0..n {
        let cells: Vec<String> = columns
            .iter()
            .enumerate()
            .map(|(c, name)| match *name {
                "t" => format!("{:.6}", t0 + i as f64 * dt),
                _ => format!("{:.6e}", ((i * 7 + c * 13) % 97) as f64 * 1e-3 - 0.05),
            })
            .collect();
        for (col, cell) in values.iter_mut().zip(&cells) {
            col.push(cell.parse().unwrap());
        }
        text += &cells.join(",");
        text.push('\n');
    }
    (text, values)
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

fn opts() -> LoadOptions {
    LoadOptions::default()
}

/// The default options with blocks of `chunk_bytes`, to cross block boundaries in small files.
fn chunked(chunk_bytes: usize) -> LoadOptions {
    LoadOptions {
        chunk_bytes,
        ..opts()
    }
}

fn load_err(path: &Path, options: &LoadOptions) -> LoadError {
    let err = load(path, options).expect_err("the file should be refused");
    let message = err.to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(
        message.contains(&*name),
        "message does not name the file: {message}"
    );
    assert!(!message.contains('\n'), "message is not one line: {message}");
    err
}

/// The column of `run` that holds header `name`.
fn column<'a>(run: &'a Run, name: &str) -> &'a [f64] {
    let triad = |v: &'a Option<[Vec<f64>; 3]>, k: usize| v.as_ref().map(|t| t[k].as_slice()).unwrap();
    match name {
        "t" => &run.time_s,
        "roll" => &run.angles[0],
        "yaw" => &run.angles[1],
        "pitch" => &run.angles[2],
        "gx" => triad(&run.gyro, 0),
        "gy" => triad(&run.gyro, 1),
        "gz" => triad(&run.gyro, 2),
        "ax" => triad(&run.accel, 0),
        "ay" => triad(&run.accel, 1),
        "az" => triad(&run.accel, 2),
        other => &run.extra.iter().find(|e| e.name == other).unwrap().values,
    }
}

fn assert_columns(run: &Run, columns: &[&str], values: &[Vec<f64>]) {
    for (name, expected) in columns.iter().zip(values) {
        let got = column(run, name);
        assert_eq!(got.len(), expected.len(), "column {name}");
        assert!(
            got.iter().zip(expected).all(|(a, b)| a.to_bits() == b.to_bits()),
            "column {name} differs"
        );
    }
}

#[test]
fn plain_file_loads_exact_values_and_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let (text, values) = csv(&ALL, 500, 0.0, 0.002);
    let path = write(dir.path(), "cruise.csv", &text);
    let run = load(&path, &opts()).unwrap();
    assert_columns(&run, &ALL, &values);
    assert_eq!(run.len(), 500);
    assert!(!run.is_empty());
    assert!(
        (run.sample_rate_hz - 500.0).abs() < 1e-6,
        "{}",
        run.sample_rate_hz
    );
    assert!((run.dt_s() - 0.002).abs() < 1e-12);
    assert!((run.duration_s() - 0.998).abs() < 1e-9);
    assert_eq!(run.blocks(), vec![Block::Gyro, Block::Accel]);
    assert_eq!(run.source.file_name, "cruise.csv");
    assert_eq!(run.source.size_bytes, text.len() as u64);
    assert_eq!(
        run.source.sha256,
        format!("{:x}", Sha256::digest(text.as_bytes()))
    );
    assert!(run.extra.is_empty());
    assert_eq!(run.sidecar.regime, "cruise");
    assert!(!run.sidecar.found);
    assert_eq!(run.sidecar.g_mps2, 9.80665);
    assert_eq!(run.sidecar.accel_lever_arm_m, [0.0; 3]);
    assert!(
        run.notices
            .iter()
            .any(|n| n.contains("no sidecar cruise.json") && n.contains("'cruise'")),
        "{:?}",
        run.notices
    );
}

/// A run's `Debug` (what a failed assertion or a log line prints) summarises it: the sample count
/// and time span, not the 100 000 samples of each column.
#[test]
fn debug_summarises_the_columns() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(
        &["t", "roll", "yaw", "pitch", "gx", "gy", "gz", "temp"],
        100_000,
        5.0,
        0.002,
    );
    let run = load(&write(dir.path(), "long.csv", &text), &opts()).unwrap();
    let shown = format!("{run:?}");
    assert!(shown.len() < 2_000, "{} characters", shown.len());
    for part in [
        "samples: 100000",
        "Some(5.0)",
        "gyro: true",
        "accel: false",
        "\"temp\"",
    ] {
        assert!(shown.contains(part), "{part} not in {shown}");
    }
}

#[test]
fn sha256_matches_sha256sum_of_a_fixed_file() {
    let dir = tempfile::tempdir().unwrap();
    let text: String = std::iter::once("t,roll,yaw,pitch,gx,gy,gz\n".to_owned())
        .chain((0..16).map(|i| format!("{i}.5,1,2,3,4,5,6\n")))
        .collect();
    let run = load(&write(dir.path(), "fixed.csv", text), &opts()).unwrap();
    // `sha256sum fixed.csv` of these exact bytes.
    assert_eq!(
        run.source.sha256,
        "8871e0bbc4baeb935efbc43e913a6adeac4e57cf9d19ddb961f105edb005ba87"
    );
    assert_eq!(run.time_s[0], 0.5);
}

#[test]
fn gzip_loads_like_plain_and_is_detected_by_magic_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (text, values) = csv(&ALL, 3000, 5.0, 0.01);
    let gz = gzip(text.as_bytes());
    for name in ["approach.csv.gz", "approach_misnamed.csv"] {
        let path = write(dir.path(), name, &gz);
        for chunk_bytes in [8 << 20, 1000] {
            let run = load(&path, &chunked(chunk_bytes)).unwrap();
            assert_columns(&run, &ALL, &values);
            assert_eq!(
                run.source.sha256,
                format!("{:x}", Sha256::digest(&gz)),
                "hash of the stored bytes"
            );
            assert_eq!(run.source.size_bytes, gz.len() as u64);
        }
    }
    let run = load(&dir.path().join("approach.csv.gz"), &opts()).unwrap();
    assert_eq!(run.sidecar.regime, "approach");
}

#[test]
fn any_chunk_size_gives_the_same_run() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 400, 0.0, 0.001);
    let path = write(dir.path(), "r.csv", format!("{}\n\n", text.replace('\n', "\r\n")));
    let reference = load(&path, &opts()).unwrap();
    for chunk_bytes in [1, 7, 64, 129, 1000, 4096] {
        assert_eq!(
            load(&path, &chunked(chunk_bytes)).unwrap(),
            reference,
            "chunk {chunk_bytes}"
        );
    }
}

/// Cells in the forms a recorder may write, some of which the fast path leaves to `str::parse`
/// (17 significant digits, long exponents, padding, `E`, a leading `+` or `.`).
fn varied_cell(rng: &mut Rng, row: usize) -> String {
    let x = rng.normal() * 10f64.powi((rng.uniform() * 12.0) as i32 - 8);
    match rng.next_u64() % 9 {
        0 => format!("{x}"),
        1 => format!("{x:e}"),
        2 => format!("{x:.6e}"),
        3 => format!("{x:.17}"),
        4 => {
            let fixed = format!("{:.9}", x.abs());
            fixed
                .strip_prefix('0')
                .map_or(fixed.clone(), |rest| format!("+{rest}"))
        }
        5 => format!("{x:.3E}"),
        6 => format!(" {x:.12} "),
        7 => format!("{:.5}e-0003", x * 1e3),
        _ => format!("{}", (row % 1000) as f64 * 1e-3),
    }
}

/// A naive reference: every line split at commas, every cell trimmed and read by `str::parse`.
fn reference_columns(text: &str, width: usize) -> Vec<Vec<f64>> {
    let mut columns = vec![Vec::new(); width];
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        for (column, cell) in columns.iter_mut().zip(line.split(',')) {
            column.push(cell.trim().parse().unwrap());
        }
    }
    columns
}

#[test]
fn varied_number_forms_load_as_str_parse_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(23);
    let mut text = ALL.join(",") + "\n";
    for row in 0..3000 {
        let t = 100.0 + row as f64 * 0.004;
        let mut cells = vec![format!("{t:.4}")];
        cells.extend((1..ALL.len()).map(|_| varied_cell(&mut rng, row)));
        text += &cells.join(",");
        text += if row % 5 == 0 { "\r\n" } else { "\n" };
    }
    let expected = reference_columns(&text, ALL.len());
    assert_eq!(expected[0].len(), 3000);
    let path = write(dir.path(), "varied.csv", &text);
    // Angles of random sizes jump: kept as read, not unwrapped or refused.
    let as_read = |chunk_bytes| LoadOptions {
        max_angle_step_rad: None,
        ..chunked(chunk_bytes)
    };
    for chunk_bytes in [8 << 20, 4096, 333, 61] {
        let run = load(&path, &as_read(chunk_bytes)).unwrap();
        assert_columns(&run, &ALL, &expected);
    }
    let gz = write(dir.path(), "varied.csv.gz", gzip(text.as_bytes()));
    assert_columns(&load(&gz, &as_read(777)).unwrap(), &ALL, &expected);
    assert!(matches!(
        load(&path, &chunked(4096)),
        Err(LoadError::AngleJump { line, .. }) if line > 2
    ));
}

#[test]
fn permuted_columns_load_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let columns = ["az", "gy", "t", "pitch", "ax", "roll", "gz", "ay", "yaw", "gx"];
    let (text, values) = csv(&columns, 100, 0.0, 0.01);
    let run = load(&write(dir.path(), "p.csv", text), &opts()).unwrap();
    assert_columns(&run, &columns, &values);
}

#[test]
fn exponents_plus_signs_spaces_and_late_start_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = "t , roll,yaw ,pitch,gx,gy,gz\n".to_owned();
    for i in 0..20 {
        let t = 1234.5 + f64::from(i) * 0.25;
        writeln!(text, "{t}, -8.5e-05 ,+1.5E+2,\t-2.5e-3,1e0,+0,.5").unwrap();
    }
    let run = load(&write(dir.path(), "e.csv", text), &opts()).unwrap();
    assert_eq!(run.time_s[0], 1234.5);
    assert!((run.sample_rate_hz - 4.0).abs() < 1e-9);
    assert_eq!(run.angles[0][3], -8.5e-05);
    assert_eq!(run.angles[1][3], 150.0);
    assert_eq!(run.angles[2][3], -2.5e-3);
    assert_eq!(run.gyro.as_ref().unwrap()[2][19], 0.5);
}

#[test]
fn quoted_names_and_cells_load_as_plain_ones() {
    let dir = tempfile::tempdir().unwrap();
    let (text, values) = csv(&ALL, 60, 0.0, 0.01);
    let quote = |line: &str| {
        line.split(',')
            .map(|c| format!("\"{c}\""))
            .collect::<Vec<_>>()
            .join(",")
    };
    let (header, rows) = text.split_once('\n').unwrap();
    let names_only = format!("{}\n{rows}", quote(header));
    let everything: String = text.lines().map(|l| quote(l) + "\n").collect();
    for (k, variant) in [names_only, everything].iter().enumerate() {
        let run = load(&write(dir.path(), &format!("q{k}.csv"), variant), &opts()).unwrap();
        assert_columns(&run, &ALL, &values);
    }
    // A quote left open is not a number: the cell is named as written.
    let open = text.replacen("\n0", "\n\"0", 1);
    let err = load_err(&write(dir.path(), "open.csv", open), &opts());
    assert!(
        matches!(
            err,
            LoadError::NotNumeric {
                line: 2,
                column: 1,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn a_name_in_another_case_is_named_in_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "c.csv",
        csv(&["t", "Roll", "yaw", "pitch", "gx", "gy", "gz"], 20, 0.0, 0.01).0,
    );
    let err = load_err(&path, &opts());
    assert!(
        matches!(&err, LoadError::MissingColumn { column: "roll", near_miss: Some((2, name)), .. } if name == "Roll"),
        "{err}"
    );
    assert!(err.to_string().contains("column 2 is named 'Roll'"), "{err}");
    // Without a near miss the message is as before.
    let path = write(
        dir.path(),
        "d.csv",
        csv(&["t", "yaw", "pitch", "gx", "gy", "gz"], 20, 0.0, 0.01).0,
    );
    assert!(!load_err(&path, &opts()).to_string().contains("named"));
}

#[test]
fn bom_crlf_missing_final_newline_and_blank_trailing_lines_are_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let (text, values) = csv(&ALL[..7], 50, 0.0, 0.01);
    let crlf = text.replace('\n', "\r\n");
    let variants = [
        format!("\u{feff}{text}"),
        crlf.clone(),
        crlf.trim_end().to_owned(),
        text.trim_end().to_owned(),
        format!("{text}\n\n  \n"),
        format!("{crlf}\r\n\r\n"),
    ];
    for (k, variant) in variants.iter().enumerate() {
        let run = load(&write(dir.path(), &format!("v{k}.csv"), variant), &opts()).unwrap();
        assert_columns(&run, &ALL[..7], &values);
        assert_eq!(
            run.notices.iter().any(|n| n.contains("byte-order mark")),
            k == 0,
            "variant {k}"
        );
    }
}

#[test]
fn unknown_columns_are_kept_with_a_notice() {
    let dir = tempfile::tempdir().unwrap();
    let columns = ["t", "temp_c", "roll", "yaw", "pitch", "ax", "ay", "az", "Roll"];
    let (text, values) = csv(&columns, 40, 0.0, 0.01);
    let run = load(&write(dir.path(), "u.csv", text), &opts()).unwrap();
    assert_eq!(
        run.extra.iter().map(|e| e.name.as_str()).collect::<Vec<_>>(),
        ["temp_c", "Roll"]
    );
    assert_columns(&run, &columns, &values);
    assert!(
        run.notices
            .iter()
            .any(|n| n == "unknown column 'temp_c' kept and ignored"),
        "{:?}",
        run.notices
    );
    assert!(
        run.notices
            .iter()
            .any(|n| n == "unknown column 'Roll' kept and ignored")
    );
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

/// A time column in milliseconds (a rate of 1 Hz for a 1 kHz recording) is noticed with the
/// question of its units; a 100 Hz run's is not.
#[test]
fn a_slow_sample_rate_asks_whether_t_is_in_seconds() {
    let dir = tempfile::tempdir().unwrap();
    for (dt, said) in [(1.0, true), (0.01, false)] {
        let (text, _) = csv(&ALL, 40, 0.0, dt);
        let run = load(&write(dir.path(), "ms.csv", text), &opts()).unwrap();
        let asked = run
            .notices
            .iter()
            .any(|n| n.contains("is column 't' in seconds?"));
        assert_eq!(asked, said, "dt {dt}: {:?}", run.notices);
    }
}

#[test]
fn single_block_runs_load() {
    let dir = tempfile::tempdir().unwrap();
    let (gyro, _) = csv(&ALL[..7], 30, 0.0, 0.01);
    let run = load(&write(dir.path(), "g.csv", gyro), &opts()).unwrap();
    assert_eq!(run.blocks(), vec![Block::Gyro]);
    assert!(run.accel.is_none() && run.outputs(Block::Gyro).is_some() && run.outputs(Block::Accel).is_none());
    let columns = ["t", "roll", "yaw", "pitch", "ax", "ay", "az"];
    let (accel, _) = csv(&columns, 30, 0.0, 0.01);
    let run = load(&write(dir.path(), "a.csv", accel), &opts()).unwrap();
    assert_eq!(run.blocks(), vec![Block::Accel]);
    assert!(run.gyro.is_none());
    assert_eq!(serde_json::to_string(&run.blocks()).unwrap(), r#"["accel"]"#);
}

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

#[test]
fn progress_is_reported_and_cancel_stops() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 2000, 0.0, 0.01);
    let path = write(dir.path(), "p.csv", &text);
    let options = LoadOptions {
        chunk_bytes: 4096,
        ..opts()
    };
    let mut seen: Vec<LoadProgress> = Vec::new();
    load_with_progress(&path, &options, &mut |p| {
        seen.push(p);
        ControlFlow::Continue(())
    })
    .unwrap();
    assert!(seen.len() > 10, "{} calls", seen.len());
    assert!(seen.windows(2).all(|w| w[0].bytes_done <= w[1].bytes_done));
    assert!(seen.iter().all(|p| p.bytes_total == text.len() as u64));
    assert_eq!(seen.last().unwrap().bytes_done, text.len() as u64);
    let mut calls = 0;
    let err = load_with_progress(&path, &options, &mut |_| {
        calls += 1;
        if calls == 3 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .unwrap_err();
    assert!(matches!(err, LoadError::Cancelled), "{err}");
    assert_eq!(calls, 3);
}

// ---------------------------------------------------------------------------------------------
// Bad files: one test per error variant, with its line and column.

/// A valid 7-column gyro run of 40 rows (header line 1, row `i` at line `i + 2`) as lines.
fn gyro_lines() -> Vec<String> {
    csv(&ALL[..7], 40, 0.0, 0.01)
        .0
        .lines()
        .map(str::to_owned)
        .collect()
}

fn write_lines(dir: &Path, name: &str, lines: &[String]) -> PathBuf {
    write(dir, name, lines.join("\n") + "\n")
}

/// The error of loading `lines` written as `name` with the default options.
fn lines_err(dir: &Path, name: &str, lines: &[String]) -> LoadError {
    load_err(&write_lines(dir, name, lines), &opts())
}

/// [`gyro_lines`] with cell `column` (0-based) of file line `line` (1-based) replaced by `value`.
fn with_cell(line: usize, column: usize, value: &str) -> Vec<String> {
    let mut lines = gyro_lines();
    let mut cells: Vec<String> = lines[line - 1].split(',').map(str::to_owned).collect();
    value.clone_into(&mut cells[column]);
    lines[line - 1] = cells.join(",");
    lines
}

#[test]
fn io_and_not_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.csv");
    assert!(matches!(load_err(&missing, &opts()), LoadError::Io { path, .. } if path == missing));
    let folder = dir.path().join("folder.csv");
    std::fs::create_dir(&folder).unwrap();
    assert!(matches!(load_err(&folder, &opts()), LoadError::NotAFile { .. }));
    // A sidecar that is a directory is refused too, naming the sidecar.
    let (text, _) = csv(&ALL[..7], 20, 0.0, 0.01);
    let run = write(dir.path(), "s.csv", text);
    std::fs::create_dir(dir.path().join("s.json")).unwrap();
    let err = load(&run, &opts()).unwrap_err();
    assert!(
        matches!(&err, LoadError::NotAFile { path } if path.ends_with("s.json")),
        "{err}"
    );
}

#[test]
fn binary_content_is_not_text() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = gyro_lines().join("\n").into_bytes();
    let line5 = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(3)
        .unwrap()
        .0
        + 3;
    bytes[line5] = 0;
    let path = write(dir.path(), "nul.csv", &bytes);
    assert!(matches!(
        load_err(&path, &opts()),
        LoadError::NotText { line: 5, .. }
    ));
    let mut lines = gyro_lines();
    lines[6].push('\u{e9}');
    let mut bytes = lines.join("\n").into_bytes();
    let e9 = bytes.iter().position(|&b| b == 0xC3).unwrap();
    bytes.remove(e9); // a lone continuation byte: invalid UTF-8 on line 7
    let path = write(dir.path(), "utf8.csv", &bytes);
    assert!(matches!(
        load_err(&path, &opts()),
        LoadError::NotText { line: 7, .. }
    ));
    let path = write(dir.path(), "head.csv", b"t,ro\xffll\n1,2\n");
    assert!(matches!(
        load_err(&path, &opts()),
        LoadError::NotText { line: 1, .. }
    ));
}

#[test]
fn broken_gzip_is_bad_gzip() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = write(
        dir.path(),
        "garbage.csv.gz",
        b"\x1f\x8bthis is not deflate at all",
    );
    assert!(matches!(load_err(&garbage, &opts()), LoadError::BadGzip { .. }));
    let gz = gzip((gyro_lines().join("\n") + "\n").as_bytes());
    let truncated = write(dir.path(), "truncated.csv.gz", &gz[..gz.len() - 12]);
    let err = load_err(&truncated, &opts());
    assert!(matches!(err, LoadError::BadGzip { .. }), "{err}");
    assert!(err.to_string().contains("unreadable gzip"));
}

#[test]
fn empty_files() {
    let dir = tempfile::tempdir().unwrap();
    for (k, content) in ["", "\n\n", "\u{feff}", "  \r\n"].iter().enumerate() {
        let path = write(dir.path(), &format!("empty{k}.csv"), content);
        assert!(
            matches!(load_err(&path, &opts()), LoadError::Empty { .. }),
            "{content:?}"
        );
    }
}

#[test]
fn missing_columns_and_partial_blocks() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (&["t", "roll", "pitch", "gx", "gy", "gz"], "yaw"),
        (&["roll", "yaw", "pitch", "ax", "ay", "az"], "t"),
        (&["t", "roll", "yaw", "pitch", "gx", "gy", "ax", "ay", "az"], "gz"),
        (&["t", "roll", "yaw", "pitch", "temp"], "gx"),
    ];
    for (columns, missing) in cases {
        let path = write(dir.path(), "m.csv", csv(columns, 20, 0.0, 0.01).0);
        let err = load_err(&path, &opts());
        assert!(
            matches!(err, LoadError::MissingColumn { column, header_line: 1, .. } if column == missing),
            "{columns:?}: {err}"
        );
        assert!(
            err.to_string()
                .contains(&format!("m.csv:1: missing column '{missing}'")),
            "{err}"
        );
    }
}

#[test]
fn header_problems() {
    let dir = tempfile::tempdir().unwrap();
    let dup = write(
        dir.path(),
        "dup.csv",
        csv(
            &["t", "roll", "yaw", "pitch", "roll", "gx", "gy", "gz"],
            20,
            0.0,
            0.01,
        )
        .0,
    );
    let err = load_err(&dup, &opts());
    assert!(
        matches!(&err, LoadError::DuplicateColumn { name, columns: (2, 5), .. } if name == "roll"),
        "{err}"
    );
    assert!(err.to_string().contains("dup.csv:1:5 (column 'roll')"), "{err}");
    for (delimiter, name) in [(';', "semi.csv"), ('\t', "tab.csv")] {
        let text = gyro_lines().join("\n").replace(',', &delimiter.to_string());
        let path = write(dir.path(), name, text);
        assert!(
            matches!(load_err(&path, &opts()), LoadError::WrongDelimiter { found, .. } if found == delimiter)
        );
    }
    let mut lines = gyro_lines();
    lines[0].push(',');
    assert!(matches!(
        lines_err(dir.path(), "trailing.csv", &lines),
        LoadError::EmptyColumnName { column: 8, .. }
    ));
}

#[test]
fn not_numeric_names_line_column_and_cell() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines = with_cell(20, 2, "1.2.3");
    let path = write_lines(dir.path(), "cruise.csv", &lines);
    for chunk_bytes in [8 << 20, 100] {
        let err = load_err(&path, &chunked(chunk_bytes));
        assert!(
            matches!(&err, LoadError::NotNumeric { line: 20, column: 3, name, cell, .. } if name == "yaw" && cell == "1.2.3"),
            "{err}"
        );
        assert!(
            err.to_string()
                .ends_with(r#"cruise.csv:20:3 (column 'yaw'): not a number: "1.2.3""#),
            "{err}"
        );
    }
    lines[19] = lines[19].replace("1.2.3", "");
    assert!(matches!(
        lines_err(dir.path(), "blankcell.csv", &lines),
        LoadError::NotNumeric {
            line: 20,
            column: 3,
            ..
        }
    ));
}

#[test]
fn nan_and_infinities_are_non_finite() {
    let dir = tempfile::tempdir().unwrap();
    for (k, bad) in ["nan", "inf", "-inf", "NaN", "+Infinity", "1e999"]
        .iter()
        .enumerate()
    {
        let err = lines_err(dir.path(), &format!("nf{k}.csv"), &with_cell(31, 6, bad));
        assert!(
            matches!(&err, LoadError::NonFinite { line: 31, column: 7, name, cell, .. } if name == "gz" && cell == bad),
            "{bad}: {err}"
        );
    }
}

#[test]
fn wrong_field_counts_and_truncated_last_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines = gyro_lines();
    lines[10].push_str(",0.5");
    let err = lines_err(dir.path(), "extra.csv", &lines);
    assert!(
        matches!(
            err,
            LoadError::WrongFieldCount {
                line: 11,
                expected: 7,
                found: 8,
                truncated: false,
                ..
            }
        ),
        "{err}"
    );
    let mut lines = gyro_lines();
    let last = lines.len() - 1;
    let cut = lines[last].match_indices(',').nth(4).unwrap().0 + 3;
    lines[last].truncate(cut); // "…,0.0" cut mid-number after 6 fields
    let path = write(dir.path(), "cut.csv", lines.join("\n"));
    let err = load_err(&path, &opts());
    assert!(
        matches!(
            err,
            LoadError::WrongFieldCount {
                line: 41,
                expected: 7,
                found: 6,
                truncated: true,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string()
            .contains("line 41 has 6 fields, header has 7 (truncated last line?)"),
        "{err}"
    );
}

#[test]
fn blank_line_inside_data_and_overlong_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines = gyro_lines();
    lines.insert(12, String::new());
    let path = write_lines(dir.path(), "blank.csv", &lines);
    for chunk_bytes in [8 << 20, 50] {
        let err = load_err(&path, &chunked(chunk_bytes));
        assert!(
            matches!(err, LoadError::BlankLine { line: 13, .. }),
            "chunk {chunk_bytes}: {err}"
        );
    }
    let mut lines = gyro_lines();
    lines.insert(3, "1".repeat(3 << 20));
    assert!(matches!(
        lines_err(dir.path(), "long.csv", &lines),
        LoadError::LineTooLong { line: 4, .. }
    ));
}

#[test]
fn time_must_increase_uniformly() {
    let dir = tempfile::tempdir().unwrap();
    let lines = with_cell(10, 0, "0.07");
    let err = lines_err(dir.path(), "repeat.csv", &lines);
    assert!(
        matches!(
            err,
            LoadError::TimeNotIncreasing {
                line: 10,
                column: 1,
                t_prev: 0.07,
                t: 0.07,
                ..
            }
        ),
        "{err}"
    );
    // A 2 % longer step at line 30 (t is the first column).
    let (text, _) = csv(&ALL[..7], 40, 0.0, 0.01);
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    for (i, line) in lines.iter_mut().enumerate().skip(29) {
        let rest = line.split_once(',').unwrap().1.to_owned();
        *line = format!("{:.6},{rest}", (i - 1) as f64 * 0.01 + 0.0002);
    }
    let err = lines_err(dir.path(), "gap.csv", &lines);
    assert!(
        matches!(
            err,
            LoadError::IrregularSampling {
                line: 30,
                column: 1,
                ..
            }
        ),
        "{err}"
    );
    // The message gives the step and the nominal without rounding digits, the deviation and the
    // limit (it gave "step 0.0020299999999999763 s, nominal 0.0019999999999997797 s").
    let words = err.to_string();
    assert!(
        words.contains("a step of 0.0102 s, 2 % off the nominal 0.01 s")
            && words.contains("at most 1 % is accepted"),
        "{words}"
    );
    if let LoadError::IrregularSampling { dt, nominal_dt, .. } = err {
        assert!(
            (dt - 0.0102).abs() < 1e-9 && (nominal_dt - 0.01).abs() < 1e-9,
            "{dt} {nominal_dt}"
        );
    }
    // A 0.5 % jitter is within the 1 % tolerance.
    let path = write_lines(
        dir.path(),
        "gap.csv",
        &lines
            .iter()
            .map(|l| l.replacen("0.0002", "0.00005", 1))
            .collect::<Vec<_>>(),
    );
    assert!(
        load(
            &path,
            &LoadOptions {
                sampling_tolerance: 0.03,
                ..opts()
            }
        )
        .is_ok()
    );
}

#[test]
fn too_few_samples() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "short.csv", csv(&ALL[..7], 15, 0.0, 0.01).0);
    assert!(matches!(
        load_err(&path, &opts()),
        LoadError::TooFewSamples { n: 15, min: 16, .. }
    ));
    let path = write(dir.path(), "header_only.csv", "t,roll,yaw,pitch,gx,gy,gz\n");
    assert!(matches!(
        load_err(&path, &opts()),
        LoadError::TooFewSamples { n: 0, .. }
    ));
    let path = write(dir.path(), "sixteen.csv", csv(&ALL[..7], 16, 0.0, 0.01).0);
    assert_eq!(load(&path, &opts()).unwrap().len(), 16);
}

#[test]
fn too_large_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "big.csv", csv(&ALL, 2000, 0.0, 0.01).0);
    let options = LoadOptions {
        chunk_bytes: 4096,
        memory_limit_bytes: Some(100_000),
        ..opts()
    };
    let err = load_err(&path, &options);
    let (needed_bytes, available_bytes) = too_large(&err);
    assert_eq!(available_bytes, 100_000);
    // 2000 rows x 10 columns x 8 bytes, estimated from the first 4 KiB.
    assert!((150_000..250_000).contains(&needed_bytes), "{needed_bytes}");
    assert!(
        load(
            &path,
            &LoadOptions {
                memory_limit_bytes: Some(200_000_000),
                ..options
            }
        )
        .is_ok()
    );
}

/// A gzip file's size says little about its text, and the decompressor reads ahead: the first
/// block's estimate is low, so the limit is checked again as the file streams.
#[test]
fn too_large_gzip_is_refused_as_it_streams() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL, 2000, 0.0, 0.01);
    let path = write(dir.path(), "big.csv.gz", gzip(text.as_bytes()));
    let options = LoadOptions {
        chunk_bytes: 4096,
        memory_limit_bytes: Some(100_000),
        ..opts()
    };
    let mut calls = 0;
    let err = load_with_progress(&path, &options, &mut |_| {
        calls += 1;
        ControlFlow::Continue(())
    })
    .unwrap_err();
    let (needed_bytes, available_bytes) = too_large(&err);
    assert_eq!(available_bytes, 100_000);
    // Refused once the rows read so far exceed the limit (1250 rows of 10 columns), before the
    // 2000 rows were all decoded.
    assert!((100_000..160_000).contains(&needed_bytes), "{needed_bytes}");
    assert!(calls > 3, "the first blocks passed: {calls} progress calls");
    assert!(
        err.to_string()
            .contains("big.csv.gz: the decoded run needs about"),
        "{err}"
    );
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

// ---------------------------------------------------------------------------------------------
// Robustness: random damage never panics.

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

/// The needed and available bytes of a [`LoadError::TooLarge`]; panics on any other error.
fn too_large(err: &LoadError) -> (u64, u64) {
    let LoadError::TooLarge {
        needed_bytes,
        available_bytes,
        ..
    } = err
    else {
        panic!("{err}")
    };
    (*needed_bytes, *available_bytes)
}
