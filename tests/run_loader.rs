//! Integration tests of `imu_attest::run` on good files: they load to the exact values written
//! (plain or gzip, in blocks of any size, numbers in every form a recorder writes, quoted, permuted
//! or unknown columns, one block or both), with their hash, notices and progress. Bad files:
//! `run_loader_errors.rs`; the sidecar: `run_loader_sidecar.rs`; random damage:
//! `run_loader_damage.rs`.
#![expect(
    clippy::unwrap_used,
    reason = "test helpers: a failed setup step should panic"
)]
#![expect(
    clippy::float_cmp,
    reason = "a parser must reproduce the written values to the bit"
)]

use std::fmt::Write as _;
use std::ops::ControlFlow;

use crate::common::loader as loader_common;
use imu_attest::rng::Rng;
use imu_attest::run::{Block, LoadError, LoadOptions, LoadProgress, Run, load, load_with_progress};
use loader_common::{ALL, chunked, csv, gzip, load_err, opts, write};
use sha2::{Digest as _, Sha256};

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
