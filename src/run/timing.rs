//! The time column's checks: strictly increasing, uniformly sampled.
//!
//! The nominal step is the median of the first [`NOMINAL_STEPS`] steps (robust to a few bad
//! ones); every step of the file must then lie within the tolerance (1 % by default) of it. Row
//! `i` (0-based) of the data is line `i + 2` of the file: the header is line 1, and blank lines
//! are only allowed after the last row.

use std::path::Path;

use super::LoadError;

/// How many leading steps the nominal step is the median of.
pub const NOMINAL_STEPS: usize = 4096;

/// The file line of 0-based data row `row`.
fn line_of_row(row: usize) -> usize {
    row + 2
}

/// The median of the first [`NOMINAL_STEPS`] steps of `t` (0 when `t` has fewer than 2 samples).
#[must_use]
pub fn nominal_step(t: &[f64]) -> f64 {
    let mut steps: Vec<f64> = t.windows(2).take(NOMINAL_STEPS).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return 0.0;
    }
    let mid = steps.len() / 2;
    let (_, median, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    *median
}

/// Checks `t` (finite values, at least two) and returns the sample rate `(n-1)/(t_last-t_first)`.
///
/// # Errors
/// [`LoadError::TimeNotIncreasing`] at the first step that is not positive,
/// [`LoadError::IrregularSampling`] at the first step more than `tolerance` (relative) away from
/// the nominal step, whichever comes first in the file; [`LoadError::TimeSpan`] when the span
/// gives no finite positive rate. `t_column` is the 0-based column of `t`.
pub(super) fn check_time(path: &Path, t: &[f64], t_column: usize, tolerance: f64) -> Result<f64, LoadError> {
    let nominal = nominal_step(t);
    let limit = tolerance * nominal;
    for (i, w) in t.windows(2).enumerate() {
        let dt = w[1] - w[0];
        let line = line_of_row(i + 1);
        let column = t_column + 1;
        if dt.is_nan() || dt <= 0.0 {
            return Err(LoadError::TimeNotIncreasing {
                path: path.to_owned(),
                line,
                column,
                t_prev: w[0],
                t: w[1],
            });
        }
        // With a non-positive nominal step, a non-increasing step comes first and is the error.
        if nominal > 0.0 && (dt - nominal).abs() > limit {
            return Err(LoadError::IrregularSampling {
                path: path.to_owned(),
                line,
                column,
                dt,
                nominal_dt: nominal,
                tolerance,
            });
        }
    }
    let (Some(&first), Some(&last)) = (t.first(), t.last()) else {
        return Ok(0.0);
    };
    let rate = (t.len() - 1) as f64 / (last - first);
    if t.len() > 1 && !(rate.is_finite() && rate > 0.0) {
        return Err(LoadError::TimeSpan {
            path: path.to_owned(),
            column: t_column + 1,
            first,
            last,
        });
    }
    Ok(rate)
}
