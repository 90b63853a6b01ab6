//! The header line: which column holds what.
//!
//! Names are case-sensitive and exact after trimming spaces and one pair of enclosing double
//! quotes (RFC 4180: `"t"` is `t`): `t`, `roll`, `yaw`, `pitch`, `gx`, `gy`, `gz`, `ax`, `ay`, `az`.
//! Column order is free; other names are kept as extra columns. A missing name that is present
//! in another case (`Roll`) is named in the error: not taken, since `T` is as often a
//! temperature as a time.

use std::path::Path;

use super::LoadError;

/// Required columns: time and the three platform angles.
const REQUIRED: [&str; 4] = ["t", "roll", "yaw", "pitch"];
/// Gyro block columns.
const GYRO: [&str; 3] = ["gx", "gy", "gz"];
/// Accelerometer block columns.
const ACCEL: [&str; 3] = ["ax", "ay", "az"];

/// Where each known quantity sits in a row (0-based column indices).
#[derive(Clone, Debug)]
pub(super) struct Layout {
    /// Header names, trimmed, in file order.
    pub names: Vec<String>,
    /// Column of `t`.
    pub t: usize,
    /// Columns of roll, yaw, pitch.
    pub angles: [usize; 3],
    /// Columns of gx, gy, gz when the gyro block is present.
    pub gyro: Option<[usize; 3]>,
    /// Columns of ax, ay, az when the accelerometer block is present.
    pub accel: Option<[usize; 3]>,
    /// Columns with other names, in file order.
    pub extra: Vec<usize>,
}

impl Layout {
    /// Reads a header line (without its line ending, BOM already removed).
    ///
    /// # Errors
    /// [`LoadError::WrongDelimiter`] when there is no comma but a `;` or tab,
    /// [`LoadError::EmptyColumnName`], [`LoadError::DuplicateColumn`], and
    /// [`LoadError::MissingColumn`] for a missing required column, a partial block, or no block.
    pub fn parse(path: &Path, line: &str) -> Result<Self, LoadError> {
        if !line.contains(',')
            && let Some(found) = [';', '\t'].into_iter().find(|&c| line.contains(c))
        {
            return Err(LoadError::WrongDelimiter {
                path: path.to_owned(),
                found,
            });
        }
        let names: Vec<String> = line
            .split(',')
            .map(|n| unquote(n.trim()).trim().to_owned())
            .collect();
        for (i, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(LoadError::EmptyColumnName {
                    path: path.to_owned(),
                    column: i + 1,
                });
            }
            if let Some(first) = names[..i].iter().position(|n| n == name) {
                return Err(LoadError::DuplicateColumn {
                    path: path.to_owned(),
                    name: name.clone(),
                    columns: (first + 1, i + 1),
                });
            }
        }
        let find = |wanted: &str| names.iter().position(|n| n == wanted);
        let missing = |column: &'static str, why| LoadError::MissingColumn {
            path: path.to_owned(),
            column,
            header_line: 1,
            why,
            near_miss: names
                .iter()
                .position(|n| n.eq_ignore_ascii_case(column))
                .map(|i| (i + 1, names[i].clone())),
        };
        let mut required = [0; 4];
        for (slot, name) in required.iter_mut().zip(REQUIRED) {
            *slot = find(name).ok_or_else(|| missing(name, "every run needs t, roll, yaw and pitch"))?;
        }
        let block = |cols: [&'static str; 3], why| -> Result<Option<[usize; 3]>, LoadError> {
            let found = cols.map(find);
            if found.iter().all(Option::is_none) {
                return Ok(None);
            }
            match found.iter().zip(cols).find(|(f, _)| f.is_none()) {
                Some((_, name)) => Err(missing(name, why)),
                None => Ok(Some(found.map(Option::unwrap_or_default))),
            }
        };
        let gyro = block(GYRO, "the gyro block needs all of gx, gy, gz")?;
        let accel = block(ACCEL, "the accelerometer block needs all of ax, ay, az")?;
        if gyro.is_none() && accel.is_none() {
            return Err(missing(
                "gx",
                "no sensor block: a run needs gx, gy, gz (gyro) and/or ax, ay, az (accelerometer)",
            ));
        }
        let known: Vec<usize> = required
            .iter()
            .chain(gyro.iter().flatten())
            .chain(accel.iter().flatten())
            .copied()
            .collect();
        let extra = (0..names.len()).filter(|i| !known.contains(i)).collect();
        let [t, roll, yaw, pitch] = required;
        Ok(Self {
            names,
            t,
            angles: [roll, yaw, pitch],
            gyro,
            accel,
            extra,
        })
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.names.len()
    }
}

/// `text` without one pair of enclosing double quotes (RFC 4180 quoting of a header name or a
/// number cell), else as it is.
pub(super) fn unquote(text: &str) -> &str {
    text.strip_prefix('"')
        .and_then(|t| t.strip_suffix('"'))
        .unwrap_or(text)
}
