//! Variable projection: for given nonlinear parameters, the linear ones solve a weighted least
//! squares problem built from the group Gram matrices, and the weighted residual power that
//! remains is the profile cost the nonlinear search minimises.
//!
//! Weights are `1 / E|psi_k|^2`, the disturbance level the identifier's noise model expects, so
//! a correct model leaves `E[cost] = n_bins` per channel and `chi2 = 2 cost` is chi-squared with two
//! degrees of freedom per independent complex bin.

use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;

use super::design::{Design, X};
use super::structure::{Filters, Layout, Structure, Theta};

/// The result of one projection.
#[derive(Clone, Debug)]
pub struct Profile {
    /// Weighted residual power, summed over channels and band bins (`chi2 / 2`).
    pub cost: f64,
    /// The linear parameters.
    pub beta: Vec<f64>,
}

/// The weighted normal equations of the linear parameters at `theta`: `N`, `r` and the
/// outputs' weighted power `c0`, so that the cost of any linear parameters `b` is
/// `c0 - 2 r.b + b' N b`. `None` when they are not finite or all zero (a degenerate `theta`).
#[must_use]
pub fn normal_equations(
    design: &Design,
    grams: &[DMatrix<Complex64>],
    structure: &Structure,
    layout: &Layout,
    theta: &Theta,
) -> Option<(DMatrix<f64>, DVector<f64>, f64)> {
    let p = layout.n_params;
    let mut normal = DMatrix::<f64>::zeros(p, p);
    let mut rhs = DVector::<f64>::zeros(p);
    let mut c0 = [0.0; 3];
    let mut factors = vec![Complex64::default(); layout.terms.len()];
    for (g, gram) in grams.iter().enumerate() {
        let group = GroupSums {
            normal: &mut normal,
            rhs: &mut rhs,
            c0: &mut c0,
        };
        group.add(design, structure, layout, theta, g, gram, &mut factors);
    }
    let scale = (0..p).map(|k| normal[(k, k)]).fold(0.0_f64, f64::max);
    (scale.is_finite() && scale > 0.0).then(|| (normal, rhs, c0.iter().sum()))
}

/// Where one group's weighted sums are added.
struct GroupSums<'a> {
    normal: &'a mut DMatrix<f64>,
    rhs: &'a mut DVector<f64>,
    c0: &'a mut [f64; 3],
}

impl GroupSums<'_> {
    /// Adds group `g`'s terms (`factors` is scratch of one entry per layout term).
    #[expect(
        clippy::too_many_arguments,
        reason = "the pieces of one projection, passed through"
    )]
    fn add(
        self,
        design: &Design,
        structure: &Structure,
        layout: &Layout,
        theta: &Theta,
        g: usize,
        gram: &DMatrix<Complex64>,
        factors: &mut [Complex64],
    ) {
        let filters = Filters::at(structure, theta, design.group_hz[g]);
        for (a, t) in factors.iter_mut().zip(&layout.terms) {
            *a = filters.factor(t);
        }
        let w = [0, 1, 2].map(|i| 1.0 / design.group_expected[i][g]);
        for i in 0..3 {
            self.c0[i] += w[i] * gram[(X + i, X + i)].re;
        }
        for (m, tm) in layout.terms.iter().enumerate() {
            let wi = w[tm.channel];
            let am = factors[m].conj();
            self.rhs[tm.param] += wi * (am * gram[(tm.regressor, X + tm.channel)]).re;
            for (n, tn) in layout.terms.iter().enumerate().skip(m) {
                if tn.channel != tm.channel {
                    continue;
                }
                let v = wi * (am * factors[n] * gram[(tm.regressor, tn.regressor)]).re;
                self.normal[(tm.param, tn.param)] += v;
                if n != m {
                    self.normal[(tn.param, tm.param)] += v;
                }
            }
        }
    }
}

/// Each group's share of the cost at `theta` and the linear parameters `beta`: per group the
/// cost `c0_g - 2 r_g.b + b' N_g b` and the half-gradient `r_g - N_g b` of minus it with
/// respect to `b` (the groups' scores, summed to zero at the optimum). Empty on a degenerate
/// `theta` (a non-finite sum).
#[must_use]
pub fn group_shares(
    design: &Design,
    grams: &[DMatrix<Complex64>],
    structure: &Structure,
    layout: &Layout,
    theta: &Theta,
    beta: &DVector<f64>,
) -> Vec<(f64, DVector<f64>)> {
    let p = layout.n_params;
    let mut factors = vec![Complex64::default(); layout.terms.len()];
    let mut normal = DMatrix::<f64>::zeros(p, p);
    let mut rhs = DVector::<f64>::zeros(p);
    let mut shares = Vec::with_capacity(grams.len());
    for (g, gram) in grams.iter().enumerate() {
        normal.fill(0.0);
        rhs.fill(0.0);
        let mut c0 = [0.0; 3];
        let group = GroupSums {
            normal: &mut normal,
            rhs: &mut rhs,
            c0: &mut c0,
        };
        group.add(design, structure, layout, theta, g, gram, &mut factors);
        let score = &rhs - &normal * beta;
        let cost = c0.iter().sum::<f64>() - rhs.dot(beta) - score.dot(beta);
        if !cost.is_finite() || score.iter().any(|v| !v.is_finite()) {
            return Vec::new();
        }
        shares.push((cost, score));
    }
    shares
}

/// Solves the linear parameters for `theta`. `None` when the normal equations are singular or
/// not finite (a degenerate `theta`).
#[must_use]
pub fn project(
    design: &Design,
    grams: &[DMatrix<Complex64>],
    structure: &Structure,
    layout: &Layout,
    theta: &Theta,
) -> Option<Profile> {
    let (mut normal, rhs, c0) = normal_equations(design, grams, structure, layout, theta)?;
    let p = layout.n_params;
    let scale = (0..p).map(|k| normal[(k, k)]).fold(0.0_f64, f64::max);
    for k in 0..p {
        normal[(k, k)] += 1e-13 * scale;
    }
    let beta = normal.cholesky()?.solve(&rhs);
    if beta.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let total = c0 - rhs.dot(&beta);
    Some(Profile {
        cost: total,
        beta: beta.iter().copied().collect(),
    })
}

/// The model's output spectrum on every band bin.
#[must_use]
pub fn predict(
    design: &Design,
    structure: &Structure,
    layout: &Layout,
    theta: &Theta,
    beta: &[f64],
) -> [Vec<Complex64>; 3] {
    let n = design.n_bins();
    let mut out = [(); 3].map(|()| vec![Complex64::default(); n]);
    for (k, &f) in design.frequency_hz.iter().enumerate() {
        let filters = Filters::at(structure, theta, f);
        for t in &layout.terms {
            out[t.channel][k] += filters.factor(t) * beta[t.param] * design.z[t.regressor][k];
        }
    }
    out
}
