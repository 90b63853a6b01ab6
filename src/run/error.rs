//! [`LoadError`]: everything that can be wrong with a run file or its sidecar.
//!
//! Each variant carries structured data (path, 1-based line, 1-based column number and name where
//! they apply) so that the GUI can point at the place and the CLI can print it. `Display` is one
//! line in the compiler's `file:line:column: what is wrong` style, for example
//! `cruise.csv:1042:5 (column 'yaw'): not a number: "1.2.3"`.

use std::path::PathBuf;

/// Why a run could not be loaded. Never produced by a panic: every bad input maps to one variant.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The file (or its sidecar) could not be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file that failed.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The path names a directory or another non-regular file.
    #[error("{}: not a file (a directory?)", path.display())]
    NotAFile {
        /// The path given.
        path: PathBuf,
    },
    /// The file is binary: a NUL byte or invalid UTF-8 on this line.
    #[error("{}:{line}: not text (NUL byte or invalid UTF-8): is this really a CSV run?", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
        /// 1-based line of the first bad byte.
        line: usize,
    },
    /// The file starts with the gzip magic bytes but cannot be decompressed.
    #[error("{}: unreadable gzip: {detail}", path.display())]
    BadGzip {
        /// The file.
        path: PathBuf,
        /// The decompressor's complaint.
        detail: String,
    },
    /// The file holds no header line (zero bytes, or only blank lines).
    #[error("{}: empty file: no header line", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A required column, or a column needed to complete a block, is missing from the header.
    #[error(
        "{}:{header_line}: missing column '{column}': {why}{}",
        path.display(),
        near_miss.as_ref().map_or(String::new(), |(col, name)| format!(
            " (column {col} is named '{name}': names are lower case, as in the contract)"
        ))
    )]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The missing column's name.
        column: &'static str,
        /// Line of the header (always 1).
        header_line: usize,
        /// Why it is needed.
        why: &'static str,
        /// A header name equal to the missing one but for case, and its column (1-based).
        near_miss: Option<(usize, String)>,
    },
    /// A header cell is empty (for example a trailing comma).
    #[error("{}:1:{column}: column {column} has no name", path.display())]
    EmptyColumnName {
        /// The file.
        path: PathBuf,
        /// 1-based column number.
        column: usize,
    },
    /// Two header cells carry the same name.
    #[error("{}:1:{} (column '{name}'): duplicate column, also column {}", path.display(), columns.1, columns.0)]
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// The repeated name.
        name: String,
        /// The two 1-based column numbers.
        columns: (usize, usize),
    },
    /// The header has no comma but another delimiter (`;` or tab).
    #[error("{}:1: columns are separated by {found:?}, not by ',' (the run format is comma-separated)", path.display())]
    WrongDelimiter {
        /// The file.
        path: PathBuf,
        /// The delimiter found.
        found: char,
    },
    /// A cell is not a decimal number.
    #[error("{}:{line}:{column} (column '{name}'): not a number: {cell:?}", path.display())]
    NotNumeric {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column number.
        column: usize,
        /// The column's header name.
        name: String,
        /// The cell as written (trimmed, cut to 64 characters).
        cell: String,
    },
    /// A cell is `nan`, `inf` or `-inf` (any spelling Rust's float parser accepts).
    #[error("{}:{line}:{column} (column '{name}'): not a finite number: {cell:?}", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column number.
        column: usize,
        /// The column's header name.
        name: String,
        /// The cell as written (trimmed).
        cell: String,
    },
    /// A data line has more or fewer fields than the header.
    #[error("{}:{line}: line {line} has {found} fields, header has {expected}{}", path.display(),
        if *truncated { " (truncated last line?)" } else { "" })]
    WrongFieldCount {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// Number of header columns.
        expected: usize,
        /// Number of fields on the line.
        found: usize,
        /// The line is the file's last one and is short: the recording was probably cut off.
        truncated: bool,
    },
    /// A blank line is followed by more data (blank lines are allowed only at the end).
    #[error("{}:{line}: blank line inside the data (only trailing blank lines are allowed)", path.display())]
    BlankLine {
        /// The file.
        path: PathBuf,
        /// 1-based line of the blank line.
        line: usize,
    },
    /// A line is longer than any run row could be (probably not a CSV file).
    #[error("{}:{line}: line longer than {limit} bytes: is this really a CSV run?", path.display())]
    LineTooLong {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The limit in bytes.
        limit: usize,
    },
    /// `t` did not strictly increase from the previous line to this one.
    #[error("{}:{line}:{column} (column 't'): time not increasing: t = {t} after {t_prev}", path.display())]
    TimeNotIncreasing {
        /// The file.
        path: PathBuf,
        /// 1-based line of the offending sample.
        line: usize,
        /// 1-based column number of `t`.
        column: usize,
        /// Time on the previous line, s.
        t_prev: f64,
        /// Time on this line, s.
        t: f64,
    },
    /// A time step deviates more than the tolerance (1 %) from the nominal (median) step.
    #[error(
        "{}:{line}:{column} (column 't'): irregular sampling: a step of {} s, {} % off the \
         nominal {} s (the median step; at most {} % is accepted){}",
        path.display(),
        significant(*dt, 7),
        significant(100.0 * (dt - nominal_dt).abs() / nominal_dt, 4),
        significant(*nominal_dt, 7),
        significant(100.0 * tolerance, 4),
        missing_samples_hint(*dt, *nominal_dt, *tolerance)
    )]
    IrregularSampling {
        /// The file.
        path: PathBuf,
        /// 1-based line at the end of the bad step.
        line: usize,
        /// 1-based column number of `t`.
        column: usize,
        /// The step, s.
        dt: f64,
        /// The nominal step (median of the first steps), s.
        nominal_dt: f64,
        /// The relative deviation accepted.
        tolerance: f64,
    },
    /// The time column increases uniformly but spans no finite, positive duration in floating
    /// point (steps so small the rate overflows, or a span beyond the largest number).
    #[error("{}:2:{column} (column 't'): time runs from {first:e} to {last:e} s: no finite sample rate", path.display())]
    TimeSpan {
        /// The file.
        path: PathBuf,
        /// 1-based column number of `t`.
        column: usize,
        /// First time, s.
        first: f64,
        /// Last time, s.
        last: f64,
    },
    /// An angle steps further between two samples than any stand moves, after removing whole
    /// turns (wraps): a recording fault.
    #[error("{}:{line}:{column} (column '{name}'): angle jumps by {step_rad:.3} rad in one sample \
        (more than {limit_rad} rad, and not a wrap of 2 pi): a recording fault?", path.display())]
    AngleJump {
        /// The file.
        path: PathBuf,
        /// 1-based line of the sample after the jump.
        line: usize,
        /// 1-based column number of the angle.
        column: usize,
        /// The angle's header name (`roll`, `yaw` or `pitch`).
        name: &'static str,
        /// The step with whole turns removed, rad.
        step_rad: f64,
        /// The largest step accepted, rad.
        limit_rad: f64,
    },
    /// Fewer data rows than the minimum.
    #[error("{}: {n} samples, at least {min} needed", path.display())]
    TooFewSamples {
        /// The file.
        path: PathBuf,
        /// Rows found.
        n: usize,
        /// Rows needed.
        min: usize,
    },
    /// The sidecar is not valid JSON, or a field has the wrong type.
    #[error("{}:{line}:{column}: {detail}", path.display())]
    Sidecar {
        /// The sidecar file.
        path: PathBuf,
        /// 1-based line (`serde_json`'s).
        line: usize,
        /// 1-based column (`serde_json`'s).
        column: usize,
        /// What is wrong.
        detail: String,
    },
    /// A sidecar field has the right type but an impossible value.
    #[error("{}: field '{field}': {detail}", path.display())]
    SidecarValue {
        /// The sidecar file.
        path: PathBuf,
        /// The field's name.
        field: &'static str,
        /// What is wrong.
        detail: String,
    },
    /// The decoded run would not fit in the available memory.
    #[error("{}: the decoded run needs about {} MB, only {} MB available", path.display(),
        needed_bytes / 1_000_000, available_bytes / 1_000_000)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Estimated bytes of the decoded columns.
        needed_bytes: u64,
        /// Bytes available (`MemAvailable` or the limit in the options).
        available_bytes: u64,
    },
    /// The progress callback asked to stop.
    #[error("loading cancelled")]
    Cancelled,
}

/// `x` to `digits` significant digits, without trailing zeros (`0.0020299999999999763` to 7 is
/// `0.00203`; a deviation of 1.0043 % to 4 is `1.004`, not a contradicting `1`).
/// For a step that is a whole number `k >= 2` of nominal steps (within the tolerance), the
/// words that say `k - 1` samples are missing and what can be done; empty otherwise. The
/// spectra assume uniform sampling, so a gap is not bridged silently: the user cuts the record
/// there or fills the gap and says so.
fn missing_samples_hint(dt: f64, nominal_dt: f64, tolerance: f64) -> String {
    let ratio = dt / nominal_dt;
    let k = ratio.round();
    if !(2.0..=1e6).contains(&k) || (ratio - k).abs() > tolerance * k {
        return String::new();
    }
    let missing = k as u64 - 1;
    let samples = if missing == 1 { "sample" } else { "samples" };
    format!(
        ": {missing} {samples} missing there (the step is {k} nominal steps); the spectra need \
         uniform sampling: cut the record at the gap, or fill it (interpolated, and say so) \
         before loading"
    )
}

fn significant(x: f64, digits: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let decimals = (digits - 1 - x.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}
