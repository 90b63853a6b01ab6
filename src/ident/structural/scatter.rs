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
//! (`align`) scatters less than the weights say. Per row, `c` is its chi2 over its degrees of
//! freedom (`2 rank Omega_i` real ones per bin) summed over [`HALF_WINDOW`] bins on each side,
//! divided by `1 - p / N` (the order-0 fit's `p` parameters took their share of the band's `N`).
//! `c` is known to a relative `sqrt(2 b / nu)` (`nu` the window's degrees of freedom, `b` the bins'
//! correlation); the weight is divided by `c (1 + 2 sqrt(2 b / nu))`, its upper bound, where that
//! is below 1 (floored at [`MIN_SCALE`]). So weights that are right are left as they are (a window
//! of 33 Hann bins scatters about 14 %: the bound reaches below 1 in about 6 % of windows, and
//! then by little), and weights that overstate the noise tenfold are raised about eightfold.
//! Never narrowed the other way: where the model misfits (`c > 1`) the weights stay, and the fit's
//! chi2 says so. Bins are taken in the band's order.
//!
//! The scaling depends on the data and the order-0 model alone, not on the order asked (the warm
//! path's "same data", `super::warm`). Weights given as variances (`Weights::Variance`), estimates
//! without offsets (no move) and fits that ask not to (`StructuralSettings::narrow_to_scatter`:
//! the stationarity stretches, whose deviations are floors) are left as they are.

use super::weights::RowWeight;

/// Bins on each side of a bin whose chi2 is pooled with its own.
pub const HALF_WINDOW: usize = 16;

/// The smallest scale of the weights' noise: at most this many times more weight than given
/// (deviations at least a tenth of what the weights say).
pub const MIN_SCALE: f64 = 1e-2;

/// The row weights `rows` scaled to their local scatter `chi2` (per bin and row, module docs) of a
/// fit of `parameters` real parameters, with neighbouring bins correlated by `bin_correlation`;
/// `None` when no row is narrowed.
#[must_use]
pub fn narrowed(
    rows: &[[RowWeight; 3]],
    chi2: &[[f64; 3]],
    parameters: usize,
    bin_correlation: f64,
) -> Option<Vec<[RowWeight; 3]>> {
    let n = rows.len().min(chi2.len());
    if n == 0 {
        return None;
    }
    // Running sums of each row's chi2 and real degrees of freedom.
    let mut prefix = vec![[(0.0, 0.0); 3]; n + 1];
    for k in 0..n {
        prefix[k + 1] = std::array::from_fn(|i| {
            let (c, d) = prefix[k][i];
            (c + chi2[k][i], d + 2.0 * f64::from(rows[k][i].rank))
        });
    }
    let total: f64 = prefix[n].iter().map(|(_, d)| d).sum();
    let in_sample = (1.0 - parameters as f64 / total).max(0.5);
    let b = bin_correlation.max(1.0);
    let mut any = false;
    let out = (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(HALF_WINDOW), (k + HALF_WINDOW + 1).min(n));
            std::array::from_fn(|i| {
                let (chi2, dof) = (
                    prefix[hi][i].0 - prefix[lo][i].0,
                    prefix[hi][i].1 - prefix[lo][i].1,
                );
                let c = chi2 / dof / in_sample;
                let bound = c * (1.0 + 2.0 * (2.0 * b / dof).sqrt());
                let scale = if bound.is_finite() && bound < 1.0 {
                    bound.max(MIN_SCALE)
                } else {
                    1.0
                };
                any |= scale < 1.0;
                rows[k][i].unscaled(scale)
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

    /// `n` bins of rows with `Omega = 4 I` (rank 3), or of rank 1 where `rank_one`.
    fn rows(n: usize, rank_one: bool) -> Vec<[RowWeight; 3]> {
        let omega = if rank_one {
            Matrix3::from_diagonal(&nalgebra::Vector3::new(4.0, 0.0, 0.0).map(Complex64::from))
        } else {
            Matrix3::from_diagonal_element(Complex64::from(4.0))
        };
        let row = RowWeight {
            omega,
            white: omega.map(Complex64::sqrt),
            rank: if rank_one { 1 } else { 3 },
        };
        vec![[row; 3]; n]
    }

    /// The upper bound of a window's `c` (module docs) for a full window of rank-3 rows and
    /// uncorrelated bins.
    fn bound(c: f64) -> f64 {
        c * (1.0 + 2.0 * (2.0 / (6.0 * (2 * HALF_WINDOW + 1) as f64)).sqrt())
    }

    /// A row scattering a tenth of what its weights say gets the inverse of its bound; rows at or
    /// above their expectation keep theirs; nothing narrowed is `None`; a vanishing scatter is
    /// held at the floor.
    #[test]
    fn rows_are_narrowed_to_their_scatter_and_never_widened() {
        let n = 100;
        let out = narrowed(&rows(n, false), &vec![[0.6, 6.0, 30.0]; n], 0, 1.0).expect("row 0");
        for bin in &out[HALF_WINDOW..n - HALF_WINDOW] {
            let want = 4.0 / bound(0.1);
            assert!(
                (bin[0].omega[(0, 0)].re - want).abs() < 1e-9 * want,
                "{}",
                bin[0].omega[(0, 0)]
            );
            assert!((bin[1].omega[(0, 0)].re - 4.0).abs() < 1e-12);
            assert!((bin[2].omega[(0, 0)].re - 4.0).abs() < 1e-12);
        }
        assert!(narrowed(&rows(n, false), &vec![[6.0, 7.0, 60.0]; n], 0, 1.0).is_none());
        // Within the bound of 1 (a window scatters): not narrowed.
        assert!(narrowed(&rows(n, false), &vec![[5.4; 3]; n], 0, 1.0).is_none());
        let out = narrowed(&rows(n, false), &vec![[0.0, 6.0, 6.0]; n], 0, 1.0).unwrap();
        assert!((out[50][0].omega[(0, 0)].re - 4.0 / MIN_SCALE).abs() < 1e-6);
    }

    /// A rank-1 row has two real degrees of freedom per bin: a chi2 of 2 is its expectation,
    /// not a third of it; and the fit's parameters take their share of the degrees of freedom.
    #[test]
    fn degrees_of_freedom_follow_the_rank_and_the_parameters() {
        let n = 100;
        assert!(narrowed(&rows(n, true), &vec![[2.0; 3]; n], 0, 1.0).is_none());
        assert!(narrowed(&rows(n, false), &vec![[2.0; 3]; n], 0, 1.0).is_some());
        // 1800 degrees of freedom, 900 of them taken by the fit: a chi2 of 3 per row and bin
        // is its expectation.
        assert!(narrowed(&rows(n, false), &vec![[3.0; 3]; n], 900, 1.0).is_none());
        assert!(narrowed(&rows(n, false), &vec![[3.0; 3]; n], 0, 1.0).is_some());
    }

    /// The scatter is a window mean: one misfitting bin among bins scattering a tenth of their
    /// weights' noise narrows its window's bins less, and bins beyond the window not at all less.
    #[test]
    fn the_scatter_is_pooled_over_the_window() {
        let n = 200;
        let mut chi2 = vec![[0.6; 3]; n];
        chi2[100] = [60.0; 3];
        let out = narrowed(&rows(n, false), &chi2, 0, 1.0).unwrap();
        let width = (2 * HALF_WINDOW + 1) as f64;
        let inside = 4.0 / bound(((width - 1.0) * 0.1 + 10.0) / width);
        for k in [100 - HALF_WINDOW, 100, 100 + HALF_WINDOW] {
            assert!(
                (out[k][1].omega[(0, 0)].re - inside).abs() < 1e-9 * inside,
                "bin {k}"
            );
        }
        let beyond = 4.0 / bound(0.1);
        for k in [100 - HALF_WINDOW - 1, 100 + HALF_WINDOW + 1] {
            assert!(
                (out[k][1].omega[(0, 0)].re - beyond).abs() < 1e-9 * beyond,
                "bin {k}"
            );
        }
    }
}
