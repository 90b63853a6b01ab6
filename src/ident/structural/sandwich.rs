//! The sandwich covariance of the structural fit: where the fit does not explain the data in the
//! way its weights say (a misfit that piles up in some bins, an errors-in-variables bias that
//! varies with frequency), the spread of the bins' own scores says how uncertain each parameter
//! is, which the one-number `chi2 / dof` widening cannot.
//!
//! With `J` the Jacobian of the whitened real residuals `r` (unit variance when the weights are
//! right), each bin's score is `s_k = J_k^T r_k` (its rows). The scores of [`CLUSTER_BINS`]
//! adjacent bins are summed (Welch bins of overlapping Hann segments are correlated with their
//! neighbours), and `V = (J^T J)^-1 M (J^T J)^-1` with `M = C / (C - 1) sum_c (s_c - mean)(s_c -
//! mean)^T` over the `C` clusters. When the weights are right `V = (J^T J)^-1` (the Gauss-Newton
//! covariance); `report::assemble` widens a parameter's standard deviation to the sandwich's
//! where it is larger, never narrows it.
//!
//! Undetermined: fewer than four clusters per parameter (the meat would be too noisy to widen
//! by), a singular `J` (its parameters are `+inf` already), or a non-finite score. Units: those of
//! the parameters (normalised, as [`super::model`]).

use nalgebra::{DMatrix, DVector};

/// Adjacent Welch bins summed into one cluster.
pub(super) const CLUSTER_BINS: usize = 4;

/// Each bin's score `J_k^T r_k` (rows `18 k .. 18 k + 18` of `jac` and `residual`).
pub(super) fn bin_scores(jac: &faer::Mat<f64>, residual: &[f64], bins: usize) -> Vec<DVector<f64>> {
    let p = jac.ncols();
    let per_bin = residual.len() / bins.max(1);
    (0..bins)
        .map(|k| {
            DVector::from_fn(p, |c, _| {
                (k * per_bin..(k + 1) * per_bin)
                    .map(|row| jac[(row, c)] * residual[row])
                    .sum()
            })
        })
        .collect()
}

/// The meat of a clustered sandwich: the scores (each a vector of the `p` parameters) summed
/// over clusters of `width` adjacent ones, and `C / (C - 1) sum_c (s_c - mean)(s_c - mean)^T`
/// over the `C` clusters. `None` with fewer than four clusters per parameter (too noisy to widen
/// by) or a non-finite score. Shared with the diagnosis (`diagnose::uncertainty`).
pub(crate) fn clustered_meat(scores: &[DVector<f64>], width: usize) -> Option<DMatrix<f64>> {
    let p = scores.first()?.len();
    let clusters: Vec<DVector<f64>> = scores
        .chunks(width.max(1))
        .map(|c| c.iter().fold(DVector::zeros(p), |acc, v| acc + v))
        .collect();
    let c = clusters.len();
    if c < 4 * p || clusters.iter().any(|v| v.iter().any(|x| !x.is_finite())) {
        return None;
    }
    let mean = clusters.iter().fold(DVector::zeros(p), |acc, v| acc + v) / c as f64;
    let mut meat = DMatrix::<f64>::zeros(p, p);
    for v in &clusters {
        let d = v - &mean;
        meat += &d * d.transpose();
    }
    Some(meat * (c as f64 / (c as f64 - 1.0)))
}

/// The sandwich variance of each parameter, from the upper-triangular `r` of `J`'s QR
/// (`J^T J = R^T R`) and the bins' scores. `None` where undetermined (module docs).
pub(super) fn variances(r: &DMatrix<f64>, scores: &[DVector<f64>]) -> Option<Vec<f64>> {
    let p = r.ncols();
    let meat = clustered_meat(scores, CLUSTER_BINS)?;
    // (R^T R)^-1 = V S^-2 V^T from R's SVD (not by inverting R^T R, which squares the
    // condition); a direction below 1e-12 of the largest singular value leaves its parameters
    // undetermined (`+inf` already), and the sandwich is not formed.
    let svd = r.clone().svd(false, true);
    let v_t = svd.v_t?;
    let s = svd.singular_values;
    let s_max = s.iter().copied().fold(0.0, f64::max);
    let determined = |x: f64| x.is_finite() && x > 1e-12 * s_max;
    if !(s_max.is_finite() && s_max > 0.0 && s.iter().all(|&x| determined(x))) {
        return None;
    }
    let inverse = DMatrix::<f64>::from_fn(p, p, |i, j| {
        (0..s.len())
            .map(|k| v_t[(k, i)] * v_t[(k, j)] / (s[k] * s[k]))
            .sum::<f64>()
    });
    let v = &inverse * meat * &inverse;
    let diagonal: Vec<f64> = (0..p).map(|i| v[(i, i)]).collect();
    diagonal
        .iter()
        .all(|x| x.is_finite() && *x >= 0.0)
        .then_some(diagonal)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, DVector};

    use super::variances;
    use crate::rng::Rng;

    /// A straight line fitted to 1200 points in bins of one point, with noise of unit variance
    /// (as weighted) on the first 80 % and `loud` on the rest: the sandwich's variances against
    /// the closed form `(X'X)^-1 X' Sigma X (X'X)^-1`, averaged over draws.
    #[test]
    fn the_sandwich_variance_matches_the_closed_form() {
        let n = 1200;
        let x: Vec<[f64; 2]> = (0..n).map(|k| [1.0, k as f64 / n as f64]).collect();
        let sigma = |k: usize, loud: f64| if k >= 4 * n / 5 { loud } else { 1.0 };
        let xtx = DMatrix::from_fn(2, 2, |i, j| x.iter().map(|v| v[i] * v[j]).sum::<f64>());
        let r = xtx.clone().cholesky().expect("positive").l().transpose();
        let inverse = xtx.try_inverse().expect("regular");
        for loud in [1.0, 3.0] {
            let meat = DMatrix::from_fn(2, 2, |i, j| {
                (0..n)
                    .map(|k| sigma(k, loud).powi(2) * x[k][i] * x[k][j])
                    .sum::<f64>()
            });
            let closed = &inverse * meat * &inverse;
            let draws = 40;
            let mut mean = [0.0; 2];
            for seed in 0..draws {
                let mut rng = Rng::new(500 + seed);
                let scores: Vec<DVector<f64>> = (0..n)
                    .map(|k| {
                        let e = sigma(k, loud) * rng.normal();
                        DVector::from_vec(vec![x[k][0] * e, x[k][1] * e])
                    })
                    .collect();
                let v = variances(&r, &scores).expect("enough clusters");
                for i in 0..2 {
                    mean[i] += v[i] / draws as f64;
                }
            }
            for i in 0..2 {
                let ratio = mean[i] / closed[(i, i)];
                assert!((ratio - 1.0).abs() < 0.08, "loud {loud}, parameter {i}: {ratio}");
            }
        }
    }
}
