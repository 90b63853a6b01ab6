//! The sample run bundled into the binary (`sample_runs/cruise.csv.gz` + `cruise.json`), written
//! once to a folder under the system's temporary directory so the loader can read it from a path.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

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
/// that many bytes. The temporary name is the process's and the call's own: two threads of one
/// process writing at once (the app's tests in one binary) each rename a whole file of their
/// own, where a shared name let the second rename find the first's file gone.
fn write_once(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    if std::fs::metadata(path).is_ok_and(|m| m.len() == bytes.len() as u64) {
        return Ok(());
    }
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_extension(format!("part{}-{call}", std::process::id()));
    let mut file = std::fs::File::create(&tmp)?;
    file.write_all(bytes)?;
    file.sync_all()?;
    std::fs::rename(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::write_once;

    /// Threads writing the same file at once each succeed and leave it whole (with one temporary
    /// name per process, a rename found the file another thread had already renamed: `NotFound`).
    #[test]
    fn concurrent_writers_each_succeed_and_leave_the_file_whole() {
        let bytes: Vec<u8> = (0..200_000u32).map(|i| (i % 251) as u8).collect();
        for round in 0..20 {
            let dir = tempfile::tempdir().expect("tempdir");
            let path = dir.path().join(format!("sample{round}.bin"));
            let results: Vec<std::io::Result<()>> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..8).map(|_| s.spawn(|| write_once(&path, &bytes))).collect();
                handles.into_iter().map(|h| h.join().expect("no panic")).collect()
            });
            for r in &results {
                assert!(r.is_ok(), "round {round}: {r:?}");
            }
            assert_eq!(std::fs::read(&path).expect("written"), bytes);
        }
    }
}
