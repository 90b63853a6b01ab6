//! Standard deviations of a fitted block model's parameters: the sizes of the effects the
//! diagnosis names and the gain and delay of a model extended by accepted effects.
//!
//! The cost the fit minimises is `C(b, x) = c0 - 2 r(x).b + b' N(x) b` (`profile.rs`), `b` the
//! linear parameters and `x` the nonlinear ones in the search's scaled units (`fit::pack`). Its
//! Hessian at the optimum, `2 N` in the linear block, the mixed and nonlinear blocks by central
//! differences, gives the covariance `V = f H^-1` of every parameter jointly (so the gain's
//! uncertainty includes the delay's, and a lag's the gain's). The factor `f`:
//! - the weights are `1/E|psi_k|^2` of independent bins, which would make `V = H^-1` (each
//!   complex bin is two real observations of half that variance); but the whole-record bins are
//!   Hann-tapered, and a least-squares fit on tapered data has the variance of one on untapered
//!   data times `mean(w^4) / mean(w^2)^2 = 35/18` ([`TAPER_VARIANCE`]), however the bins'
//!   correlation is accounted for: the estimator is the same;
//! - where the model does not explain the data (`chi2` per degree of freedom above 1), the
//!   variance is widened by that ratio, as the identifier does;
//! - and per parameter by the **sandwich** `H^-1 M H^-1` where it is larger: `M` the outer
//!   products of the scores (each group's cost gradient, the nonlinear parameters' by central
//!   differences) summed over [`SANDWICH_CLUSTERS`] clusters of adjacent groups. The `chi2`
//!   factor is one number for the whole band; a real record's misfit piles up where some
//!   regressors live (on `broad11` the `k2` of z: 0.012 by the `chi2` factor, 0.045 by the
//!   sandwich, which reconciles it with the fast run's), and only the scores' own spread says
//!   so. Never narrowed by it; on simulated runs it changes the sizes' calibration by
//!   nothing measurable (`tests/accept_effects.rs`: z rms 0.70 before and after).
//!
//! Tones are fitted apart (`tone.rs`): their frequency's standard deviation is the Cramér-Rao
//! bound of a sinusoid, `sqrt(12 / chi2) / (2 pi N) fs` with `chi2` what the tone explains in the
//! untapered record (all channels, one frequency, each against its own continuum, the sum taken
//! for their correlation), times the taper's factor for a frequency
//! ([`TAPER_FREQUENCY_VARIANCE`]), and each channel's amplitude's is its own,
//! `sqrt(35/18 level_i / (2 G_i))` ([`super::tone::Tone::unit_std`]).
//! A clock drift's is the stretches' delay trend's, times what the whole record's taper loses of
//! a drift (`clock::TAPERED_DRIFT_STD`), or the two estimates' difference where larger; without
//! stretches, the curvature of the search's profiled cost (`clock::drift_deviation`; `null` when
//! that curvature is not positive).
//!
//! A nonlinear parameter at a bound of its range, or one the band does not see (`unseen`), is
//! held at its value: its own deviation is undetermined, the others' are those given it.
//!
//! Units: as the parameters (s, Hz, output units); `None` where the Hessian is not positive
//! definite (a parameter the data do not determine).

use nalgebra::{DMatrix, DVector};

use super::band_limit::BandLimitShape;
use super::fit::{pack, unpack};
use super::profile::{group_shares, normal_equations};
use super::state::State;
use crate::effect::Effect;
use serde_json::{Value, json};

/// Variance of a least-squares estimate from Hann-tapered data relative to the same estimate
/// from untapered data: `mean(w^4) / mean(w^2)^2` of `w = sin^2`, `(35/128) / (3/8)^2`.
pub const TAPER_VARIANCE: f64 = 35.0 / 18.0;

/// The same ratio for a sinusoid's frequency, whose information lies in the record's ends that
/// the taper weighs down: `(S(w^4 t^2) S(t^2)) / S(w^2 t^2)^2`, `t` from the record's middle;
/// in closed form `35 pi^2 (24 pi^2 - 205) / (108 (2 pi^2 - 15)^2)` = 4.5386.
pub const TAPER_FREQUENCY_VARIANCE: f64 = 4.538_593_647_68;

/// The joint covariance of a state's parameters: the linear ones (`K` row-major, then `k2`,
/// `G`, the lever-arm offset, as `structure::Layout`), then the nonlinear ones in `fit::pack`'s
/// scaled units.
#[derive(Clone, Debug)]
pub struct Covariance {
    /// The matrix.
    pub matrix: DMatrix<f64>,
    /// Number of linear parameters (the nonlinear ones follow).
    pub n_linear: usize,
}

impl Covariance {
    /// Standard deviation of `sum c_k p_k` over `(index, c)` pairs; `None` if not positive.
    #[must_use]
    pub fn std_of(&self, terms: &[(usize, f64)]) -> Option<f64> {
        let mut v = 0.0;
        for &(a, ca) in terms {
            for &(b, cb) in terms {
                v += ca * cb * self.matrix[(a, b)];
            }
        }
        (v.is_finite() && v > 0.0).then(|| v.sqrt())
    }

    /// Standard deviation of linear parameter `k`.
    #[must_use]
    pub fn linear_std(&self, k: usize) -> Option<f64> {
        self.std_of(&[(k, 1.0)])
    }

    /// Standard deviation of nonlinear parameter `k` (scaled units).
    #[must_use]
    pub fn nonlinear_std(&self, k: usize) -> Option<f64> {
        self.std_of(&[(self.n_linear + k, 1.0)])
    }
}

/// The covariance of `state`'s fitted parameters, widened by `chi2_per_dof` when above 1.
/// A nonlinear parameter at a bound of its range (a step to either side leaves it: a band limit
/// or a lag fitted at 0, a mode at the band's edge), or one the band does not see ([`unseen`]),
/// is held at its value (its row and column NaN, the others' covariance conditional on it).
/// `None` when any other parameter has no curvature,
/// their Hessian is not positive definite, or a cross term's step leaves the range.
#[must_use]
pub fn covariance(state: &State, band_hz: [f64; 2], chi2_per_dof: f64) -> Option<Covariance> {
    let f = &state.fitted;
    let (design, grams, structure, layout) = (&state.design, &state.grams, &f.structure, &f.layout);
    let (x0, hs) = packed_with_steps(f);
    let beta = DVector::from_column_slice(&f.profile.beta);
    let (p, q) = (layout.n_params, x0.len());
    let (h, keep) = determined(hessian(design, grams, f, band_hz)?, p)?;
    let reduced = reduced_covariance(
        &h,
        chi2_per_dof,
        |x: &[f64]| {
            let theta = unpack(structure, x, band_hz)?;
            let shares = group_shares(design, grams, structure, layout, &theta, &beta);
            (!shares.is_empty()).then_some(shares)
        },
        &x0,
        &hs,
        &keep,
        p,
    )?;
    // Back to every parameter's place, NaN where held.
    let mut matrix = DMatrix::from_element(p + q, p + q, f64::NAN);
    for (i, &a) in keep.iter().enumerate() {
        for (j, &b) in keep.iter().enumerate() {
            matrix[(a, b)] = reduced[(i, j)];
        }
    }
    Some(Covariance { matrix, n_linear: p })
}

/// The fit's nonlinear parameters packed (`fit::pack`'s scaled units) and the central
/// differences' steps: a fiftieth of the search's first steps (the Hessian's and the sandwich's
/// scores' alike).
fn packed_with_steps(fitted: &super::fit::Fitted) -> (Vec<f64>, Vec<f64>) {
    let (x0, steps) = pack(&fitted.structure, &fitted.theta);
    (x0, steps.iter().map(|s| 0.02 * s).collect())
}

/// The Hessian of the fit's cost at `fitted` over the linear parameters (`2 N`) and the
/// nonlinear ones (`fit::pack`'s scaled units; the mixed and nonlinear blocks by central
/// differences at a fiftieth of the search's first steps), and which nonlinear parameters a
/// step leaves the range of (held: their rows and columns left 0, [`determined`]). `None` where
/// the cost cannot be evaluated at the fit or a cross term's step leaves the range.
pub(super) fn hessian(
    design: &super::design::Design,
    grams: &[DMatrix<num_complex::Complex64>],
    fitted: &super::fit::Fitted,
    band_hz: [f64; 2],
) -> Option<(DMatrix<f64>, Vec<bool>)> {
    let (structure, layout) = (&fitted.structure, &fitted.layout);
    let (x0, hs) = packed_with_steps(fitted);
    let beta = DVector::from_column_slice(&fitted.profile.beta);
    let (p, q) = (layout.n_params, x0.len());
    let equations = |x: &[f64]| {
        let theta = unpack(structure, x, band_hz)?;
        normal_equations(design, grams, structure, layout, &theta)
    };
    let cost = |x: &[f64]| equations(x).map(|(n, r, c0)| c0 - 2.0 * r.dot(&beta) + (n * &beta).dot(&beta));
    let gradient = |x: &[f64]| equations(x).map(|(n, r, _)| 2.0 * (n * &beta - r));
    let (n0, _, _) = equations(&x0)?;
    let mut h = DMatrix::<f64>::zeros(p + q, q + p);
    h.view_mut((0, 0), (p, p)).copy_from(&(2.0 * n0));
    let shifted = |moves: &[(usize, f64)]| {
        let mut x = x0.clone();
        for &(k, d) in moves {
            x[k] += d;
        }
        x
    };
    let c0 = cost(&x0)?;
    // A step that leaves the physical range (a band limit's `T` at its bound 0), or a parameter
    // the band does not see ([`unseen`]), holds that parameter: its diagonal stays 0 (below).
    let mut held = vec![false; q];
    for a in 0..q {
        let (up, down) = (shifted(&[(a, hs[a])]), shifted(&[(a, -hs[a])]));
        let (Some(g_up), Some(g_down), Some(c_up), Some(c_down)) =
            (gradient(&up), gradient(&down), cost(&up), cost(&down))
        else {
            held[a] = true;
            continue;
        };
        let curvature = (c_up - 2.0 * c0 + c_down) / (hs[a] * hs[a]);
        // Not the delay (slot 0): a model whose delay the band does not see is no model.
        if a > 0 && unseen(curvature, hs[a]) {
            held[a] = true;
            continue;
        }
        let mixed = (g_up - g_down) / (2.0 * hs[a]);
        for k in 0..p {
            h[(k, p + a)] = mixed[k];
            h[(p + a, k)] = mixed[k];
        }
        h[(p + a, p + a)] = curvature;
        for b in (0..a).filter(|&b| !held[b]) {
            let corner = |sa: f64, sb: f64| cost(&shifted(&[(a, sa * hs[a]), (b, sb * hs[b])]));
            let v = (corner(1.0, 1.0)? - corner(1.0, -1.0)? - corner(-1.0, 1.0)? + corner(-1.0, -1.0)?)
                / (4.0 * hs[a] * hs[b]);
            h[(p + a, p + b)] = v;
            h[(p + b, p + a)] = v;
        }
    }
    Some((h, held))
}

/// The cost (in the fit's units, three quarters of a chi2) below which a step of the search's own
/// size leaves a nonlinear parameter unseen ([`unseen`]): its deviation would be some 30 of those
/// steps. The cost's sum over the band rounds at about 1e-5 of it there (a band limit's `T` with
/// no effect in the band, measured: a curvature of -8e-4 at a step of 3 us).
const UNSEEN_COST: f64 = 1e-3;

/// Whether a nonlinear parameter whose cost has `curvature` at the Hessian's step `h` (a fiftieth
/// of the search's first step, [`packed_with_steps`]) is not seen by the data: at that curvature,
/// a step of the search's own size would move the cost by less than [`UNSEEN_COST`] (the local
/// curvature extrapolated, the most the parameter can hold with the others fixed: a band
/// limit's `T`, whose effect grows as `T^16`, can move the cost more over a whole step). A band limit
/// accepted on a stand without one whose fit puts its corner far above the band (`T` = 5 us
/// to 0.76 ms beside a 30-40 Hz band top: its gain there moves as `(f/f_c)^16`) is such a one.
/// It is held like one at a bound ([`determined`]): before, its curvature at rounding's level (of
/// either sign) left every deviation of the model, `K`'s and the delay's too, `null` in the model
/// file, on 8 of 72 blocks of a campaign of runs with coloured angle noise and the band limit
/// accepted. A curvature beyond it is the data's: negative, the fit is no minimum, and the model
/// stays undetermined.
fn unseen(curvature: f64, h: f64) -> bool {
    let search_step = 50.0 * h;
    0.5 * curvature.abs() * search_step * search_step < UNSEEN_COST
}

/// The Hessian of the parameters the data determine, and their indices: a nonlinear parameter
/// at a bound (a band limit fitted at `T = 0`, whose gain moves as `T^(2n)` there, no curvature,
/// and a step below leaves the range; `held`) is held at its value: the others' covariance is the
/// one given it (conditional), its own undetermined. Before, one such parameter left every
/// deviation of the model undetermined, `K`'s and the delay's too. One the band does not see
/// ([`unseen`]) is held the same way. Any other parameter with no curvature leaves the model
/// undetermined: `None`. `p` linear parameters come first.
pub(super) fn determined(
    (h, held): (DMatrix<f64>, Vec<bool>),
    p: usize,
) -> Option<(DMatrix<f64>, Vec<usize>)> {
    let all = h.nrows();
    let held_at = |k: usize| k >= p && held[k - p];
    let curved = |k: usize| h[(k, k)].is_finite() && h[(k, k)] > 0.0;
    if (0..all).any(|k| !(held_at(k) || curved(k))) {
        return None;
    }
    let keep: Vec<usize> = (0..all).filter(|&k| !held_at(k)).collect();
    let n = keep.len();
    Some((DMatrix::from_fn(n, n, |i, j| h[(keep[i], keep[j])]), keep))
}

/// The covariance of the parameters `keep` (all linear ones first, then the curved nonlinear
/// ones, in `fit::pack`'s order) from their Hessian `h`, widened by `chi2_per_dof` and the
/// sandwich. `shares_at(x)` gives each group's cost and linear scores at packed `x`; the
/// nonlinear scores are their central differences at the steps `hs` around `x0`.
fn reduced_covariance(
    h: &DMatrix<f64>,
    chi2_per_dof: f64,
    shares_at: impl Fn(&[f64]) -> Option<Vec<(f64, DVector<f64>)>>,
    x0: &[f64],
    hs: &[f64],
    keep: &[usize],
    p: usize,
) -> Option<DMatrix<f64>> {
    let n = h.nrows();
    // Scale to unit diagonal before inverting: K (near 1) and k2 (1e-3) differ by orders.
    let s = DVector::from_iterator(n, (0..n).map(|k| 1.0 / h[(k, k)].sqrt()));
    let scaled = DMatrix::from_fn(n, n, |i, j| h[(i, j)] * s[i] * s[j]);
    let inverse = scaled.cholesky()?.inverse();
    let factor = TAPER_VARIANCE * chi2_per_dof.max(1.0);
    let matrix = DMatrix::from_fn(n, n, |i, j| factor * inverse[(i, j)] * s[i] * s[j]);
    // The sandwich: where the misfit is not spread like the weights say (a real record's misfit
    // piles up where some regressors live), the scores' own spread is the honest variance.
    let Some(at_x0) = shares_at(x0) else {
        return Some(matrix);
    };
    let shifted = |k: usize, d: f64| {
        let mut x = x0.to_vec();
        x[k] += d;
        x
    };
    let mut scores: Vec<DVector<f64>> = at_x0.iter().map(|(_, u)| -2.0 * u).collect();
    for (row, &k) in keep.iter().enumerate().skip(p) {
        let a = k - p;
        let (Some(up), Some(down)) = (shares_at(&shifted(a, hs[a])), shares_at(&shifted(a, -hs[a]))) else {
            return Some(matrix);
        };
        for (g, score) in scores.iter_mut().enumerate() {
            let slope = (up[g].0 - down[g].0) / (2.0 * hs[a]);
            *score = score.clone().insert_row(row, slope);
        }
    }
    let bread = DMatrix::from_fn(n, n, |i, j| inverse[(i, j)] * s[i] * s[j]);
    Some(match sandwich_widening(&bread, &scores, &matrix) {
        Some(widening) => DMatrix::from_fn(n, n, |i, j| widening[i] * widening[j] * matrix[(i, j)]),
        None => matrix,
    })
}

/// Clusters of adjacent groups the sandwich's scores are summed over (many bins each, so the
/// taper's correlation between neighbouring bins stays inside a cluster).
const SANDWICH_CLUSTERS: usize = 200;

/// Per parameter, the factor `sqrt(max(1, V_sandwich / V_model))` by which the model-based
/// standard deviation is widened (never narrowed: with a few hundred clusters the sandwich's
/// own variance is ~10 %). `V_sandwich = H^-1 M H^-1`, `M` the clusters' score outer products
/// with the small-sample factor `C / (C - 1)`. `None` with fewer than four clusters per
/// parameter (the meat would be too noisy to widen by).
fn sandwich_widening(
    bread: &DMatrix<f64>,
    scores: &[DVector<f64>],
    model: &DMatrix<f64>,
) -> Option<Vec<f64>> {
    let n = bread.nrows();
    let width = scores.len().div_ceil(SANDWICH_CLUSTERS).max(1);
    let meat = crate::ident::structural::sandwich::clustered_meat(scores, width)?;
    let v = bread * meat * bread;
    Some(
        (0..n)
            .map(|i| {
                let ratio = v[(i, i)] / model[(i, i)];
                if ratio.is_finite() {
                    ratio.max(1.0).sqrt()
                } else {
                    1.0
                }
            })
            .collect(),
    )
}

/// Where each nonlinear parameter sits in `fit::pack`'s vector.
struct Slots {
    skew: Option<usize>,
    lag: Option<usize>,
    band_limit: Option<usize>,
    resonances: usize,
}

fn slots(structure: &super::structure::Structure) -> Slots {
    let skew = structure.skew.then_some(1);
    let after_skew = 1 + 2 * usize::from(structure.skew);
    let lag = structure.lag.map(|_| after_skew);
    let after_lag = after_skew + structure.lag.map_or(0, super::structure::LagShape::parameters);
    Slots {
        skew,
        lag,
        band_limit: structure.band_limit.map(|_| after_lag),
        resonances: after_lag + usize::from(structure.band_limit.is_some()),
    }
}

/// The band limit's deviations (`T_s`, `corner_hz`, `reference_rate_hz` for the interpolated
/// shape, `gain_rise_at_band_top` at `top_hz`) from `cov`, `T` at nonlinear slot `at` (ms). The
/// corner `c / T` moves by `-c / T^2` per s of `T`, the rate `1 / T` by `-1 / T^2` (no corner or
/// rate, and no deviation, at `T = 0`); the rise by its slope, by central difference.
fn band_limit_std(shape: BandLimitShape, t: f64, top_hz: f64, cov: Option<&Covariance>, at: usize) -> Value {
    let n = cov.map_or(0, |c| c.n_linear);
    let h = 1e-3 * t.max(1e-6);
    let slope =
        (shape.rise_at(t + h, top_hz) - shape.rise_at((t - h).max(0.0), top_hz)) / (t + h - (t - h).max(0.0));
    let corner = -shape.corner_times_t() / (t * t);
    let rate = -1.0 / (t * t);
    let of = |slope: f64| cov.and_then(|c| c.std_of(&[(n + at, slope * 1e-3)]));
    let mut v = json!({
        "T_s": cov.and_then(|c| c.nonlinear_std(at)).map(|v| v * 1e-3),
        "corner_hz": of(corner).filter(|_| shape.corner_hz(t).is_some()),
        "gain_rise_at_band_top": of(slope),
    });
    // Under the same keys as the parameters: a reference rate for the interpolated shape only.
    if shape == BandLimitShape::Interpolated {
        v["reference_rate_hz"] = json!(of(rate).filter(|_| shape.reference_rate_hz(t).is_some()));
    }
    v
}

/// Standard deviation of the delay `tau`, s.
#[must_use]
pub fn tau_std(cov: &Covariance) -> Option<f64> {
    cov.nonlinear_std(0).map(|v| v * 1e-3)
}

/// The standard deviations of [`super::report::parameters`]'s figures, under the same keys
/// (`null` where not determined or not computed).
#[must_use]
pub fn parameter_std(effect: Effect, state: &State, index: usize, cov: Option<&Covariance>) -> Value {
    let f = &state.fitted;
    let linear3 = |at: Option<usize>| at.map(|p| [0, 1, 2].map(|i| cov.and_then(|c| c.linear_std(p + i))));
    let slot = slots(&f.structure);
    let n = cov.map_or(0, |c| c.n_linear);
    match effect {
        Effect::GSensitivity => {
            let g = f
                .layout
                .g
                .map(|p| [0, 1, 2].map(|i| [0, 1, 2].map(|j| cov.and_then(|c| c.linear_std(p + 3 * i + j)))));
            json!({"G": g})
        }
        Effect::SensorLag | Effect::ReferenceLag => {
            let t_std = slot.lag.and_then(|k| cov?.nonlinear_std(k)).map(|v| v * 1e-3);
            if f.structure.lag != Some(super::structure::LagShape::SecondOrder) {
                return json!({"T_s": t_std});
            }
            // The damping is searched as its logarithm: its deviation is `zeta` times that one's;
            // the natural frequency `1 / (2 pi T)` moves by `-1 / (2 pi T^2)` per s of `T` (`T`
            // in ms), the corner `f_n r(zeta)` with it and with the damping (`r`'s slope by
            // central difference, per unit of `ln zeta`).
            let (t, zeta) = (f.theta.lag_s, f.theta.lag_damping);
            let mut v = json!({
                "T_s": t_std,
                "damping": slot.lag.and_then(|k| cov?.nonlinear_std(k + 1)).map(|v| v * zeta),
            });
            if t > 0.0 {
                let natural = 1.0 / (2.0 * std::f64::consts::PI * t);
                let ratio = super::structure::LagShape::corner_ratio;
                let h = 1e-6 * zeta;
                let ratio_slope = zeta * (ratio(zeta + h) - ratio(zeta - h)) / (2.0 * h);
                let d_t = -natural / t * 1e-3;
                v["natural_frequency_hz"] = json!(slot.lag.and_then(|k| cov?.std_of(&[(n + k, d_t)])));
                v["corner_hz"] = json!(slot.lag.and_then(|k| {
                    cov?.std_of(&[(n + k, d_t * ratio(zeta)), (n + k + 1, natural * ratio_slope)])
                }));
            }
            v
        }
        Effect::ReferenceBandLimit => {
            let (Some(at), Some(shape)) = (slot.band_limit, f.structure.band_limit) else {
                return Value::Null;
            };
            let top = state.design.frequency_hz.last().copied().unwrap_or(0.0);
            band_limit_std(shape, f.theta.band_limit_t_s, top, cov, at)
        }
        Effect::AxisTimeSkew => {
            let Some(a) = slot.skew else { return Value::Null };
            // Channel skews [a, b, -a - b] (ms in the vector); delays add tau (slot 0).
            let skews: [&[(usize, f64)]; 3] = [
                &[(n + a, 1.0)],
                &[(n + a + 1, 1.0)],
                &[(n + a, -1.0), (n + a + 1, -1.0)],
            ];
            let skew = skews.map(|t| cov.and_then(|c| c.std_of(t)).map(|v| v * 1e-3));
            let delay = skews.map(|t| {
                let mut t = t.to_vec();
                t.push((n, 1.0));
                cov.and_then(|c| c.std_of(&t)).map(|v| v * 1e-3)
            });
            json!({"channel_delay_s": delay, "skew_s": skew})
        }
        Effect::ScaleNonlinearity => json!({"k2": linear3(f.layout.k2)}),
        Effect::LeverArmError => json!({"offset_m": linear3(f.layout.lever_arm)}),
        Effect::PlatformResonance => {
            let at = slot.resonances + 2 * index;
            let zeta = f.theta.resonances.get(index).map_or(0.0, |r| r.1);
            json!({
                "frequency_hz": cov.and_then(|c| c.nonlinear_std(at)),
                // x = ln(zeta): sd(zeta) = zeta sd(x).
                "damping": cov.and_then(|c| c.nonlinear_std(at + 1)).map(|v| v * zeta),
            })
        }
        Effect::ClockDrift => {
            let duration = state.design.n_samples as f64 / state.design.sample_rate_hz;
            let sd = state.clock_drift_std;
            json!({"drift_ppm": sd.map(|v| v * 1e6), "delay_change_s": sd.map(|v| v * duration)})
        }
        Effect::VibrationTone => state.tones.get(index).map_or(Value::Null, |t| {
            // Each channel's chi2 is measured against its own local continuum (so already
            // widened by it), in untapered units. The three channels count as n_eff independent
            // ones where their disturbance is correlated (the angle noise reaches all three): the
            // chi2 summed over them is worth n_eff / 3 of its face value. Not the evidence's
            // chi2, which weighs the channels by the inverse of their correlation: right for
            // telling a line from a peak of motion all three share, ten times too large for a
            // size's deviation where the channels are nearly collinear.
            let (design, residual) = match (t.upper, state.upper.as_deref()) {
                (true, Some(upper)) => (upper, &state.upper_residual),
                _ => (&state.design, &state.residual),
            };
            let chi2 = (t.channel_chi2.iter().sum::<f64>()
                * effective_channels(design, residual, t.frequency_hz)
                / 3.0)
                .max(f64::MIN_POSITIVE);
            let n = state.design.n_samples as f64;
            let frequency = (12.0 * TAPER_FREQUENCY_VARIANCE / chi2).sqrt()
                / (2.0 * std::f64::consts::PI * n)
                * state.design.sample_rate_hz;
            let amplitude = t.unit_std.map(|u| u * TAPER_VARIANCE.sqrt());
            json!({"frequency_hz": frequency, "amplitude": amplitude})
        }),
    }
}

/// Bins each side of a line over which the channels' correlation is measured.
const CORRELATION_HALF: usize = 60;

/// The effective number of independent channels of `residual` around `f_hz`: `9 / sum |rho_ij|^2`
/// of the channels' correlation over the bins near it (3 when uncorrelated, 1 when identical).
fn effective_channels(
    design: &super::design::Design,
    residual: &[Vec<num_complex::Complex64>; 3],
    f_hz: f64,
) -> f64 {
    let n = design.n_bins();
    let df = design.sample_rate_hz / design.fft_len as f64;
    let at = ((f_hz / df).round() as usize)
        .saturating_sub(design.first_bin)
        .min(n.saturating_sub(1));
    let range = at.saturating_sub(CORRELATION_HALF)..(at + CORRELATION_HALF + 1).min(n);
    let c = |i: usize, j: usize| -> num_complex::Complex64 {
        range
            .clone()
            .map(|k| residual[i][k] * residual[j][k].conj())
            .sum()
    };
    let diag = [0, 1, 2].map(|i| c(i, i).re);
    if diag.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return 3.0;
    }
    let mut sum = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            sum += c(i, j).norm_sqr() / (diag[i] * diag[j]);
        }
    }
    (9.0 / sum).clamp(1.0, 3.0)
}

#[cfg(test)]
#[path = "uncertainty_tests.rs"]
mod tests;
