//! Property-based fuzzing of the three parsers that read user files: the run (CSV, plain or
//! gzipped), its sidecar, and the identifier's settings. Inputs are arbitrary bytes and mutations
//! of valid files (truncations, bit flips, inserted commas, quotes, NaN, inf, huge exponents, BOMs,
//! NULs, swapped, dropped and repeated lines). Every input must give either a value that keeps the
//! parser's contract or a structured error with a one-line message naming the file; never a
//! panic. The same targets run under cargo-fuzz (`fuzz/`, see the README).
//!
//! Cases per property: `PROPTEST_CASES` (proptest's default, 256, in CI). Crashes found are kept
//! as files in `tests/data/fuzz_regressions/`, replayed by `fuzz_regressions_are_replayed`.
#![expect(
    clippy::unwrap_used,
    reason = "test helpers: a failed setup step should panic"
)]

use std::io::Write as _;
use std::path::Path;

use imu_attest::ident::band::BandSetting;
use imu_attest::ident::settings::{MIN_EQUIVALENT_AVERAGES, Settings, equivalent_averages_of};
use imu_attest::run::{Block, LoadError, LoadOptions, Run, load_bytes, parse_sidecar};
use proptest::prelude::*;

const COLUMNS: [&str; 10] = ["t", "roll", "yaw", "pitch", "gx", "gy", "gz", "ax", "ay", "az"];

/// Tokens worth inserting: delimiters, quotes, special numbers, line ends, encodings.
const TOKENS: [&str; 24] = [
    ",",
    ",,",
    "\"",
    "'",
    ";",
    "\t",
    "\n",
    "\r\n",
    "\r",
    "\n\n",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e999",
    "-1e-999",
    "1e308",
    "9e307",
    "0x1p3",
    "\u{feff}",
    "\0",
    "\u{fffd}",
    "-",
    "1.7976931348623157e308",
];

/// A valid run text: `n` rows of `columns` starting at `t0` with step `dt`.
fn valid_csv(columns: &[&str], n: usize, t0: f64, dt: f64, scale: f64) -> String {
    let mut text = columns.join(",") + "\n";
    for i in 0..n {
        let cells: Vec<String> = columns
            .iter()
            .enumerate()
            .map(|(c, name)| match *name {
                "t" => format!("{:.6}", t0 + i as f64 * dt),
                _ => format!("{:.6e}", (((i * 7 + c * 13) % 97) as f64 * 1e-3 - 0.05) * scale),
            })
            .collect();
        text += &cells.join(",");
        text.push('\n');
    }
    text
}

/// One damage to a file.
#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    FlipBit(usize, u8),
    Insert(usize, &'static str),
    InsertByte(usize, u8),
    Delete(usize),
    SwapLines(usize, usize),
    DropLine(usize),
    RepeatLine(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 0..8_u8).prop_map(|(at, bit)| Mutation::FlipBit(at, bit)),
        (any::<usize>(), prop::sample::select(&TOKENS[..])).prop_map(|(at, t)| Mutation::Insert(at, t)),
        (any::<usize>(), any::<u8>()).prop_map(|(at, b)| Mutation::InsertByte(at, b)),
        any::<usize>().prop_map(Mutation::Delete),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        any::<usize>().prop_map(Mutation::DropLine),
        any::<usize>().prop_map(Mutation::RepeatLine),
    ]
}

/// Applies `m` to `bytes` (positions are taken modulo the length).
fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let at = |i: usize, len: usize| if len == 0 { 0 } else { i % (len + 1) };
    let lines = |bytes: &[u8]| -> Vec<Vec<u8>> {
        bytes
            .split_inclusive(|&b| b == b'\n')
            .map(<[u8]>::to_vec)
            .collect()
    };
    match *m {
        Mutation::Truncate(i) => bytes.truncate(at(i, bytes.len())),
        Mutation::FlipBit(i, bit) if !bytes.is_empty() => {
            let i = i % bytes.len();
            bytes[i] ^= 1 << bit;
        }
        Mutation::Insert(i, token) => {
            let i = at(i, bytes.len());
            bytes.splice(i..i, token.bytes());
        }
        Mutation::InsertByte(i, b) => bytes.insert(at(i, bytes.len()), b),
        Mutation::Delete(i) if !bytes.is_empty() => {
            bytes.remove(i % bytes.len());
        }
        Mutation::SwapLines(a, b) => {
            let mut l = lines(bytes);
            if !l.is_empty() {
                let n = l.len();
                l.swap(a % n, b % n);
                *bytes = l.concat();
            }
        }
        Mutation::DropLine(i) => {
            let mut l = lines(bytes);
            if !l.is_empty() {
                let n = l.len();
                l.remove(i % n);
                *bytes = l.concat();
            }
        }
        Mutation::RepeatLine(i) => {
            let mut l = lines(bytes);
            if !l.is_empty() {
                let n = l.len();
                let line = l[i % n].clone();
                l.insert(i % n, line);
                *bytes = l.concat();
            }
        }
        _ => {}
    }
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// A loaded run keeps the loader's contract: equal, finite columns, a finite positive rate,
/// strictly increasing time.
fn assert_run_contract(run: &Run) {
    let n = run.len();
    assert!(n >= imu_attest::run::MIN_SAMPLES);
    assert!(!run.blocks().is_empty());
    let mut columns: Vec<&Vec<f64>> = vec![&run.time_s];
    columns.extend(run.angles.iter());
    for block in [Block::Gyro, Block::Accel] {
        columns.extend(run.outputs(block).into_iter().flatten());
    }
    columns.extend(run.extra.iter().map(|e| &e.values));
    for c in columns {
        assert_eq!(c.len(), n);
        assert!(c.iter().all(|v| v.is_finite()));
    }
    assert!(run.time_s.windows(2).all(|w| w[1] > w[0]));
    assert!(
        run.sample_rate_hz.is_finite() && run.sample_rate_hz > 0.0,
        "{}",
        run.sample_rate_hz
    );
    assert!(run.dt_s().is_finite() && run.duration_s().is_finite());
}

/// Loads `bytes` as `fuzz.csv` with blocks of `chunk_bytes`; checks the result either way.
/// Returns whether the run was accepted.
fn check_run_bytes(bytes: &[u8], chunk_bytes: usize) -> bool {
    let options = LoadOptions {
        chunk_bytes,
        memory_limit_bytes: Some(1 << 30),
        ..LoadOptions::default()
    };
    match load_bytes(Path::new("fuzz.csv"), bytes, &options) {
        Ok(run) => {
            assert_run_contract(&run);
            true
        }
        Err(e) => {
            assert_error_message(&e.to_string(), "fuzz.csv");
            if let LoadError::NotNumeric { line, column, .. } | LoadError::NonFinite { line, column, .. } = e
            {
                assert!(line >= 2 && column >= 1, "{e}");
            }
            false
        }
    }
}

/// A structured error's message: one non-empty line naming the file.
fn assert_error_message(message: &str, file: &str) {
    assert!(!message.trim().is_empty());
    assert!(!message.contains('\n'), "not one line: {message}");
    assert!(message.contains(file), "does not name {file}: {message}");
}

fn chunk_size() -> impl Strategy<Value = usize> {
    prop::sample::select(vec![1_usize, 7, 64, 4096, 8 << 20])
}

/// A valid run: some of the columns, in some order, 14 to 40 rows (so some are too short).
fn valid_run() -> impl Strategy<Value = Vec<u8>> {
    (
        prop::sample::subsequence(COLUMNS[1..].to_vec(), 3..=9).prop_shuffle(),
        14_usize..40,
        -1e3..1e3_f64,
        prop::sample::select(vec![1e-3, 0.002, 0.01, 1.0]),
        prop::sample::select(vec![1.0, 1e-300, 1e300]),
    )
        .prop_map(|(mut columns, n, t0, dt, scale)| {
            columns.insert(0, "t");
            valid_csv(&columns, n, t0, dt, scale).into_bytes()
        })
}

proptest! {
    #[test]
    fn arbitrary_bytes_never_panic_the_run_parser(
        bytes in prop::collection::vec(any::<u8>(), 0..600),
        chunk in chunk_size(),
    ) {
        check_run_bytes(&bytes, chunk);
        // Arbitrary bytes after a valid header reach the row parser.
        let mut text = b"t,roll,yaw,pitch,gx,gy,gz\n".to_vec();
        text.extend_from_slice(&bytes);
        check_run_bytes(&text, chunk);
    }

    #[test]
    fn mutated_runs_never_panic_the_run_parser(
        file in valid_run(),
        mutations in prop::collection::vec(mutation(), 0..6),
        gzipped in any::<bool>(),
        damage_gzip in prop::option::of(mutation()),
        chunk in chunk_size(),
    ) {
        let mut bytes = file;
        for m in &mutations {
            apply(&mut bytes, m);
        }
        if gzipped {
            bytes = gzip(&bytes);
            if let Some(m) = &damage_gzip {
                apply(&mut bytes, m);
            }
        }
        check_run_bytes(&bytes, chunk);
    }

    #[test]
    fn mutated_sidecars_never_panic(
        bytes in sidecar_bytes(),
    ) {
        let mut notices = Vec::new();
        match parse_sidecar(Path::new("fuzz.json"), &bytes, "fuzz", &mut notices) {
            Ok(s) => {
                prop_assert!(s.g_mps2.is_finite() && s.g_mps2 > 0.0);
                prop_assert!(s.accel_lever_arm_m.iter().chain(&s.gyro_lever_arm_m).all(|v| v.is_finite()));
                prop_assert!(s.angle_noise_rad.is_none_or(|v| v.is_finite() && v >= 0.0));
                prop_assert!(!s.regime.trim().is_empty());
            }
            Err(e) => {
                prop_assert!(matches!(e, LoadError::Sidecar { .. } | LoadError::SidecarValue { .. }), "{e}");
                assert_error_message(&e.to_string(), "fuzz.json");
            }
        }
    }

    #[test]
    fn mutated_settings_never_panic(
        bytes in settings_bytes(),
        n_samples in 0_usize..100_000,
        rate in prop::sample::select(vec![0.0, 1.0, 500.0, 1e300, f64::NAN]),
    ) {
        match Settings::from_json(&bytes, Path::new("fuzz.json")) {
            Ok(s) => {
                // Validation of any parsed settings against any run shape returns, and what it
                // accepts keeps the rules.
                if s.validate(n_samples, rate, &[Block::Gyro, Block::Accel]).is_ok() {
                    if let BandSetting::Fixed([low, high]) = s.band_hz {
                        prop_assert!(low > 0.0 && low < high && high <= rate / 2.0);
                    }
                    prop_assert!(s.welch.segment_len <= n_samples);
                    // Enough averages for the 3-input estimate (at most one per segment).
                    prop_assert!(s.welch.n_segments(n_samples) >= 8);
                    prop_assert!(equivalent_averages_of(&s.welch, n_samples) >= MIN_EQUIVALENT_AVERAGES);
                }
                // Whatever parsed writes back as JSON and reads back the same.
                let text = serde_json::to_string(&s).unwrap();
                prop_assert_eq!(Settings::from_json(text.as_bytes(), Path::new("again.json")).unwrap(), s);
            }
            Err(e) => assert_error_message(&e.to_string(), "fuzz.json"),
        }
    }
}

/// A valid sidecar, its fields' values replaced by random JSON, then mutated; or arbitrary bytes.
fn sidecar_bytes() -> impl Strategy<Value = Vec<u8>> {
    let value = prop_oneof![
        Just("null".to_owned()),
        any::<f64>().prop_map(|v| format!("{v:e}")),
        prop::sample::select(vec![
            "-9.8",
            "0",
            "1e999",
            "[0.1, 0.2]",
            "[1, 2, 3, 4]",
            "[1e999, 0, 0]",
            "\"x\"",
            "\" \"",
            "{}",
            "[]",
            "true"
        ])
        .prop_map(str::to_owned),
    ];
    let fields = imu_attest::run::SIDECAR_FIELDS;
    let structured = (
        prop::collection::vec((prop::sample::select(fields.to_vec()), value), 0..8),
        prop::collection::vec(mutation(), 0..3),
    )
        .prop_map(|(pairs, mutations)| {
            let body: Vec<String> = pairs.iter().map(|(k, v)| format!("\"{k}\": {v}")).collect();
            let mut bytes = format!("{{{}}}", body.join(", ")).into_bytes();
            for m in &mutations {
                apply(&mut bytes, m);
            }
            bytes
        });
    prop_oneof![structured, prop::collection::vec(any::<u8>(), 0..200)]
}

/// Valid settings with random values in their fields, then mutated; or arbitrary bytes.
fn settings_bytes() -> impl Strategy<Value = Vec<u8>> {
    let number = prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:e}")),
        (-100_i64..100_000).prop_map(|v| v.to_string()),
        prop::sample::select(vec!["1e999", "-0", "0.1", "40", "\"auto\"", "null", "[]"])
            .prop_map(str::to_owned),
    ];
    let structured = (
        prop::collection::vec(number, 17),
        prop::sample::select(vec!["hann", "hamming", "rectangular", "blackman_harris", "bogus"]),
        prop::sample::select(vec!["mean", "linear", "none", "bogus"]),
        prop::collection::vec(mutation(), 0..3),
    )
        .prop_map(|(v, window, detrend, mutations)| {
            let text = format!(
                r#"{{"welch": {{"segment_len": {}, "overlap": {}, "window": "{window}", "detrend": "{detrend}"}},
                "band_hz": [{}, {}], "weight_A": [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]],
                "lambda": [{}, {}, {}], "order": {}, "blocks": ["gyro"]}}"#,
                v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11], v[12], v[13], v[14], v[15], v[16]
            );
            let mut bytes = text.into_bytes();
            for m in &mutations {
                apply(&mut bytes, m);
            }
            bytes
        });
    prop_oneof![structured, prop::collection::vec(any::<u8>(), 0..200)]
}

/// Every run file kept from a crash (each was once accepted wrongly or crashed the loader) is
/// loaded again with several block sizes: none may panic, each must be refused.
#[test]
fn fuzz_regressions_are_replayed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz_regressions");
    let mut replayed = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("md")) {
            continue;
        }
        for chunk in [7, 64, 8 << 20] {
            assert!(!check_run_bytes(&bytes, chunk), "{name} must be refused");
        }
        replayed += 1;
    }
    assert!(replayed > 0, "no regression file in {}", root.display());
}
