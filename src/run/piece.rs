//! One piece of whole lines parsed into column vectors, on one rayon thread.
//!
//! Lines go through the fast path ([`super::number::fast_row`]) first; a line it does not take is
//! parsed by `str::parse` here, which words the fault. Cells are trimmed of spaces and tabs and of
//! one pair of enclosing double quotes (`"0.5"`, as some loggers write), a trailing `\r` (CRLF) is
//! dropped, numbers may carry a leading `+` and exponents. NaN and
//! infinities are refused. Line numbers in faults are relative to the piece.

use super::number::fast_row;
use super::stream::MAX_LINE_BYTES;

/// Longest cell kept in an error message, in characters.
const MAX_CELL_CHARS: usize = 64;

/// What went wrong on a line, relative to its piece.
#[derive(Debug)]
pub(super) enum Fault {
    /// A NUL byte or invalid UTF-8.
    NotText,
    /// A blank line followed by data.
    Blank,
    /// Longer than [`MAX_LINE_BYTES`].
    TooLong,
    /// Not as many fields as header columns; `unterminated`: the file's last line, no newline.
    FieldCount { found: usize, unterminated: bool },
    /// Cell `column` (0-based) is not a number.
    NotNumeric { column: usize, cell: String },
    /// Cell `column` (0-based) is NaN or infinite.
    NonFinite { column: usize, cell: String },
}

/// What parsing one piece found (its values are in its column buffers).
pub(super) struct Piece {
    /// Lines in the piece, blank ones included.
    pub lines: usize,
    /// Data rows parsed.
    pub rows: usize,
    /// Relative line of the first of the blank lines that end the piece.
    pub trailing_blank: Option<usize>,
}

/// Parses one piece of whole lines into `cols` (one empty vector per column).
///
/// The fast path takes only ASCII digits, signs, `.`, `e`, blanks, commas and line ends, so the
/// text check (no NUL, valid UTF-8) is needed only on the lines it leaves to the general parser.
///
/// # Errors
/// The first bad line's relative number and its [`Fault`].
pub(super) fn parse_piece(bytes: &[u8], cols: &mut [Vec<f64>]) -> Result<Piece, (usize, Fault)> {
    let width = cols.len();
    for col in cols.iter_mut() {
        col.reserve(bytes.len() / (2 * width) + 1);
    }
    let mut lines = 0;
    let mut rows = 0;
    let mut trailing_blank = None;
    let mut pos = 0;
    while pos < bytes.len() {
        if let Some(next) = fast_row(bytes, pos, cols) {
            if let Some(blank) = trailing_blank {
                return Err((blank, Fault::Blank));
            }
            pos = next;
            rows += 1;
            lines += 1;
            continue;
        }
        for col in cols.iter_mut() {
            col.truncate(rows);
        }
        let (line, next, terminated) = match memchr::memchr(b'\n', &bytes[pos..]) {
            Some(nl) => (&bytes[pos..pos + nl], pos + nl + 1, true),
            None => (&bytes[pos..], bytes.len(), false),
        };
        pos = next;
        let line = match std::str::from_utf8(line) {
            Ok(line) if !line.contains('\0') => line,
            _ => return Err((lines, Fault::NotText)),
        };
        let line = line.strip_suffix('\r').unwrap_or(line);
        if line.len() > MAX_LINE_BYTES {
            return Err((lines, Fault::TooLong));
        }
        if line.trim_ascii().is_empty() {
            trailing_blank = trailing_blank.or(Some(lines));
        } else {
            if let Some(blank) = trailing_blank {
                return Err((blank, Fault::Blank));
            }
            parse_row(line, cols)
                .map_err(|fault| (lines, truncation_first(line, fault, !terminated, width)))?;
            rows += 1;
        }
        lines += 1;
    }
    Ok(Piece {
        lines,
        rows,
        trailing_blank,
    })
}

/// Parses one non-blank line and pushes one value onto each column.
fn parse_row(line: &str, cols: &mut [Vec<f64>]) -> Result<(), Fault> {
    let mut found = 0;
    for (column, cell) in line.split(',').enumerate() {
        found += 1;
        let Some(col) = cols.get_mut(column) else { continue };
        let cell = cell.trim_ascii();
        match super::header::unquote(cell).trim_ascii().parse::<f64>() {
            Ok(v) if v.is_finite() => col.push(v),
            Ok(_) => {
                return Err(Fault::NonFinite {
                    column,
                    cell: clip(cell),
                });
            }
            Err(_) => {
                return Err(Fault::NotNumeric {
                    column,
                    cell: clip(cell),
                });
            }
        }
    }
    if found == cols.len() {
        Ok(())
    } else {
        Err(Fault::FieldCount {
            found,
            unterminated: false,
        })
    }
}

/// On an unterminated (last) line that is short, the short count explains a bad cell best: the
/// recording was cut off mid-number.
fn truncation_first(line: &str, fault: Fault, unterminated: bool, width: usize) -> Fault {
    if !unterminated {
        return fault;
    }
    let found = line.split(',').count();
    if found < width {
        Fault::FieldCount { found, unterminated }
    } else {
        fault
    }
}

/// A cell cut to [`MAX_CELL_CHARS`] characters for an error message.
fn clip(cell: &str) -> String {
    cell.chars().take(MAX_CELL_CHARS).collect()
}
