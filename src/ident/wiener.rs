//! The regularised Wiener-Kolmogorov stage (cheap; recomputed when A, Lambda or the estimate
//! change): `W_u = (I - A^-1 Lambda) W` with `W` the settings' [`Estimate`] from the factorisation
//! stage: `H1 = S_xu S_uu^-1` (the default) or the paper's causal `W0 = [S_xu D_u^-H]_+ D_u^-1`.
//!
//! Why `H1` by default (measured, README "Never silently wrong"): the structural fit weighs each
//! bin by the inverse covariance of `H1` (`row_weights`), and `H1` at a bin depends on that bin's
//! spectra only. `W0` at a bin depends on the spectra at every frequency through the projection,
//! so where the reference's angles are band-limited inside the grid (the inputs lose power above
//! the limit while the outputs do not; a zero-phase roll-off has no causal inverse) its error in
//! the band is larger than the weights say: at 1 kHz with a 30 Hz band limit the accelerometer's
//! K came out on average 0.39 % off through `W0` (z rms 1.5-1.6) and 0.17 % through `H1` (z rms
//! 0.9-1.1), on the same runs; zeroing what the projection takes from bins without coherence did
//! not help (README), so it is the limit's own structure, not the noise there. The structural model
//! `K e^(-tau s)` (or richer) is causal by construction, so fitting it to `H1` loses nothing the
//! projection would have given, and `H1` satisfies the regularising constraint `W S_uu = S_xu`
//! exactly (auto-Lambda is 0 for it). `W0` stays available (`"estimate": "causal_wiener"`).
//!
//! Lambda `"auto"` solves the regularising constraint (READING.md): the identified model must
//! reproduce the measured cross-spectrum, `W_u S_uu = S_xu`, which the causal projection alone does
//! not guarantee (`H1` meets it exactly, so for it the solution is 0). Over the analysis band,
//! with `E = W S_uu - S_xu` and `F = W S_uu` (`W` the estimate), the
//! A-weighted residual `sum_f tr[(E - A^-1 Lambda F)^H A (E - A^-1 Lambda F)]` is quadratic in the
//! diagonal Lambda; its minimum solves the 3x3 system
//! `M lambda = v`, `M_ik = (A^-1)_ik sum_f Re(F_k F_i^H)`, `v_i = sum_f Re(E_i F_i^H)`
//! (rows `E_i`, `F_i`), solved with `lambda >= 0` (the constraint corrects an estimate's
//! leakage, the causal projection's, by shrinking; it never justifies amplifying it) and scaled back
//! so that `A^-1 Lambda` shrinks the gain by at most [`MAX_SHRINK`]. With `Lambda = 0` the weight A drops out entirely (the multichannel Wiener
//! filter is optimal for every positive-definite weight): A shapes the result only through
//! `A^-1 Lambda` and this fit.
//!
//! Confidence: the variance of each element of `W_u` is taken as that of the multichannel H1
//! estimate (exact for `H1`, an approximation for `W0`), `E|dW_ij|^2 = S_psi,ii (S_uu^-1)_jj / (n_eq - 3)`, with `n_eq` the overlap-corrected
//! number of averages; multiple coherence `gamma_i^2 = 1 - S_psi,ii / S_xx,ii`.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;
use serde::Serialize;

use super::IdentError;
use super::factorisation::Factorisation;
use super::settings::{Estimate, LambdaSetting, MAX_SHRINK, max_shrink};
use super::spectra::BlockSpectra;

/// The identified frequency response and its quality figures, one-sided grid.
#[derive(Clone, Debug, Serialize)]
pub struct WienerEstimate {
    /// The Lagrange multipliers used.
    pub lambda: [f64; 3],
    /// Whether they were solved from the constraint.
    pub lambda_auto: bool,
    /// The estimate regularised.
    pub estimate: Estimate,
    /// `I - A^-1 Lambda`: `W_u = regularisation W` at every bin ([`Self::w_u`]).
    #[serde(skip)]
    regularisation: Matrix3<f64>,
    /// The estimate `W` per bin (the factorisation's `H1` or `W0`, shared).
    #[serde(skip)]
    unregularised: Arc<Vec<Matrix3<Complex64>>>,
    /// Standard deviation of each element of `W_u` per bin (complex magnitude): the
    /// factorisation's [`Factorisation::estimate_std`], shared.
    #[serde(skip)]
    pub w_u_std: Arc<Vec<Matrix3<f64>>>,
    /// Multiple coherence of each output with the three inputs, per bin (shared likewise).
    #[serde(skip)]
    pub coherence: Arc<Vec<[f64; 3]>>,
    /// Band-integrated residual of `W_u S_uu = S_xu`, relative to `S_xu` (A-weighted).
    pub constraint_residual: f64,
    /// The same for `Lambda = 0`, for comparison.
    pub constraint_residual_unregularised: f64,
}

impl WienerEstimate {
    /// `W_u` at bin `k` of the one-sided grid, `k < self.bins()`, computed when asked (a real
    /// 3x3 product): the fit and the model read it at the band's native bins alone, and a retune
    /// no longer fills the whole padded grid.
    ///
    /// # Panics
    /// For `k` past the grid, as indexing does.
    #[must_use]
    pub fn w_u(&self, k: usize) -> Matrix3<Complex64> {
        real_times(&self.regularisation, &self.unregularised[k])
    }

    /// Number of bins of the one-sided grid.
    #[must_use]
    pub fn bins(&self) -> usize {
        self.unregularised.len()
    }
}

/// Indices of the bins inside `[low, high]` Hz.
#[must_use]
pub fn band_bins(frequency_hz: &[f64], band_hz: [f64; 2]) -> Vec<usize> {
    (0..frequency_hz.len())
        .filter(|&k| frequency_hz[k] >= band_hz[0] && frequency_hz[k] <= band_hz[1])
        .collect()
}

/// Applies A and Lambda to the factorisation stage's `estimate`.
///
/// # Errors
/// [`IdentError::EmptyBand`] when no bin lies in the band; [`IdentError::Singular`] when A cannot be
/// inverted or the auto-Lambda system is singular (an output or input with no power in the band);
/// [`IdentError::Factor`] for the causal estimate of a factorisation without its causal stage.
pub fn regularised_wiener(
    spectra: &BlockSpectra,
    fact: &Factorisation,
    estimate: Estimate,
    weight_a: &Matrix3<f64>,
    lambda: LambdaSetting,
    band_hz: [f64; 2],
) -> Result<WienerEstimate, IdentError> {
    let band = band_bins(&spectra.frequency_hz, band_hz);
    if band.is_empty() {
        return Err(IdentError::EmptyBand {
            low: band_hz[0],
            high: band_hz[1],
        });
    }
    let a_inv = weight_a.try_inverse().ok_or(IdentError::Singular("weight_A"))?;
    let base = fact.estimate(estimate)?;
    let e: Vec<Matrix3<Complex64>> = band
        .iter()
        .map(|&k| base[k] * spectra.s_uu[k] - spectra.s_xu[k])
        .collect();
    let f: Vec<Matrix3<Complex64>> = band.iter().map(|&k| base[k] * spectra.s_uu[k]).collect();
    let (values, auto) = match lambda {
        LambdaSetting::Values(v) => (v, false),
        LambdaSetting::Auto => (solve_lambda(&e, &f, &a_inv)?, true),
    };
    let scale = Matrix3::identity() - a_inv * Matrix3::from_diagonal(&Vector3::from(values));
    let den: f64 = band
        .iter()
        .map(|&k| weighted_square(weight_a, &spectra.s_xu[k]))
        .sum();
    let residual = |lam: [f64; 3]| {
        let l = a_inv * Matrix3::from_diagonal(&Vector3::from(lam));
        let num: f64 = e
            .iter()
            .zip(&f)
            .map(|(em, fm)| weighted_square(weight_a, &(em - real_times(&l, fm))))
            .sum();
        if den > 0.0 { (num / den).sqrt() } else { 0.0 }
    };
    Ok(WienerEstimate {
        lambda: values,
        lambda_auto: auto,
        estimate,
        regularisation: scale,
        unregularised: Arc::clone(base),
        w_u_std: Arc::clone(&fact.estimate_std),
        coherence: Arc::clone(&fact.coherence),
        constraint_residual: residual(values),
        constraint_residual_unregularised: residual([0.0; 3]),
    })
}

/// `a m` for a real `a` (27 real-by-complex products instead of 27 complex ones).
fn real_times(a: &Matrix3<f64>, m: &Matrix3<Complex64>) -> Matrix3<Complex64> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * m[(0, j)] + a[(i, 1)] * m[(1, j)] + a[(i, 2)] * m[(2, j)])
}

/// `tr(r^H A r)` for a real symmetric `A`.
fn weighted_square(a: &Matrix3<f64>, r: &Matrix3<Complex64>) -> f64 {
    let mut sum = 0.0;
    for j in 0..3 {
        for k in 0..3 {
            for l in 0..3 {
                sum += a[(k, l)] * (r[(k, j)].conj() * r[(l, j)]).re;
            }
        }
    }
    sum
}

/// Solves `M lambda = v` of the module docs.
fn solve_lambda(
    e: &[Matrix3<Complex64>],
    f: &[Matrix3<Complex64>],
    a_inv: &Matrix3<f64>,
) -> Result<[f64; 3], IdentError> {
    let mut ff = Matrix3::<f64>::zeros();
    let mut v = Vector3::<f64>::zeros();
    for (em, fm) in e.iter().zip(f) {
        for i in 0..3 {
            for k in 0..3 {
                ff[(i, k)] += (fm.row(k) * fm.row(i).adjoint())[(0, 0)].re;
            }
            v[i] += (em.row(i) * fm.row(i).adjoint())[(0, 0)].re;
        }
    }
    let m = a_inv.component_mul(&ff);
    if m.try_inverse().is_none() {
        return Err(IdentError::Singular("auto-lambda system"));
    }
    // Non-negative least squares over the 8 active sets (lambda_j = 0 outside the set): the
    // feasible stationary point of least objective `l^T M l - 2 v^T l`.
    let objective = |l: &Vector3<f64>| (l.transpose() * m * l)[(0, 0)] - 2.0 * v.dot(l);
    let mut best = (Vector3::zeros(), 0.0);
    for set in 1_u8..8 {
        let idx: Vec<usize> = (0..3).filter(|j| set & (1 << j) != 0).collect();
        let sub = nalgebra::DMatrix::from_fn(idx.len(), idx.len(), |r, c| m[(idx[r], idx[c])]);
        let rhs = nalgebra::DVector::from_fn(idx.len(), |r, _| v[idx[r]]);
        let Some(sol) = sub.lu().solve(&rhs) else {
            continue;
        };
        let mut l = Vector3::zeros();
        for (r, &j) in idx.iter().enumerate() {
            l[j] = sol[r];
        }
        if l.iter().all(|x| *x >= 0.0 && x.is_finite()) && objective(&l) < best.1 {
            best = (l, objective(&l));
        }
    }
    let mut lambda = [best.0[0], best.0[1], best.0[2]];
    // At most MAX_SHRINK of the gain: scale back along the same direction.
    let a = a_inv.try_inverse().unwrap_or_else(Matrix3::identity);
    let shrink = max_shrink(&a, &lambda);
    if shrink > MAX_SHRINK {
        lambda = lambda.map(|l| l * MAX_SHRINK / shrink);
    }
    Ok(lambda)
}
