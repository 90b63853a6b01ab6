//! Tick marks on 1-2-5 steps for linear axes (time, and the time series' values).
//!
//! `egui_plot`'s default spacer steps by powers of ten and labels a step only when its marks are
//! at least 60 points apart, so a two-minute record across 600 points shows one label ("100"): 10 s
//! is 50 points, 100 s the next step. Here the three line strengths are the 1-2-5 steps nearest
//! the finest grid spacing, about 3x that, and the first at least 10x it (80 points at egui's 8
//! point grid: labelled at full strength), nested so that two strengths' labels never crowd each
//! other, and two minutes carry labels every 20 s.

use egui_plot::{GridInput, GridMark, uniform_grid_spacer};

/// The smallest step of the form `{1, 2, 5} x 10^n` at or above `x` (`x > 0`, finite).
#[must_use]
pub fn nice_at_least(x: f64) -> f64 {
    let power = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * power)
}

/// The steps `{1, 2, 5} x 10^n` that divide `c` (itself such a step) a whole number of times,
/// ascending, from `c / 100` to `c`.
fn nice_divisors(c: f64) -> Vec<f64> {
    let top = c.log10().floor();
    let mut out: Vec<f64> = (-2..=0)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powf(top + f64::from(k))))
        .filter(|&v| {
            let ratio = c / v;
            v <= c * (1.0 + 1e-12) && (ratio - ratio.round()).abs() < 1e-9 * ratio
        })
        .collect();
    out.sort_by(f64::total_cmp);
    out
}

/// The three step sizes for the finest step `base` (`egui_plot`'s `base_step_size`), nested (each
/// divides the next, so the labels of two strengths never crowd each other).
#[must_use]
pub fn nice_steps(base: f64) -> [f64; 3] {
    if !(base.is_finite() && base > 0.0) {
        return [1.0, 2.0, 10.0];
    }
    let coarse = nice_at_least(10.0 * base);
    let divisors = nice_divisors(coarse);
    let fine = divisors
        .iter()
        .copied()
        .find(|&v| v >= base * (1.0 - 1e-12))
        .unwrap_or(coarse);
    let target = (fine * coarse).sqrt().log10();
    let middle = divisors
        .iter()
        .copied()
        .filter(|&v| v >= fine && ((v / fine) - (v / fine).round()).abs() < 1e-9 * (v / fine))
        .min_by(|a, b| (a.log10() - target).abs().total_cmp(&(b.log10() - target).abs()))
        .unwrap_or(coarse);
    [fine, middle, coarse]
}

/// A tick's label with as many decimals as its step needs (`egui_plot`'s default rounds the
/// decimals of a 0.5 step to none, labelling 0.5 as "0" and -0.5 as "-0").
#[must_use]
pub fn nice_label(mark: GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let step = mark.step_size.abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 15.0) as usize
    } else {
        0
    };
    // A mark at zero computed as -1e-17 reads "0", not "-0".
    let value = if mark.value.abs() < 1e-9 * step {
        0.0
    } else {
        mark.value
    };
    format!("{value:.decimals$}")
}

/// The grid spacer of [`nice_steps`].
pub fn nice_grid_spacer<'a>() -> impl Fn(GridInput) -> Vec<GridMark> + 'a {
    uniform_grid_spacer(|input: GridInput| nice_steps(input.base_step_size))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_carry_the_decimals_of_their_step() {
        let label = |value, step_size| nice_label(GridMark { value, step_size }, &(0.0..=1.0));
        assert_eq!(label(0.5, 0.5), "0.5");
        assert_eq!(label(-0.5, 0.5), "-0.5");
        assert_eq!(label(-1e-17, 0.2), "0.0");
        assert_eq!(label(40.0, 20.0), "40");
        assert_eq!(label(0.05, 0.05), "0.05");
        assert_eq!(label(3.0, 1.0), "3");
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs()
    }

    fn close_all(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(&b).all(|(x, y)| close(*x, *y))
    }

    #[test]
    fn steps_are_1_2_5_and_the_coarsest_is_labelled() {
        assert!(close(nice_at_least(1.0), 1.0));
        assert!(close(nice_at_least(1.86), 2.0));
        assert!(close(nice_at_least(2.5), 5.0));
        assert!(close(nice_at_least(6.0), 10.0));
        assert!(close(nice_at_least(0.037), 0.05));
        // 131 s over 600 points: the finest grid line every 8 points is 1.75 s.
        let base = 131.0 / 600.0 * 8.0;
        assert!(close_all(nice_steps(base), [2.0, 10.0, 20.0]));
        // An angle axis of about 1 rad over 230 points: labelled every 0.5 and 0.1, not 0.2.
        assert!(close_all(nice_steps(0.035), [0.05, 0.1, 0.5]));
        for base in [1e-4, 0.003, 0.7, 1.0, 13.0, 4e5] {
            let [a, b, c] = nice_steps(base);
            assert!(
                a >= base && a <= b && b <= c && c >= 10.0 * base,
                "{base}: {a} {b} {c}"
            );
            for ratio in [b / a, c / b] {
                assert!(
                    (ratio - ratio.round()).abs() < 1e-9,
                    "{base}: {a} {b} {c} not nested"
                );
            }
            for s in [a, b, c] {
                let mantissa = s / 10f64.powf(s.log10().floor());
                assert!([1.0, 2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-9), "{s}");
            }
            assert!(c <= 50.0 * base, "{base}: labels not too sparse ({c})");
        }
    }
}
