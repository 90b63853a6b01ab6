//! Weights no more conservative than the estimate's own scatter.
//!
//! The weights say how far each bin's estimate may stray: `Omega_i = dof S_uu / S_psi,ii`, with
//! `S_psi` the `H1` residual. Part of that residual need not scatter the estimate at all. A
//! system whose response turns across a Welch bin (a delay `tau`: `2 pi tau df` per bin) leaves
//! in the residual the inputs' content off the bin's centre that the inputs at the centre do not
//! explain; its mean on the estimate is the offset matrix's term, which the move takes out
//! (`align`), and the rest is orthogonal to the inputs over the segments. With strong motion and
//! a delay of milliseconds it dominates the residual of a low-noise gyro: measured on an
//! independent simulator, a chi2 per bin of 0.03-0.3 of its expectation below 5 Hz (0.8-1.2 on
//! the same runs at `tau = 0`) and `K` deviations 1.5-3 times too wide.
//!
//! [`narrowed`] scales each output row's weight up where the settled order-0 model's residual
//! (`align`) scatters less than the weights say: by `1 / c`, `c` the row's chi2 per real degree
//! of freedom (six per row and bin) averaged over [`HALF_WINDOW`] bins on each side, where `c < 1`
//! (floored at [`MIN_SCALE`]). Never narrowed the other way: where the model misfits (`c > 1`)
//! the weights stay, and the fit's chi2 says so. Bins are taken in the band's order. The average
//! over 33 bins (about 200 degrees of freedom, correlated by the window) is known to about 15 %;
//! where `c` is 1, taking `min(1, c)` raises the weights by about 4 % on average.
//!
//! The scaling depends on the data and the order-0 model alone, not on the order asked (the warm
//! path's "same data", `super::warm`). Weights given as variances (`Weights::Variance`) are left
//! as they are.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::weights::RowWeight;

/// Bins on each side of a bin whose chi2 is averaged with its own.
pub const HALF_WINDOW: usize = 16;

/// The smallest scale of the weights' noise: at most this many times more weight than given.
pub const MIN_SCALE: f64 = 1e-3;

/// The row weights `rows` scaled by their local scatter `chi2` (per bin and row, module docs);
/// `None` when no row is narrowed.
#[must_use]
pub fn narrowed(rows: &[[RowWeight; 3]], chi2: &[[f64; 3]]) -> Option<Vec<[Matrix3<Complex64>; 3]>> {
    let n = rows.len().min(chi2.len());
    if n == 0 {
        return None;
    }
    // Running sums for the window means.
    let mut prefix = vec![[0.0; 3]; n + 1];
    for k in 0..n {
        prefix[k + 1] = std::array::from_fn(|i| prefix[k][i] + chi2[k][i]);
    }
    let mut any = false;
    let out = (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(HALF_WINDOW), (k + HALF_WINDOW + 1).min(n));
            std::array::from_fn(|i| {
                let c = (prefix[hi][i] - prefix[lo][i]) / (6.0 * (hi - lo) as f64);
                let scale = if c.is_finite() && c < 1.0 {
                    c.max(MIN_SCALE)
                } else {
                    1.0
                };
                any |= scale < 1.0;
                rows[k][i].omega / Complex64::from(scale)
            })
        })
        .collect();
    any.then_some(out)
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::{HALF_WINDOW, MIN_SCALE, narrowed};
    use crate::ident::structural::weights::RowWeight;

    fn rows(n: usize) -> Vec<[RowWeight; 3]> {
        let omega = Matrix3::from_diagonal_element(Complex64::from(4.0));
        vec![
            [RowWeight {
                omega,
                white: omega.map(Complex64::sqrt),
            }; 3];
            n
        ]
    }

    /// A row scattering a tenth of what its weights say gets ten times the weight; rows at or
    /// above their expectation keep theirs; nothing narrowed is `None`.
    #[test]
    fn rows_are_narrowed_to_their_scatter_and_never_widened() {
        let n = 100;
        let chi2: Vec<[f64; 3]> = vec![[0.6, 6.0, 30.0]; n];
        let out = narrowed(&rows(n), &chi2).expect("row 0 is narrowed");
        for bin in &out {
            assert!((bin[0][(0, 0)].re - 40.0).abs() < 1e-9, "{}", bin[0][(0, 0)]);
            assert!((bin[1][(0, 0)].re - 4.0).abs() < 1e-12);
            assert!((bin[2][(0, 0)].re - 4.0).abs() < 1e-12);
        }
        assert!(narrowed(&rows(n), &vec![[6.0, 7.0, 60.0]; n]).is_none());
        // A vanishing scatter is held at the floor.
        let out = narrowed(&rows(n), &vec![[0.0, 6.0, 6.0]; n]).unwrap();
        assert!((out[50][0][(0, 0)].re - 4.0 / MIN_SCALE).abs() < 1e-6);
    }

    /// The scatter is a window mean: one bin far below its expectation among bins at it moves
    /// its neighbours by its share of the window only, and bins beyond the window not at all.
    #[test]
    fn the_scatter_is_averaged_over_the_window() {
        let n = 200;
        let mut chi2 = vec![[6.0; 3]; n];
        chi2[100] = [0.0; 3];
        let out = narrowed(&rows(n), &chi2).unwrap();
        let width = (2 * HALF_WINDOW + 1) as f64;
        let inside = 4.0 / ((width - 1.0) / width);
        for k in [100 - HALF_WINDOW, 100, 100 + HALF_WINDOW] {
            assert!((out[k][1][(0, 0)].re - inside).abs() < 1e-9, "bin {k}");
        }
        for k in [100 - HALF_WINDOW - 1, 100 + HALF_WINDOW + 1, 0, n - 1] {
            assert!((out[k][1][(0, 0)].re - 4.0).abs() < 1e-12, "bin {k}");
        }
    }
}
