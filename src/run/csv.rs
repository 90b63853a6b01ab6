//! The data rows: chunks of whole lines are cut into pieces at newlines, the pieces are parsed in
//! parallel (rayon, [`super::piece`]) into per-piece column vectors, then appended in order to the
//! run's columns.
//!
//! Each piece reports faults relative to its own first line; the merge adds the lines of the
//! pieces before it, so errors name the exact line of the file. Blank lines are allowed only at
//! the end: a blank line followed by data, even in a later piece or chunk, is an error.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::LoadError;
use super::header::Layout;
use super::piece::{Fault, Piece, parse_piece};
use super::stream::MAX_LINE_BYTES;

/// Pieces per rayon thread in one chunk, for load balance.
const PIECES_PER_THREAD: usize = 4;
/// Accumulates the columns of a run from successive chunks.
pub(super) struct Rows {
    path: PathBuf,
    layout: Layout,
    /// 1-based line number of the next line to be fed.
    pub next_line: usize,
    /// Absolute line of the first blank line of the current trailing run of blank lines.
    pending_blank: Option<usize>,
    /// One vector per header column.
    cols: Vec<Vec<f64>>,
    /// Column buffers of the pieces, reused from chunk to chunk.
    spare: Vec<Vec<Vec<f64>>>,
}

impl Rows {
    /// An empty accumulator whose first line will be `first_line`.
    pub fn new(path: &Path, layout: Layout, first_line: usize) -> Self {
        let cols = vec![Vec::new(); layout.width()];
        Self {
            path: path.to_owned(),
            layout,
            next_line: first_line,
            pending_blank: None,
            cols,
            spare: Vec::new(),
        }
    }

    /// The layout and one vector per header column, without spare capacity.
    pub fn into_parts(mut self) -> (Layout, Vec<Vec<f64>>) {
        self.cols.iter_mut().for_each(Vec::shrink_to_fit);
        (self.layout, self.cols)
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.cols.len()
    }

    /// Rows so far.
    pub fn len(&self) -> usize {
        self.cols.first().map_or(0, Vec::len)
    }

    /// Reserves room for `rows` more rows in every column.
    pub fn reserve(&mut self, rows: usize) {
        for col in &mut self.cols {
            col.reserve_exact(rows);
        }
    }

    /// Parses whole lines (the last may lack its newline) and appends them.
    ///
    /// # Errors
    /// [`LoadError::NotText`], [`LoadError::BlankLine`], [`LoadError::WrongFieldCount`],
    /// [`LoadError::NotNumeric`], [`LoadError::NonFinite`], at the first bad line of the text.
    pub fn feed(&mut self, text: &[u8]) -> Result<(), LoadError> {
        let width = self.layout.width();
        let pieces = split_at_newlines(text, rayon::current_num_threads() * PIECES_PER_THREAD);
        let mut buffers = std::mem::take(&mut self.spare);
        buffers.resize_with(buffers.len().max(pieces.len()), || vec![Vec::new(); width]);
        let parsed: Vec<Result<Piece, (usize, Fault)>> = pieces
            .par_iter()
            .zip(buffers.par_iter_mut())
            .map(|(p, cols)| parse_piece(p, cols))
            .collect();
        for piece in parsed {
            if let Some(line) = self.pending_blank
                && piece.as_ref().map_or(true, |p| p.rows > 0)
            {
                return Err(self.error(line, Fault::Blank));
            }
            let piece = piece.map_err(|(rel, fault)| self.error(self.next_line + rel, fault))?;
            let trailing_blank = piece.trailing_blank.map(|rel| self.next_line + rel);
            self.pending_blank = if piece.rows > 0 {
                trailing_blank
            } else {
                self.pending_blank.or(trailing_blank)
            };
            self.next_line += piece.lines;
        }
        // All pieces are good: append them column by column, the columns in parallel.
        let parts = &buffers[..pieces.len()];
        self.cols.par_iter_mut().enumerate().for_each(|(j, all)| {
            for part in parts {
                all.extend_from_slice(&part[j]);
            }
        });
        buffers.iter_mut().flatten().for_each(Vec::clear);
        self.spare = buffers;
        Ok(())
    }

    /// The load error for `fault` on 1-based `line`.
    fn error(&self, line: usize, fault: Fault) -> LoadError {
        let path = self.path.clone();
        let name = |column: usize| self.layout.names.get(column).cloned().unwrap_or_default();
        match fault {
            Fault::NotText => LoadError::NotText { path, line },
            Fault::Blank => LoadError::BlankLine { path, line },
            Fault::TooLong => LoadError::LineTooLong {
                path,
                line,
                limit: MAX_LINE_BYTES,
            },
            Fault::FieldCount { found, unterminated } => {
                let expected = self.layout.width();
                LoadError::WrongFieldCount {
                    path,
                    line,
                    expected,
                    found,
                    truncated: unterminated && found < expected,
                }
            }
            Fault::NotNumeric { column, cell } => LoadError::NotNumeric {
                path,
                line,
                column: column + 1,
                name: name(column),
                cell,
            },
            Fault::NonFinite { column, cell } => LoadError::NonFinite {
                path,
                line,
                column: column + 1,
                name: name(column),
                cell,
            },
        }
    }
}

/// Cuts `text` into about `n` pieces, each ending just after a newline (the last at the end).
fn split_at_newlines(text: &[u8], n: usize) -> Vec<&[u8]> {
    let target = text.len() / n.max(1) + 1;
    let mut pieces = Vec::with_capacity(n + 1);
    let mut rest = text;
    while rest.len() > target {
        let Some(nl) = memchr::memchr(b'\n', &rest[target..]) else {
            break;
        };
        let (piece, tail) = rest.split_at(target + nl + 1);
        pieces.push(piece);
        rest = tail;
    }
    if !rest.is_empty() {
        pieces.push(rest);
    }
    pieces
}
