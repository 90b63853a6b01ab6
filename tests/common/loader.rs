//! Helpers shared by the tests of `imu_attest::run` (`tests/run_loader*.rs`): CSV texts of known
//! values, written plain or gzip, loaded with the default or chunked options, and the error of a
//! file that should be refused.
#![expect(
    clippy::unwrap_used,
    reason = "test helpers: a failed setup step should panic"
)]

use std::io::Write as _;
use std::path::{Path, PathBuf};

use imu_attest::run::{LoadError, LoadOptions, load};

/// The ten columns of a run with both blocks, in the usual order.
pub const ALL: [&str; 10] = ["t", "roll", "yaw", "pitch", "gx", "gy", "gz", "ax", "ay", "az"];

/// A CSV text with `columns`, `n` rows, `t = t0 + i dt`, plus the values its cells parse to.
pub fn csv(columns: &[&str], n: usize, t0: f64, dt: f64) -> (String, Vec<Vec<f64>>) {
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

/// `bytes` written to `dir/name`; the path written.
pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// `bytes` gzip-compressed.
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// The default load options.
pub fn opts() -> LoadOptions {
    LoadOptions::default()
}

/// The default options with blocks of `chunk_bytes`, to cross block boundaries in small files.
pub fn chunked(chunk_bytes: usize) -> LoadOptions {
    LoadOptions {
        chunk_bytes,
        ..opts()
    }
}

/// The error of loading `path` with `options`, checked to name the file on one line.
pub fn load_err(path: &Path, options: &LoadOptions) -> LoadError {
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
