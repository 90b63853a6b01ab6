//! The sample run bundled into the binary (`sample_runs/cruise.csv.gz` + `cruise.json`), written
//! once to a folder under the system's temporary directory so the loader can read it from a path.

use std::io::Write as _;
use std::path::{Path, PathBuf};

const CSV_NAME: &str = "cruise.csv.gz";
const CSV: &[u8] = include_bytes!("../../sample_runs/cruise.csv.gz");
const SIDECAR_NAME: &str = "cruise.json";
const SIDECAR: &[u8] = include_bytes!("../../sample_runs/cruise.json");

/// Writes the sample run (if not already there with the same size) and returns its CSV path.
///
/// # Errors
/// If the temporary folder or the files cannot be written.
pub fn sample_run_path() -> std::io::Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("imu-attest-{}-sample", env!("CARGO_PKG_VERSION")));
    std::fs::create_dir_all(&dir)?;
    write_once(&dir.join(SIDECAR_NAME), SIDECAR)?;
    let csv = dir.join(CSV_NAME);
    write_once(&csv, CSV)?;
    Ok(csv)
}

/// Writes `bytes` to `path` through a temporary file and a rename, unless `path` already has
/// that many bytes.
fn write_once(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| m.len() == bytes.len() as u64) {
        return Ok(());
    }
    let tmp = path.with_extension(format!("part{}", std::process::id()));
    let mut file = std::fs::File::create(&tmp)?;
    file.write_all(bytes)?;
    file.sync_all()?;
    std::fs::rename(&tmp, path)
}
