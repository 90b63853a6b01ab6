//! The diagnosis's findings compared across runs of the same unit (issue 15): an effect of the
//! sensor is one property of it, so where two runs both name it its sizes must agree within
//! their standard deviations; where they do not, the misfit of that form is not one fixed
//! property of the unit (the runs' motion or reference shape it), and the engineer is told.
//! An effect named on one run only is listed as such: the other run's motion may not excite it
//! (a quadratic scale factor needs high rates), so absence alone is not a disagreement.
//!
//! Findings of the same block and effect are paired in the order the diagnosis named them.
//! Their sizes are compared figure by figure: every number under the effect's size keys
//! (`describe::size_keys`; all keys for effects located rather than sized) of a finding's
//! `parameters` that has a standard deviation entry (a number or `null`) in its `parameter_std`,
//! named by its key and index (`k2[2]`, `G[0][1]`), and a second-order lag's damping
//! ([`shape_figures`]). Findings of other shapes (a band limit's, a lag's) are not compared by
//! their time constants, which are other figures in each. A difference is significant as in [`super::Delta`]: beyond
//! [`super::SIGNIFICANCE_SIGMAS`] combined standard deviations; `None` where one is unknown.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::{Delta, SIGNIFICANCE_SIGMAS};
use crate::block::Block;
use crate::diagnose::Finding;
use crate::diagnose::structure::LagShape;
use crate::effect::Effect;
use crate::model::band_limit::BandLimitShape;

/// Which of the two runs named the effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Presence {
    /// Both.
    Both,
    /// The first of the pair only.
    OnlyA,
    /// The second of the pair only.
    OnlyB,
}

/// One figure of a finding's size in both runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SizeDelta {
    /// The figure: its key in `parameters` and its index (`k2[2]`).
    pub name: String,
    /// In the first run.
    pub a: f64,
    /// In the second run.
    pub b: f64,
    /// Its standard deviation in the first run (`None`: unknown).
    pub a_std: Option<f64>,
    /// In the second.
    pub b_std: Option<f64>,
    /// `b - a`, its standard deviation and significance.
    #[serde(flatten)]
    pub delta: Delta,
}

/// One effect of one block compared between two runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FindingDifference {
    /// The block.
    pub block: Block,
    /// The catalogue entry.
    pub effect: Effect,
    /// Indices into the comparison's runs, `a < b`.
    pub runs: [usize; 2],
    /// Which run named it.
    pub presence: Presence,
    /// The sizes side by side (empty unless both named it).
    pub sizes: Vec<SizeDelta>,
    /// Both named it and no figure differs significantly (`None` unless both named it and at
    /// least one figure could be judged).
    pub consistent: Option<bool>,
    /// The comparison in words.
    pub words: String,
}

/// The numbers of `v` with their names (`key[i][j]`), in order.
fn leaves(name: &str, v: &Value, out: &mut Vec<(String, Option<f64>)>) {
    match v {
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                leaves(&format!("{name}[{i}]"), x, out);
            }
        }
        Value::Null => out.push((name.to_owned(), None)),
        other => out.push((name.to_owned(), other.as_f64())),
    }
}

/// A finding's size figures that have a standard deviation entry: `(name, value, std)`.
#[must_use]
pub fn figures(f: &Finding) -> Vec<(String, f64, Option<f64>)> {
    let (Value::Object(params), Value::Object(stds)) = (&f.parameters, &f.parameter_std) else {
        return Vec::new();
    };
    // An effect's size only (a skew's channel delays hold the block's delay too); effects that
    // are located rather than sized (tones, resonances) by every figure.
    let keys = crate::diagnose::describe::size_keys(f.effect);
    let mut out = Vec::new();
    for (key, std) in stds {
        if !keys.is_empty() && !keys.contains(&key.as_str()) {
            continue;
        }
        let Some(value) = params.get(key) else { continue };
        let (mut values, mut sds) = (Vec::new(), Vec::new());
        leaves(key, value, &mut values);
        leaves(key, std, &mut sds);
        if values.len() != sds.len() {
            continue;
        }
        for ((name, v), (_, sd)) in values.into_iter().zip(sds) {
            if let Some(v) = v.filter(|v| v.is_finite()) {
                out.push((name, v, sd.filter(|s| s.is_finite() && *s > 0.0)));
            }
        }
    }
    out
}

/// A finding's figures of its shape where the shape has them: a second-order lag's damping
/// (`(name, value, std)` as [`figures`]'). Not a size (a damping is never near zero, and
/// `describe::size_within_noise` judges sizes only), but one property of the unit: two runs'
/// second-order lags are the same filter only with the same damping.
#[must_use]
pub fn shape_figures(f: &Finding) -> Vec<(String, f64, Option<f64>)> {
    let lag = matches!(f.effect, Effect::SensorLag | Effect::ReferenceLag);
    if !(lag && LagShape::of_parameters(&f.parameters) == LagShape::SecondOrder) {
        return Vec::new();
    }
    let Some(zeta) = f.parameters.get("damping").and_then(Value::as_f64) else {
        return Vec::new();
    };
    let sd = f.parameter_std.get("damping").and_then(Value::as_f64);
    vec![(
        "damping".to_owned(),
        zeta,
        sd.filter(|s| s.is_finite() && *s > 0.0),
    )]
}

/// Compares two findings of the same block and effect (or one finding's sizes on two stretches
/// of a record: `diagnose::halves`), figure by figure.
#[must_use]
pub fn sizes(a: &Finding, b: &Finding) -> Vec<SizeDelta> {
    paired(figures(a), &figures(b))
}

/// Two findings of the same block and effect compared (two runs', or one finding's on two
/// stretches of a record: `diagnose::halves`): their sizes and their shapes' figures
/// ([`shape_figures`]).
#[must_use]
pub fn sizes_and_shapes(a: &Finding, b: &Finding) -> Vec<SizeDelta> {
    let mut out = sizes(a, b);
    out.extend(paired(shape_figures(a), &shape_figures(b)));
    out
}

/// The figures of `fa` paired by name with `fb`'s.
fn paired(fa: Vec<(String, f64, Option<f64>)>, fb: &[(String, f64, Option<f64>)]) -> Vec<SizeDelta> {
    fa.into_iter()
        .filter_map(|(name, va, sa)| {
            let (_, vb, sb) = fb.iter().find(|(n, _, _)| *n == name)?;
            Some(SizeDelta {
                delta: Delta::new(va, sa, *vb, *sb),
                name,
                a: va,
                b: *vb,
                a_std: sa,
                b_std: *sb,
            })
        })
        .collect()
}

/// The figure that differs by the most standard deviations among the significant ones, with
/// that number.
#[must_use]
pub fn most_different(sizes: &[SizeDelta]) -> Option<(&SizeDelta, f64)> {
    sizes
        .iter()
        .filter(|s| s.delta.significant == Some(true))
        .filter_map(|s| s.delta.std.map(|sd| (s, s.delta.diff.abs() / sd)))
        .max_by(|x, y| x.1.total_cmp(&y.1))
}

/// The words of a compared pair (`names` of the two runs).
fn words(presence: Presence, sizes: &[SizeDelta], names: [&str; 2]) -> String {
    match presence {
        Presence::OnlyA | Presence::OnlyB => {
            let (on, off) = if presence == Presence::OnlyA {
                (names[0], names[1])
            } else {
                (names[1], names[0])
            };
            format!("named on {on} only: {off}'s motion may not excite it, or it is not the unit's")
        }
        Presence::Both => match most_different(sizes) {
            Some((s, z)) => format!(
                "named on both, but its {} differs ({} {:.4e} against {:.4e}, {z:.1} standard deviations \
                     apart): not one fixed property of the unit, the runs' motion or reference shape it",
                if s.name == "damping" { "shape" } else { "size" },
                s.name,
                s.a,
                s.b
            ),
            None if sizes.iter().any(|s| s.delta.significant.is_some()) => {
                format!("named on both, sizes agree within {SIGNIFICANCE_SIGMAS} standard deviations")
            }
            None => "named on both; sizes not judged (standard deviations unknown)".to_owned(),
        },
    }
}

/// `a`'s and `b`'s sizes over the same kind of band: where only one was sized over its usable
/// band (`diagnose::usable_band`: the other's band was given, as wide, or its model holds what
/// cannot be refitted there), its band searched's figures stand for it, as the other's are.
fn over_like_bands(a: &Finding, b: &Finding) -> Vec<SizeDelta> {
    let searched = |f: &Finding| {
        let mut g = f.clone();
        if let Some(s) = g.search_band.take() {
            g.parameters = s["parameters"].clone();
            g.parameter_std = s["parameter_std"].clone();
        }
        g
    };
    match (a.search_band.is_some(), b.search_band.is_some()) {
        (true, false) => sizes_and_shapes(&searched(a), b),
        (false, true) => sizes_and_shapes(a, &searched(b)),
        _ => sizes_and_shapes(a, b),
    }
}

/// Two findings' shapes where they differ, in words: a time constant `T` is another figure in
/// each shape, so their sizes are not compared. Band limits by `shape` and `order` (an
/// interpolated reference's `T` is its sample period, about `sqrt 6` times an order-1 shape's of
/// the same rise; two Butterworth orders fitted to one stand's limit put their corners
/// elsewhere; a report written before findings named their shape has `causal` and `order` only:
/// `causal2` or `zero_phase`). Lags by [`LagShape`] (a second order's `T` is `1 / w_n`, its
/// corner elsewhere by the damping).
fn shapes_differ(a: &Finding, b: &Finding) -> Option<String> {
    match a.effect {
        Effect::ReferenceBandLimit => {
            let shape = |f: &Finding| BandLimitShape::from_parameters(&f.parameters);
            let label = |s: Option<BandLimitShape>| {
                s.map_or_else(|| "an unnamed shape".to_owned(), BandLimitShape::label)
            };
            let (sa, sb) = (shape(a), shape(b));
            (sa != sb).then(|| format!("{} against {}", label(sa), label(sb)))
        }
        Effect::SensorLag | Effect::ReferenceLag => {
            let (sa, sb) = (
                LagShape::of_parameters(&a.parameters),
                LagShape::of_parameters(&b.parameters),
            );
            (sa != sb).then(|| format!("{} against {}", sa.what(), sb.what()))
        }
        _ => None,
    }
}

/// Every pair of runs `a < b`, every (block, effect) named on either, compared. `names` labels
/// the runs in the words (their files); `findings[i]` is run `i`'s diagnosis's findings. Sizes
/// are compared over like bands: where only one run's were fitted over its usable band
/// (`diagnose::usable_band`), its band searched's stand for it.
#[must_use]
pub fn compare_findings(findings: &[&[Finding]], names: &[String]) -> Vec<FindingDifference> {
    let mut out = Vec::new();
    for a in 0..findings.len() {
        for b in a + 1..findings.len() {
            let (ra, rb) = (findings[a], findings[b]);
            let keys: Vec<(Block, Effect)> = ra.iter().chain(rb).map(|f| (f.block, f.effect)).collect();
            let mut seen: Vec<(Block, Effect)> = Vec::new();
            for key in keys {
                if seen.contains(&key) {
                    continue;
                }
                seen.push(key);
                let of = |r: &[Finding]| -> Vec<Finding> {
                    r.iter().filter(|f| (f.block, f.effect) == key).cloned().collect()
                };
                let (fa, fb) = (of(ra), of(rb));
                for k in 0..fa.len().max(fb.len()) {
                    let presence = match (fa.get(k), fb.get(k)) {
                        (Some(_), Some(_)) => Presence::Both,
                        (Some(_), None) => Presence::OnlyA,
                        _ => Presence::OnlyB,
                    };
                    let other_shapes = match (fa.get(k), fb.get(k)) {
                        (Some(x), Some(y)) => shapes_differ(x, y),
                        _ => None,
                    };
                    let sizes = match (fa.get(k), fb.get(k)) {
                        (Some(x), Some(y)) if other_shapes.is_none() => over_like_bands(x, y),
                        _ => Vec::new(),
                    };
                    let judged: Vec<bool> = sizes.iter().filter_map(|s| s.delta.significant).collect();
                    let consistent =
                        (presence == Presence::Both && !judged.is_empty()).then(|| !judged.contains(&true));
                    let label = |i: usize| names.get(i).map_or("?", String::as_str);
                    out.push(FindingDifference {
                        block: key.0,
                        effect: key.1,
                        runs: [a, b],
                        presence,
                        words: match &other_shapes {
                            Some(shapes) => format!(
                                "named on both, in other shapes ({shapes}): their time constants are not \
                                 one figure, sizes not compared"
                            ),
                            None => words(presence, &sizes, [label(a), label(b)]),
                        },
                        sizes,
                        consistent,
                    });
                }
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "findings_tests.rs"]
mod tests;
