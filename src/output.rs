//! Writing outputs safely: atomically (a temporary file in the destination folder, flushed and
//! synced, then renamed over the destination) and never over an input.
//!
//! A failed write (full disk, unwritable folder, an error from the producer) removes the temporary
//! file and leaves the destination untouched: no partial output ever exists under the final name.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
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
    /// The destination exists and is not a regular file (a device, a FIFO, a socket): renaming
    /// over it would replace it.
    #[error("cannot write {path}: it exists and is not a regular file")]
    NotRegular {
        /// The destination.
        path: PathBuf,
    },
    /// The content holds a number JSON or CSV cannot carry (NaN or infinity): nothing is written.
    #[error("refusing to write {path}: {detail}")]
    NonFinite {
        /// The destination.
        path: PathBuf,
        /// Where the first non-finite number is.
        detail: String,
    },
    /// An I/O error; nothing was left under the destination's name.
    #[error("cannot write {path}: {source}; nothing was written")]
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
/// the temporary file is removed and `path` is untouched. [`OutputError::IsDirectory`] or
/// [`OutputError::NotRegular`] when `path` exists and is not a regular file.
pub fn write_atomic(
    path: &Path,
    produce: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), OutputError> {
    write_atomic_via(path, |tmp| File::create(tmp), produce)
}

/// [`write_atomic`] with the temporary file opened by `create`: tests hand in a sink that fails
/// like a full disk.
fn write_atomic_via<W: Write + SyncAll>(
    path: &Path,
    create: impl FnOnce(&Path) -> io::Result<W>,
    produce: impl FnOnce(&mut BufWriter<W>) -> io::Result<()>,
) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    if path.exists() && !path.is_file() {
        return Err(OutputError::NotRegular {
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
        let file = create(&tmp)?;
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

/// A sink whose bytes can be forced to the storage device before the rename.
trait SyncAll {
    /// Flushes the data to the device.
    fn sync_all(&self) -> io::Result<()>;
}

impl SyncAll for File {
    fn sync_all(&self) -> io::Result<()> {
        File::sync_all(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A file that takes `room` bytes, then fails like a full disk.
    struct FullDisk {
        file: File,
        room: usize,
    }

    impl Write for FullDisk {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from(io::ErrorKind::StorageFull));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.file.write(&buf[..n])
        }
        fn flush(&mut self) -> io::Result<()> {
            self.file.flush()
        }
    }

    impl SyncAll for FullDisk {
        fn sync_all(&self) -> io::Result<()> {
            self.file.sync_all()
        }
    }

    #[test]
    fn full_disk_leaves_no_partial_file_and_keeps_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("model.json");
        fs::write(&p, b"old model").unwrap();
        // 3 MB through a 1 MiB buffer: the disk fills while `produce` writes and again at the
        // final flush, with 10 kB (then 0 bytes) of room.
        for room in [10_000, 0] {
            let err = write_atomic_via(
                &p,
                |tmp| {
                    Ok(FullDisk {
                        file: File::create(tmp)?,
                        room,
                    })
                },
                |w| w.write_all(&vec![b'x'; 3_000_000]),
            )
            .unwrap_err();
            let OutputError::Io { source, .. } = &err else {
                panic!("{err}")
            };
            assert_eq!(source.kind(), io::ErrorKind::StorageFull, "{err}");
            assert!(err.to_string().contains("nothing was written"), "{err}");
            assert_eq!(fs::read(&p).unwrap(), b"old model");
            assert_eq!(
                fs::read_dir(dir.path()).unwrap().count(),
                1,
                "temporary file removed"
            );
        }
        // A disk that fills only when the buffer is flushed at the end.
        let err = write_atomic_via(
            &dir.path().join("small.json"),
            |tmp| {
                Ok(FullDisk {
                    file: File::create(tmp)?,
                    room: 10,
                })
            },
            |w| w.write_all(b"a small file of 31 bytes ......"),
        );
        assert!(matches!(err, Err(OutputError::Io { .. })));
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_destination_that_is_not_a_regular_file_is_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        let err = write_atomic(&fifo, |w| w.write_all(b"x")).unwrap_err();
        assert!(matches!(err, OutputError::NotRegular { .. }), "{err}");
        assert!(!fifo.is_file(), "the FIFO was not replaced by a file");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
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
        // A folder that is a regular file: as unwritable as a read-only one, even for root.
        let file = dir.path().join("plain");
        fs::write(&file, b"x").unwrap();
        let err = write_atomic(&file.join("x.json"), |w| w.write_all(b"x")).unwrap_err();
        assert!(matches!(err, OutputError::Io { .. }), "{err}");
        assert_eq!(fs::read(&file).unwrap(), b"x");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
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
