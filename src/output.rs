//! Writing outputs safely: atomically (a temporary file in the destination folder, flushed and
//! synced, then renamed over the destination) and never over an input.
//!
//! A failed write (full disk, unwritable folder, an error from the producer) removes the temporary
//! file and leaves the destination untouched: no partial output ever exists under the final name.

use std::fs::{self, File};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

/// Why an output was not written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The destination is one of the inputs (or an input's sidecar).
    #[error("refusing to write {path}: it is an input of this command")]
    WouldOverwriteInput {
        /// The destination.
        path: PathBuf,
    },
    /// The destination is a directory.
    #[error("cannot write {path}: it is a directory")]
    IsDirectory {
        /// The destination.
        path: PathBuf,
    },
    /// An I/O error; nothing was left under the destination's name.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The destination.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
}

/// Refuses `out` when it names the same file as any of `inputs` (compared after resolving links
/// and `..`, when the files exist).
///
/// # Errors
/// [`OutputError::WouldOverwriteInput`] when it does, [`OutputError::IsDirectory`] when `out` is a
/// directory.
pub fn ensure_not_input(out: &Path, inputs: &[PathBuf]) -> Result<(), OutputError> {
    if out.is_dir() {
        return Err(OutputError::IsDirectory {
            path: out.to_path_buf(),
        });
    }
    let resolve = |p: &Path| fs::canonicalize(p).ok();
    let out_resolved = resolve(out);
    for input in inputs {
        let same = match (&out_resolved, resolve(input)) {
            (Some(a), Some(b)) => *a == b,
            _ => out == input.as_path(),
        };
        if same {
            return Err(OutputError::WouldOverwriteInput {
                path: out.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Writes `path` atomically with the bytes `produce` writes into the buffered writer it is given.
///
/// # Errors
/// [`OutputError::Io`] when the folder cannot be written, the disk is full, or `produce` fails;
/// the temporary file is removed and `path` is untouched.
pub fn write_atomic(
    path: &Path,
    produce: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let io_err = |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let file = File::create(&tmp)?;
        let mut writer = BufWriter::with_capacity(1 << 20, file);
        produce(&mut writer)?;
        let file = writer.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(io_err(e));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn writes_whole_file_and_replaces_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.json");
        write_atomic(&p, |w| w.write_all(b"first")).unwrap();
        write_atomic(&p, |w| w.write_all(b"second")).unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        assert_eq!(
            fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary file left"
        );
    }

    #[test]
    fn failure_leaves_no_partial_file_and_keeps_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.csv");
        let err = write_atomic(&p, |w| {
            w.write_all(b"half a file")?;
            Err(io::Error::other("disk full"))
        });
        assert!(matches!(err, Err(OutputError::Io { .. })));
        assert!(!p.exists());
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
        fs::write(&p, b"old").unwrap();
        assert!(write_atomic(&p, |_| Err(io::Error::other("boom"))).is_err());
        assert_eq!(fs::read(&p).unwrap(), b"old");
    }

    #[test]
    fn unwritable_folder_and_directories_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no-such-folder").join("x.json");
        assert!(matches!(
            write_atomic(&missing, |w| w.write_all(b"x")),
            Err(OutputError::Io { .. })
        ));
        assert!(matches!(
            write_atomic(dir.path(), |w| w.write_all(b"x")),
            Err(OutputError::IsDirectory { .. })
        ));
    }

    #[test]
    fn refuses_to_overwrite_inputs_even_through_other_spellings() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("run.csv");
        fs::write(&input, b"t\n").unwrap();
        let other = dir.path().join(".").join("run.csv");
        assert!(matches!(
            ensure_not_input(&other, std::slice::from_ref(&input)),
            Err(OutputError::WouldOverwriteInput { .. })
        ));
        assert!(ensure_not_input(&dir.path().join("model.json"), &[input]).is_ok());
    }
}
