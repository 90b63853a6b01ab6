//! Wrapped angle columns: angle sensors and attitude loggers often write angles wrapped into
//! (-π, π] or [0, 2π), so a platform turning through ±π shows a step of almost ±2π between two
//! samples. The loader unwraps them here, after the time column's checks.
//!
//! # Rules
//! - A step between consecutive samples with `|step| > π` is a **wrap**: the whole turns
//!   (`2π round(step / 2π)`) are removed from it and from every later sample. This handles both
//!   conventions, and several turns at once.
//! - A step still larger than [`LoadOptions::max_angle_step_rad`](super::LoadOptions) (1 rad by
//!   default) after that is **refused** as [`LoadError::AngleJump`]: no stand moves a radian in one
//!   sample, so it is a recording fault, not motion. A step that is not finite (values near the
//!   largest `f64` of opposite signs) is refused the same way.
//! - A column with wraps is then shifted by whole turns so that its mean lies in [-π, π]; a column
//!   without wraps is left exactly as read. Whole turns change no rotation, so the block inputs
//!   computed from the angles do not change beyond rounding.
//! - Each unwrapped column gets one notice naming the column, the number of wraps and the file line
//!   of the first (the line of the sample after the step; row `i` is line `i + 2`).
//!
//! Units: rad. The columns are finite (the parser refused NaN and infinities); empty columns are
//! left alone.

use std::f64::consts::{PI, TAU};
use std::path::Path;

use super::LoadError;

/// The angle columns' header names, in [`super::Run::angles`] order.
pub(super) const ANGLE_NAMES: [&str; 3] = ["roll", "yaw", "pitch"];

/// What unwrapping found in one column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Wraps {
    /// Number of wrapping steps.
    count: usize,
    /// 0-based row of the sample after the first wrapping step.
    first_row: usize,
}

/// Unwraps the three angle columns in place and pushes a notice for each column that wrapped.
/// `columns` are the 0-based header columns of roll, yaw and pitch.
///
/// # Errors
/// [`LoadError::AngleJump`] at the first step (in column order roll, yaw, pitch) larger than
/// `max_step_rad` after removing whole turns.
pub(super) fn unwrap_angles(
    path: &Path,
    angles: &mut [Vec<f64>; 3],
    columns: [usize; 3],
    max_step_rad: f64,
    notices: &mut Vec<String>,
) -> Result<(), LoadError> {
    let file = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    for ((angle, name), column) in angles.iter_mut().zip(ANGLE_NAMES).zip(columns) {
        let wraps = unwrap_column(angle, max_step_rad).map_err(|(row, step_rad)| LoadError::AngleJump {
            path: path.to_owned(),
            line: row + 2,
            column: column + 1,
            name,
            step_rad,
            limit_rad: max_step_rad,
        })?;
        if let Some(w) = wraps {
            notices.push(format!(
                "column '{name}' wraps around a full turn {} time{} (the first at line {} of {file}): unwrapped",
                w.count,
                if w.count == 1 { "" } else { "s" },
                w.first_row + 2,
            ));
        }
    }
    Ok(())
}

/// Unwraps one column in place; `Ok(None)` when it has no wrap (then it is untouched).
///
/// # Errors
/// `(row, step)` of the first step larger than `max_step_rad` after removing whole turns (row of
/// the sample after the step; `step` as read, with the turns removed when finite).
fn unwrap_column(x: &mut [f64], max_step_rad: f64) -> Result<Option<Wraps>, (usize, f64)> {
    let mut turns = 0.0_f64;
    let mut wraps: Option<Wraps> = None;
    // Whole turns removed from each sample, kept as integers in f64 (exact below 2^53).
    let mut removed = Vec::new();
    for (i, w) in x.windows(2).enumerate() {
        let step = w[1] - w[0];
        let k = if step.abs() > PI {
            (step / TAU).round()
        } else {
            0.0
        };
        let rest = step - TAU * k;
        if !(rest.is_finite() && rest.abs() <= max_step_rad) {
            return Err((i + 1, if rest.is_finite() { rest } else { step }));
        }
        if k != 0.0 {
            turns += k;
            if let Some(w) = &mut wraps {
                w.count += 1;
            } else {
                removed.reserve(x.len());
                removed.resize(i + 1, 0.0);
                wraps = Some(Wraps {
                    count: 1,
                    first_row: i + 1,
                });
            }
        }
        if wraps.is_some() {
            removed.push(turns);
        }
    }
    let Some(wraps) = wraps else {
        return Ok(None);
    };
    let unwrapped = |(v, t): (&f64, &f64)| v - TAU * t;
    let mean = x.iter().zip(&removed).map(unwrapped).sum::<f64>() / x.len() as f64;
    let shift = (mean / TAU).round();
    for (v, t) in x.iter_mut().zip(&removed) {
        *v -= TAU * (t + shift);
    }
    Ok(Some(wraps))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wrapped_pi(v: f64) -> f64 {
        let w = v.rem_euclid(TAU);
        if w > PI { w - TAU } else { w }
    }

    #[test]
    fn both_conventions_unwrap_to_the_original() {
        // Several turns up, then back down through zero.
        let original: Vec<f64> = (0..2000)
            .map(|i| 9.0 * (f64::from(i) * 0.003).sin() + 0.4)
            .collect();
        for convention in [wrapped_pi as fn(f64) -> f64, |v: f64| v.rem_euclid(TAU)] {
            let mut x: Vec<f64> = original.iter().map(|&v| convention(v)).collect();
            let wraps = unwrap_column(&mut x, 1.0).unwrap().unwrap();
            assert!(wraps.count >= 4, "{wraps:?}");
            let err = x
                .iter()
                .zip(&original)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-12, "{err}");
        }
    }

    #[test]
    fn a_column_without_wraps_is_untouched_and_a_jump_is_refused() {
        let mut x = vec![3.0, 3.1, 3.2, 3.1];
        assert_eq!(unwrap_column(&mut x, 1.0), Ok(None));
        assert_eq!(x, [3.0, 3.1, 3.2, 3.1]);
        let mut jump = vec![0.0, 0.1, 1.6, 1.7];
        let (row, step) = unwrap_column(&mut jump, 1.0).unwrap_err();
        assert_eq!(row, 2);
        assert!((step - 1.5).abs() < 1e-12);
        // 2π + 1.5: a wrap and a jump together are still a jump.
        let mut both = vec![0.0, 0.1, 0.1 + TAU + 1.5];
        let (row, step) = unwrap_column(&mut both, 1.0).unwrap_err();
        assert_eq!(row, 2);
        assert!((step - 1.5).abs() < 1e-12);
        let mut huge = vec![-f64::MAX, f64::MAX];
        assert_eq!(unwrap_column(&mut huge, 1.0), Err((1, f64::INFINITY)));
    }

    #[test]
    fn the_first_wrap_is_located() {
        let mut x = vec![3.0, 3.1, -3.1, -3.0, 3.1];
        let wraps = unwrap_column(&mut x, 1.0).unwrap().unwrap();
        assert_eq!(
            wraps,
            Wraps {
                count: 2,
                first_row: 2
            }
        );
        assert!((x[2] - (TAU - 3.1)).abs() < 1e-12, "{x:?}");
    }
}
