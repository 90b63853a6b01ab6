//! Integration tests of `imu_attest::run` on bad files: one test per `LoadError` variant, each
//! with the right line and column, in a one-line message that names the file.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use crate::common::loader as loader_common;
use imu_attest::run::{LoadError, LoadOptions, load, load_with_progress};
use loader_common::{ALL, chunked, csv, gzip, load_err, opts, write};

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
    // The message gives the step and the nominal without rounding digits, the deviation and the
    // limit (it gave "step 0.0020299999999999763 s, nominal 0.0019999999999997797 s").
    let words = irregular_at(&err, 30);
    assert!(
        words.contains("a step of 0.0102 s, 2 % off the nominal 0.01 s")
            && words.contains("at most 1 % is accepted"),
        "{words}"
    );
    // A jitter is not a gap: no missing samples are claimed.
    assert!(!words.contains("missing"), "{words}");
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

/// A logger that dropped samples leaves a step of a whole number of nominal steps: the error
/// says how many samples are missing and what to do (cut or fill), and names the line.
#[test]
fn a_dropped_sample_is_named_as_missing() {
    let dir = tempfile::tempdir().unwrap();
    let (text, _) = csv(&ALL[..7], 40, 0.0, 0.01);
    for (dropped, words) in [(1, "1 sample missing there"), (3, "3 samples missing there")] {
        // `dropped` rows from line 22 on removed (the header is line 1): the step that ends on
        // the new line 22 is the gap.
        let lines: Vec<String> = text
            .lines()
            .enumerate()
            .filter(|(i, _)| !(21..21 + dropped).contains(i))
            .map(|(_, l)| l.to_owned())
            .collect();
        let message = irregular_at(&lines_err(dir.path(), "dropped.csv", &lines), 22);
        assert!(
            message.contains(words) && message.contains("cut the record at the gap"),
            "{message}"
        );
    }
}

/// The message of `err`, which must be an irregular step ending on `line`, in the time column.
fn irregular_at(err: &LoadError, line: usize) -> String {
    assert!(
        matches!(err, LoadError::IrregularSampling { line: l, column: 1, .. } if *l == line),
        "{err}"
    );
    err.to_string()
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
