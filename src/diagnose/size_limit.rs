//! What the search could have seen of the effects whose size is linear in the model: a gyro's
//! `g_sensitivity` (`G`, output units per m/s^2), an accelerometer's `lever_arm_error` (the
//! offset, m) and either block's `scale_nonlinearity` (`k2`, output units per input unit
//! squared). A search that named none of them says how large each would have had to be for its
//! evidence to reach the criterion of the last round (BIC's `ln n` per parameter plus the
//! round's look-elsewhere cost, `super::workflow`), so that a lab can certify "below this" and
//! not only "not found" (a `g_sensitivity` of the catalogue's size was missed on 5 of 20 runs,
//! its evidence 71 against 101 needed, with no word of what the run could have seen).
//!
//! The evidence of an effect of size `b` (its components as a vector) added to the final model
//! is the fall of `chi2 = 2 C / ENBW` it brings, `C` the fit's cost (`super::profile`), every
//! other parameter refitted: `2 b' S b / ENBW`, `2 S` the cost's curvature along the effect with
//! the others profiled out (the Schur complement in the cost's Hessian, linear and nonlinear
//! parameters alike, `super::uncertainty::hessian`; holding the nonlinear ones made the limits
//! 0.4-6 % lower on the runs tried: the delay and a band limit's `T` correlate a little with these
//! terms). So:
//! - one component `k` alone reaches the criterion at `sqrt(chi2_needed ENBW / (2 S_kk))`
//!   ([`SizeLimit::component`]);
//! - an effect of any direction does at the norm `sqrt(chi2_needed ENBW / (2 lambda_min(S)))`
//!   ([`SizeLimit::any_direction`]), the Frobenius norm for `G`.
//!
//! That is the evidence of the effect alone by this fit's weights; the data's own noise adds
//! about one per parameter on average and spreads it. Two things take from it, so a lab should
//! allow half as much again (`tests/diagnose_size_limit.rs`, a perfect and a real stand: each
//! effect's best and least determined components injected at 1.5 times their limit were named,
//! or said, or named as another effect):
//! - the weights are the identification's residual level, which the effect raises by its part
//!   that a linear per-frequency regression on the inputs cannot take (a nonlinearity's
//!   harmonics; on a real stand with coloured angle noise, some of `G`'s low-frequency term):
//!   measured 0.95-1.26 of the promise for `G` and the offset on a perfect stand, 0.66-0.69 for
//!   `k2`, 0.42-0.84 on the real stand, falling with the size as the level rises with it (at
//!   least 0.60 at 1.5 times the limit, where the evidence is then about the criterion);
//! - the rounds' other rules: a finding that does not shrink the outputs' unweighted residual
//!   power is said significant but not named ([`super::not_named`]), one not confirmed below
//!   where the angles are mostly their noise is set aside ([`super::noisy_angles`]), and where
//!   another effect explains the same misfit with fewer parameters that one is named (an entry
//!   `G[gz][fy]` at 1.5 times its limit was named `axis_time_skew`).
//!
//! Nothing is stated where the rounds ended on their count (no effect could have been named),
//! for an effect named, rejected, refused by a rule or set aside (said apart), or where the
//! effect's candidate could not be fitted. Units: as the effect's parameters in the report. NaN
//! cannot arise from finite input: a Hessian that is not positive definite (the run does not
//! determine the effect) gives no limit.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::{Deserialize, Serialize};

use super::candidates::{Candidate, Extension};
use super::design::WINDOW_ENBW;
use super::state::State;
use super::uncertainty::{determined, hessian};
use crate::block::Block;
use crate::effect::Effect;

/// The effects whose limit is stated (their size linear in the model).
pub const LIMITED: [Effect; 3] = [
    Effect::GSensitivity,
    Effect::LeverArmError,
    Effect::ScaleNonlinearity,
];

/// The size one effect needs for its evidence to reach the search's criterion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SizeLimit {
    /// The effect (its catalogue id in JSON).
    pub effect: Effect,
    /// The evidence (chi2) it needs.
    pub chi2_needed: f64,
    /// Per component, that component alone's size at which its evidence reaches
    /// [`Self::chi2_needed`]: `G` row-major (`[output][input]`), `k2` per output, the offset
    /// per platform axis.
    pub component: Vec<f64>,
    /// The norm (Frobenius for `G`) above which an effect of any direction reaches it.
    pub any_direction: f64,
}

/// The limits of the effects of [`LIMITED`] among `candidates` (the last round's, fitted on
/// `state` over `band_hz`), each needing `chi2_needed(added parameters)`.
pub(super) fn size_limits(
    state: &State,
    candidates: &[Candidate],
    band_hz: [f64; 2],
    chi2_needed: impl Fn(usize) -> f64,
) -> Vec<SizeLimit> {
    LIMITED
        .iter()
        .filter_map(|&effect| {
            let c = candidates.iter().find(|c| c.effect == effect)?;
            let Extension::Structural(f) = &c.extension else {
                return None;
            };
            let start = match effect {
                Effect::GSensitivity => f.layout.g?,
                Effect::LeverArmError => f.layout.lever_arm?,
                _ => f.layout.k2?,
            };
            let n = if effect == Effect::GSensitivity { 9 } else { 3 };
            let p = f.layout.n_params;
            let (h, _) = determined(hessian(&state.design, &state.grams, f, band_hz)?, p)?;
            // The cost's curvature along the effect, everything else profiled out: `2 S`.
            let s = profiled(&h, start..start + n)? / 2.0;
            let needed = chi2_needed(c.added_params);
            let (component, any_direction) = limits(s, needed)?;
            Some(SizeLimit {
                effect,
                chi2_needed: needed,
                component,
                any_direction,
            })
        })
        .collect()
}

/// Each component's limit and the any-direction one for an effect whose evidence is
/// `2 b' S b / ENBW` (`chi2 = 2 C / ENBW`), needing `needed`; `None` where `S` is not positive
/// definite or a limit not finite.
fn limits(s: DMatrix<f64>, needed: f64) -> Option<(Vec<f64>, f64)> {
    let scale = needed * WINDOW_ENBW / 2.0;
    let component: Vec<f64> = (0..s.nrows()).map(|k| (scale / s[(k, k)]).sqrt()).collect();
    let lowest = SymmetricEigen::new(s).eigenvalues.min();
    let any = (scale / lowest).sqrt();
    (lowest > 0.0 && any.is_finite() && component.iter().all(|c| c.is_finite())).then_some((component, any))
}

/// The curvature of a cost with Hessian `h` along the parameters `own` with every other one
/// profiled out (the Schur complement of the others' block, computed as the inverse of the
/// inverse's block `own`); `None` where `h` is not positive definite.
fn profiled(h: &DMatrix<f64>, own: std::ops::Range<usize>) -> Option<DMatrix<f64>> {
    let n = h.nrows();
    // Scaled to unit diagonal before inverting: K (near 1) and k2 (1e-3) differ by orders.
    let d = DVector::from_iterator(n, (0..n).map(|k| 1.0 / h[(k, k)].sqrt()));
    let scaled = DMatrix::from_fn(n, n, |i, j| h[(i, j)] * d[i] * d[j]);
    let inverse = scaled.cholesky()?.inverse();
    let m = own.len();
    let block = DMatrix::from_fn(m, m, |i, j| {
        let (a, b) = (own.start + i, own.start + j);
        inverse[(a, b)] * d[a] * d[b]
    });
    let out = block.cholesky()?.inverse();
    let out = (&out + out.transpose()) / 2.0;
    out.iter().all(|v| v.is_finite()).then_some(out)
}

impl SizeLimit {
    /// The limit in words (one sentence naming the block, no final stop).
    #[must_use]
    pub fn words(&self, block: Block) -> String {
        // A block's inputs are in its outputs' units (rad/s, m/s^2): `k2` is per input squared.
        let out = block.output_unit();
        let unit = match self.effect {
            Effect::GSensitivity => format!("{out} per m/s^2"),
            Effect::LeverArmError => "m".to_owned(),
            _ => format!("{out} per ({out})^2"),
        };
        let (what, norm) = match self.effect {
            Effect::GSensitivity => ("one entry of G", "its Frobenius norm"),
            Effect::LeverArmError => ("one axis's offset", "the offset's length"),
            _ => ("one channel's k2", "k2's norm"),
        };
        let lo = self.component.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = self.component.iter().copied().fold(0.0, f64::max);
        format!(
            "{block} block: no {} named; its evidence would have reached the criterion (chi2 {:.1}) \
             with {norm} above {:.2e} {unit} in any direction, or {what} alone above {lo:.2e} to \
             {hi:.2e} {unit}; allow 1.5 times these (the effect raises the level it is weighed against, \
             and another effect may be named in its place: measured on simulated runs, each one tried at \
             1.5 times was named or said)",
            self.effect.name_on(block),
            self.chi2_needed,
            self.any_direction,
        )
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::DMatrix;

    use super::profiled;

    #[test]
    fn the_profiled_curvature_is_the_schur_complement() {
        // A symmetric positive definite 5 x 5 with rows of very different scales: the curvature
        // along 1..3 with the others profiled out, against the Schur complement's formula.
        let a = DMatrix::from_fn(5, 5, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 * 0.1 + if i == j { 1.0 } else { 0.0 }
        });
        let scales = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1.0, 1e3, 1e-2, 1.0, 5.0]));
        let h = &scales * (&a * a.transpose()) * &scales;
        let own = [1, 2];
        let others = [0, 3, 4];
        let pick = |r: &[usize], c: &[usize]| DMatrix::from_fn(r.len(), c.len(), |i, j| h[(r[i], c[j])]);
        let (ee, eo, oo) = (pick(&own, &own), pick(&own, &others), pick(&others, &others));
        let schur = &ee - &eo * oo.try_inverse().expect("inverse") * eo.transpose();
        let got = profiled(&h, 1..3).expect("profiled");
        for (g, s) in got.iter().zip(schur.iter()) {
            assert!((g - s).abs() < 1e-9 * s.abs().max(1e-3), "{got} {schur}");
        }
        // Nothing else to profile out: the matrix itself.
        let whole = profiled(&h, 0..5).expect("whole");
        assert!((&whole - &h).abs().max() < 1e-9 * h.abs().max());
        // Not positive definite: none.
        assert!(profiled(&(-&h), 1..3).is_none());
    }

    /// The limits against the evidence they promise, `2 b' S b / ENBW`: one component at its
    /// limit gives the criterion exactly; any direction at the any-direction norm gives at least
    /// it, the least determined direction exactly; a norm a tenth below it falls short there.
    #[test]
    fn the_limits_give_the_criterion_they_state() {
        use super::{WINDOW_ENBW, limits};
        let a = DMatrix::from_fn(3, 3, |i, j| {
            ((i * 5 + j * 2) % 3) as f64 * 0.3 + if i == j { 0.5 } else { 0.0 }
        });
        let s = (&a * a.transpose()) * 1e6;
        let needed = 93.0;
        let evidence = |b: &nalgebra::DVector<f64>| 2.0 * (b.transpose() * &s * b)[(0, 0)] / WINDOW_ENBW;
        let (component, any) = limits(s.clone(), needed).expect("limits");
        for (k, c) in component.iter().enumerate() {
            let mut b = nalgebra::DVector::zeros(3);
            b[k] = *c;
            assert!((evidence(&b) / needed - 1.0).abs() < 1e-12, "{k}");
        }
        // Seeded directions on the sphere of radius `any`.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..200 {
            let b = nalgebra::DVector::from_fn(3, |_, _| uniform());
            let b = &b * (any / b.norm());
            assert!(evidence(&b) >= needed * (1.0 - 1e-12), "{b}");
        }
        let eig = nalgebra::SymmetricEigen::new(s.clone());
        let weakest = eig.eigenvalues.imin();
        let b = eig.eigenvectors.column(weakest).into_owned() * any;
        assert!((evidence(&b) / needed - 1.0).abs() < 1e-9);
        assert!(evidence(&(&b * 0.9)) < needed);
        assert!(limits(-s, needed).is_none());
    }
}
