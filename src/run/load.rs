//! [`load`] and [`load_with_progress`]: the reading thread ([`super::stream`]) feeds chunks to the
//! header reader and the parallel row parser ([`super::csv`]) on the calling thread; then the time
//! column is checked and the columns are moved into a [`Run`].

use std::fs::File;
use std::ops::ControlFlow;
use std::path::Path;

use super::csv::Rows;
use super::header::Layout;
use super::options::{LoadOptions, LoadProgress, MIN_SAMPLES, mem_available_bytes};
use super::stream::{self, Chunk, Pipe, RawSource, SourceError, TextChunk};
use super::{ExtraColumn, LoadError, Run, RunSource, sidecar, timing, wrap};

/// A sample rate below this is noticed (`t` in milliseconds?): far below any stand's recording
/// (the slowest motion-capture references run at 50-100 Hz).
const SLOW_RATE_HZ: f64 = 10.0;
/// Capacity reserved per estimated row: the estimate from the first block is rough for gzip
/// (read-ahead) and for files whose numbers grow longer.
const RESERVE_MARGIN: f64 = 1.25;

/// Loads a run (CSV or gzipped CSV) and its sidecar.
///
/// # Errors
/// Any [`LoadError`] but `Cancelled`: unreadable file or sidecar, bad gzip, bad header, bad cell,
/// time not increasing or irregular, too few rows, too large for memory. The first problem in
/// file order is reported.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Run, LoadError> {
    load_with_progress(path, options, &mut |_| ControlFlow::Continue(()))
}

/// [`load`], calling `progress` after every block read (every few MB) and once at the end.
///
/// # Errors
/// As [`load`], and [`LoadError::Cancelled`] when `progress` returns `ControlFlow::Break(())`.
pub fn load_with_progress(
    path: &Path,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress) -> ControlFlow<()>,
) -> Result<Run, LoadError> {
    let io = io_error(path);
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(LoadError::NotAFile {
            path: path.to_owned(),
        });
    }
    let mut notices = Vec::new();
    let sidecar = sidecar::read_sidecar(path, &mut notices)?;
    let file = File::open(path).map_err(io)?;
    let stored = Stored {
        bytes: Box::new(file),
        size_bytes: meta.len(),
        sidecar,
        notices,
    };
    load_stored(path, stored, options, progress)
}

/// Parses a run held in memory (the bytes of a CSV or gzipped CSV file) as [`load`] parses a
/// file; `name` names it in errors and in [`Run::source`]. No sidecar is read: the sidecar's
/// defaults for the stem of `name` are used, without a notice. The fuzz targets and the property
/// tests drive the parser through this.
///
/// # Errors
/// As [`load`], but never [`LoadError::NotAFile`] or a sidecar error.
pub fn load_bytes(name: &Path, bytes: &[u8], options: &LoadOptions) -> Result<Run, LoadError> {
    let stored = Stored {
        bytes: Box::new(bytes),
        size_bytes: bytes.len() as u64,
        sidecar: sidecar::Sidecar::defaults(&sidecar::run_stem(name)),
        notices: Vec::new(),
    };
    load_stored(name, stored, options, &mut |_| ControlFlow::Continue(()))
}

/// Maps an I/O error on `path` to [`LoadError::Io`].
fn io_error(path: &Path) -> impl Fn(std::io::Error) -> LoadError + Copy + '_ {
    move |source| LoadError::Io {
        path: path.to_owned(),
        source,
    }
}

/// The stored bytes of a run and what was learnt before reading them.
struct Stored<'a> {
    bytes: RawSource<'a>,
    size_bytes: u64,
    sidecar: sidecar::Sidecar,
    notices: Vec<String>,
}

/// Reads, parses and checks stored bytes into a [`Run`].
fn load_stored(
    path: &Path,
    stored: Stored<'_>,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress) -> ControlFlow<()>,
) -> Result<Run, LoadError> {
    let io = io_error(path);
    let Stored {
        bytes,
        size_bytes,
        sidecar,
        mut notices,
    } = stored;
    let (sha256, rows) = std::thread::scope(|scope| {
        let (pipe, reader) = stream::spawn(scope, bytes, options.chunk_bytes).map_err(io)?;
        let parsed = Parse {
            path,
            bytes_total: size_bytes,
            memory_limit: options.memory_limit_bytes.or_else(mem_available_bytes),
            notices: &mut notices,
        }
        .run(&pipe, progress);
        drop(pipe);
        // The reader never panics on input; should it, the error is reported, not propagated.
        reader
            .join()
            .map_err(|_| io(std::io::Error::other("the reading thread stopped")))?;
        parsed
    })?;
    let (layout, mut cols) = rows.into_parts();
    let n = cols.first().map_or(0, Vec::len);
    if n < MIN_SAMPLES {
        return Err(LoadError::TooFewSamples {
            path: path.to_owned(),
            n,
            min: MIN_SAMPLES,
        });
    }
    let sample_rate_hz = timing::check_time(path, &cols[layout.t], layout.t, options.sampling_tolerance)?;
    if sample_rate_hz < SLOW_RATE_HZ {
        notices.push(format!(
            "sample rate {sample_rate_hz:.3} Hz, far below a stand's: is column 't' in seconds? (in \
             milliseconds it reads 1000 times slow, and no band of the motion is left)"
        ));
    }
    let mut take = |i: usize| std::mem::take(&mut cols[i]);
    let time_s = take(layout.t);
    let mut angles = layout.angles.map(&mut take);
    if let Some(max_step_rad) = options.max_angle_step_rad {
        wrap::unwrap_angles(path, &mut angles, layout.angles, max_step_rad, &mut notices)?;
    }
    let gyro = layout.gyro.map(|c| c.map(&mut take));
    let accel = layout.accel.map(|c| c.map(&mut take));
    let extra = layout
        .extra
        .iter()
        .map(|&i| ExtraColumn {
            name: layout.names[i].clone(),
            values: take(i),
        })
        .collect();
    let source = RunSource {
        path: path.to_owned(),
        file_name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        sha256,
        size_bytes,
    };
    Ok(Run {
        source,
        time_s,
        sample_rate_hz,
        angles,
        gyro,
        accel,
        extra,
        sidecar,
        notices,
    })
}

/// The consuming side of one load.
struct Parse<'a> {
    path: &'a Path,
    bytes_total: u64,
    /// Bytes the decoded columns may take (`None`: no limit known).
    memory_limit: Option<u64>,
    notices: &'a mut Vec<String>,
}

impl Parse<'_> {
    /// Receives chunks until the final one; returns the hash and the parsed rows.
    fn run(
        mut self,
        pipe: &Pipe,
        progress: &mut dyn FnMut(LoadProgress) -> ControlFlow<()>,
    ) -> Result<(String, Rows), LoadError> {
        let mut chunk = self.recv(pipe, 1)?;
        let (layout, body_start) = self.header(&chunk.text)?;
        let mut rows = Rows::new(self.path, layout, 2);
        rows.feed(&chunk.text[body_start..])?;
        if chunk.sha256.is_none() {
            self.reserve(&mut rows, chunk.raw_done)?;
        }
        loop {
            if progress(LoadProgress {
                bytes_done: chunk.raw_done,
                bytes_total: self.bytes_total,
            })
            .is_break()
            {
                return Err(LoadError::Cancelled);
            }
            if let Some(sha256) = chunk.sha256 {
                return Ok((sha256, rows));
            }
            pipe.recycle(std::mem::take(&mut chunk.text));
            chunk = self.recv(pipe, rows.next_line)?;
            rows.feed(&chunk.text)?;
            // Checked again as the file streams: the first block's estimate can be low (a gzip
            // file's size says little about its text, and the decompressor reads ahead).
            self.estimate_fits(&rows, chunk.raw_done)?;
        }
    }

    /// The next text chunk; `next_line` is the line it starts with.
    fn recv(&self, pipe: &Pipe, next_line: usize) -> Result<TextChunk, LoadError> {
        let path = self.path.to_owned();
        match pipe.chunks.recv() {
            Ok(Chunk::Text(chunk)) => Ok(chunk),
            Ok(Chunk::Overlong(head)) => {
                let binary = memchr::memchr(0, &head).is_some() || std::str::from_utf8(&head).is_err();
                Err(if binary {
                    LoadError::NotText {
                        path,
                        line: next_line,
                    }
                } else {
                    LoadError::LineTooLong {
                        path,
                        line: next_line,
                        limit: stream::MAX_LINE_BYTES,
                    }
                })
            }
            Ok(Chunk::Failed(SourceError::Io(source))) => Err(LoadError::Io { path, source }),
            Ok(Chunk::Failed(SourceError::Gzip(detail))) => Err(LoadError::BadGzip { path, detail }),
            Err(_) => Err(LoadError::Io {
                path,
                source: std::io::Error::other("the reading thread stopped"),
            }),
        }
    }

    /// Reads the header line at the start of the first chunk; returns the layout and where the
    /// data starts. A UTF-8 byte-order mark is removed with a notice.
    fn header(&mut self, text: &[u8]) -> Result<(Layout, usize), LoadError> {
        let path = self.path;
        let start = if text.starts_with(b"\xEF\xBB\xBF") {
            self.notices.push(format!(
                "UTF-8 byte-order mark at the start of {} removed",
                path.display()
            ));
            3
        } else {
            0
        };
        let text = &text[start..];
        if text.trim_ascii().is_empty() {
            return Err(LoadError::Empty {
                path: path.to_owned(),
            });
        }
        let end = memchr::memchr(b'\n', text).unwrap_or(text.len());
        let line = text[..end].strip_suffix(b"\r").unwrap_or(&text[..end]);
        let line = match std::str::from_utf8(line) {
            Ok(line) if !line.contains('\0') => line,
            _ => {
                return Err(LoadError::NotText {
                    path: path.to_owned(),
                    line: 1,
                });
            }
        };
        let layout = Layout::parse(path, line)?;
        for &i in &layout.extra {
            self.notices
                .push(format!("unknown column '{}' kept and ignored", layout.names[i]));
        }
        Ok((layout, (start + end + 1).min(start + text.len())))
    }

    /// After the first chunk: estimates the rows of the whole file from its share of the file,
    /// refuses a run that would not fit in memory, and reserves the columns.
    ///
    /// # Errors
    /// [`LoadError::TooLarge`] when the estimated columns exceed the available memory.
    fn reserve(&self, rows: &mut Rows, raw_done: u64) -> Result<(), LoadError> {
        let estimate = self.estimate_fits(rows, raw_done)?;
        // Generous: untouched capacity costs address space only, and the columns are shrunk at
        // the end, whereas an estimate too small would copy every column once more.
        let room = (estimate * RESERVE_MARGIN) as usize + 1024;
        rows.reserve(room.saturating_sub(rows.len()));
        Ok(())
    }

    /// The estimated rows of the whole file (rows so far over the share of the file read), after
    /// checking that their columns fit in the memory limit.
    ///
    /// # Errors
    /// [`LoadError::TooLarge`] with the estimated and the available bytes.
    fn estimate_fits(&self, rows: &Rows, raw_done: u64) -> Result<f64, LoadError> {
        let parsed = rows.len().max(1) as f64;
        let share = raw_done.max(1) as f64 / self.bytes_total.max(1) as f64;
        let estimate = parsed / share.min(1.0);
        let needed_bytes = (estimate as u64).saturating_mul(rows.width() as u64 * 8);
        if let Some(available_bytes) = self.memory_limit
            && needed_bytes > available_bytes
        {
            return Err(LoadError::TooLarge {
                path: self.path.to_owned(),
                needed_bytes,
                available_bytes,
            });
        }
        Ok(estimate)
    }
}
