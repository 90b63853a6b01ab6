//! Pass/fail against a specification (`report --spec SPEC.json`).
//!
//! ```json
//! {"gyro":  {"scale_factor_error_ppm": 500, "misalignment_mrad": 1.0, "tau_s": 0.005,
//!            "angle_random_walk": 0.1},
//!  "accel": {"scale_factor_error_ppm": 1000, "velocity_random_walk": 0.05}}
//! ```
//! Every limit is an upper bound on the magnitude of the figure, in the figure's unit: ppm, mrad,
//! s, and for noise terms their IEEE display unit (`deg/sqrt(h)`, `deg/h`, `m/s/sqrt(h)`, `ug`,
//! ...; see `noise::terms::NoiseTerm::unit_on`). Scale-factor errors are checked per channel,
//! misalignments per off-diagonal element, noise terms per channel.
//!
//! Each figure's 95 % band is `|value| -/+ 2 sigma` for the model's figures and the one-sigma
//! interval of a noise term stretched to two sigma. `pass`: the whole band is within the limit;
//! `fail`: the whole band is beyond it; `undecided`: the limit lies inside the band, or the
//! figure's uncertainty (or, for a noise term, the term itself) could not be determined.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::block::Block;
use crate::model::Model;
use crate::noise::terms::NoiseTerm;

/// A figure a limit can be put on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Quantity {
    /// `(K_ii - 1) 1e6`, ppm, per channel.
    ScaleFactorError,
    /// `K_ij 1e3`, mrad, per off-diagonal element.
    Misalignment,
    /// The delay, s.
    Delay,
    /// A noise term, in its display unit, per channel.
    Noise(NoiseTerm),
}

impl Quantity {
    /// Its id in a specification file, on `block`.
    #[must_use]
    pub fn id_on(self, block: Block) -> &'static str {
        match self {
            Quantity::ScaleFactorError => "scale_factor_error_ppm",
            Quantity::Misalignment => "misalignment_mrad",
            Quantity::Delay => "tau_s",
            Quantity::Noise(term) => term.id_on(block),
        }
    }

    /// Every quantity.
    #[must_use]
    pub fn all() -> Vec<Quantity> {
        let mut out = vec![
            Quantity::ScaleFactorError,
            Quantity::Misalignment,
            Quantity::Delay,
        ];
        out.extend(NoiseTerm::ALL.map(Quantity::Noise));
        out
    }
}

/// Why a specification file was refused.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// Unreadable file.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not JSON of the expected shape.
    #[error("{path}:{line}:{column}: not a specification at '{at}': {message}")]
    Parse {
        /// The file.
        path: String,
        /// Line of the error.
        line: usize,
        /// Column of the error.
        column: usize,
        /// JSON path.
        at: String,
        /// What is wrong.
        message: String,
    },
    /// A block name that is not `gyro` or `accel`.
    #[error("{path}: unknown block '{name}' (known: gyro, accel)")]
    UnknownBlock {
        /// The file.
        path: String,
        /// The name given.
        name: String,
    },
    /// A quantity name not known on that block.
    #[error("{path}: {block}: unknown quantity '{name}' (known: {known})")]
    UnknownQuantity {
        /// The file.
        path: String,
        /// The block.
        block: Block,
        /// The name given.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// A limit that is not a positive number.
    #[error("{path}: {block}.{name}: limit {value} is not a positive number")]
    BadLimit {
        /// The file.
        path: String,
        /// The block.
        block: Block,
        /// The quantity.
        name: String,
        /// The value given.
        value: f64,
    },
}

/// A specification: limits per block and quantity.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spec {
    /// `limits[block][quantity]`.
    pub limits: BTreeMap<Block, BTreeMap<Quantity, f64>>,
}

impl Spec {
    /// Reads and checks a specification file.
    ///
    /// # Errors
    /// [`SpecError`] naming the file and, for a parse error, line and column.
    pub fn read(path: &Path) -> Result<Self, SpecError> {
        let shown = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| SpecError::Read {
            path: shown.clone(),
            source,
        })?;
        Self::parse(&bytes, &shown)
    }

    /// Parses a specification (`path` only names it in errors).
    ///
    /// # Errors
    /// See [`Spec::read`].
    pub fn parse(bytes: &[u8], path: &str) -> Result<Self, SpecError> {
        let de = &mut serde_json::Deserializer::from_slice(bytes);
        let raw: BTreeMap<String, serde_json::Value> =
            serde_path_to_error::deserialize(de).map_err(|e| SpecError::Parse {
                path: path.to_owned(),
                line: e.inner().line(),
                column: e.inner().column(),
                at: e.path().to_string(),
                message: e.inner().to_string(),
            })?;
        let mut spec = Spec::default();
        for (name, entries) in raw {
            if name == "schema" {
                continue;
            }
            let block = Block::BOTH
                .into_iter()
                .find(|b| b.name() == name)
                .ok_or_else(|| SpecError::UnknownBlock {
                    path: path.to_owned(),
                    name: name.clone(),
                })?;
            let entries: BTreeMap<String, f64> =
                serde_json::from_value(entries).map_err(|e| SpecError::Parse {
                    path: path.to_owned(),
                    line: 0,
                    column: 0,
                    at: name.clone(),
                    message: format!("limits must be numbers: {e}"),
                })?;
            let limits = spec.limits.entry(block).or_default();
            for (key, value) in entries {
                let quantity = Quantity::all()
                    .into_iter()
                    .find(|q| q.id_on(block) == key)
                    .ok_or_else(|| SpecError::UnknownQuantity {
                        path: path.to_owned(),
                        block,
                        name: key.clone(),
                        known: Quantity::all()
                            .iter()
                            .map(|q| q.id_on(block))
                            .collect::<Vec<_>>()
                            .join(", "),
                    })?;
                if !(value.is_finite() && value > 0.0) {
                    return Err(SpecError::BadLimit {
                        path: path.to_owned(),
                        block,
                        name: key,
                        value,
                    });
                }
                limits.insert(quantity, value);
            }
        }
        Ok(spec)
    }
}

/// The verdict on one figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The whole band is within the limit.
    Pass,
    /// The whole band is beyond the limit.
    Fail,
    /// The limit is inside the band, or the uncertainty is unknown.
    Undecided,
}

/// One checked figure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    /// The run's file name.
    pub run: String,
    /// The block.
    pub block: Block,
    /// The quantity's id.
    pub quantity: String,
    /// Which channel or element (`gx`, `gx/wy`; empty for the delay).
    pub element: String,
    /// The figure's magnitude.
    pub value: f64,
    /// Its 95 % band on the magnitude (`None`: not determined).
    pub band: Option<[f64; 2]>,
    /// The limit.
    pub limit: f64,
    /// The unit of value and limit.
    pub unit: String,
    /// The verdict.
    pub verdict: Verdict,
}

fn verdict(band: Option<[f64; 2]>, limit: f64) -> Verdict {
    match band {
        Some([_, hi]) if hi <= limit => Verdict::Pass,
        Some([lo, _]) if lo > limit => Verdict::Fail,
        _ => Verdict::Undecided,
    }
}

/// A symmetric two-sigma band on `|value|`.
fn two_sigma(value: f64, std: Option<f64>) -> Option<[f64; 2]> {
    std.filter(|s| s.is_finite())
        .map(|s| [(value.abs() - 2.0 * s).max(0.0), value.abs() + 2.0 * s])
}

/// Checks every figure of `model` that `spec` limits.
#[must_use]
pub fn check(spec: &Spec, model: &Model) -> Vec<Check> {
    let mut out = Vec::new();
    for (&block, limits) in &spec.limits {
        let Some(b) = model.blocks.get(block.name()) else {
            // A block the run could not identify, or the model does not hold (a gyro-only run, or
            // a block left out of the settings), is not passed by saying nothing ("nothing
            // checked" for a gyro-only run against an accelerometer's limits):
            // each figure the specification limits is undecided, its element saying why.
            let why = if model.refused_blocks.contains_key(block.name()) {
                "block not identified"
            } else {
                "block not in the model"
            };
            for (&quantity, &limit) in limits {
                out.push(Check {
                    run: model.source.file.clone(),
                    block,
                    quantity: quantity.id_on(block).to_owned(),
                    element: why.to_owned(),
                    value: f64::NAN,
                    band: None,
                    limit,
                    unit: String::new(),
                    verdict: Verdict::Undecided,
                });
            }
            continue;
        };
        for (&quantity, &limit) in limits {
            let mut push = |element: String, value: f64, band: Option<[f64; 2]>, unit: &str| {
                out.push(Check {
                    run: model.source.file.clone(),
                    block,
                    quantity: quantity.id_on(block).to_owned(),
                    element,
                    value: value.abs(),
                    band,
                    limit,
                    unit: unit.to_owned(),
                    verdict: verdict(band, limit),
                });
            };
            match quantity {
                Quantity::ScaleFactorError => {
                    for i in 0..3 {
                        let v = b.fit.scale_factor_error_ppm[i];
                        push(
                            b.outputs[i].clone(),
                            v,
                            two_sigma(v, b.fit.scale_factor_error_std_ppm[i]),
                            "ppm",
                        );
                    }
                }
                Quantity::Misalignment => {
                    for i in 0..3 {
                        for j in (0..3).filter(|&j| j != i) {
                            let v = b.fit.misalignment_mrad[i][j];
                            let band = two_sigma(v, b.fit.misalignment_std_mrad[i][j]);
                            push(format!("{}/{}", b.outputs[i], b.inputs[j]), v, band, "mrad");
                        }
                    }
                }
                Quantity::Delay => push(String::new(), b.tau_s, two_sigma(b.tau_s, b.fit.tau_std_s), "s"),
                Quantity::Noise(term) => {
                    let unit = term.unit_on(block).0;
                    for (i, name) in b.outputs.iter().enumerate() {
                        let estimate = b.noise.as_ref().and_then(|n| n.channels[i].term(term));
                        let (value, band) = estimate.map_or((0.0, None), |t| {
                            let [lo, hi] = t.interval;
                            (
                                t.value,
                                Some([
                                    (t.value - 2.0 * (t.value - lo)).max(0.0),
                                    t.value + 2.0 * (hi - t.value),
                                ]),
                            )
                        });
                        push(name.clone(), value, band, unit);
                    }
                }
            }
        }
    }
    out
}

/// `"3 fail, 1 undecided, 12 pass"` (counts that are zero left out; `"nothing checked"`).
#[must_use]
pub fn summary(checks: &[Check]) -> String {
    let count = |v: Verdict| checks.iter().filter(|c| c.verdict == v).count();
    let parts: Vec<String> = [
        (Verdict::Fail, "fail"),
        (Verdict::Undecided, "undecided"),
        (Verdict::Pass, "pass"),
    ]
    .iter()
    .filter(|(v, _)| count(*v) > 0)
    .map(|(v, name)| format!("{} {name}", count(*v)))
    .collect();
    if parts.is_empty() {
        "nothing checked".to_owned()
    } else {
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_band() {
        assert_eq!(verdict(Some([1.0, 2.0]), 3.0), Verdict::Pass);
        assert_eq!(verdict(Some([1.0, 2.0]), 0.5), Verdict::Fail);
        assert_eq!(verdict(Some([1.0, 2.0]), 1.5), Verdict::Undecided);
        assert_eq!(verdict(None, 1.5), Verdict::Undecided);
        assert_eq!(two_sigma(-3.0, Some(1.0)), Some([1.0, 5.0]));
        assert_eq!(two_sigma(0.5, Some(1.0)), Some([0.0, 2.5]));
    }

    #[test]
    fn specification_files_are_checked_with_their_place() {
        let ok = Spec::parse(
            br#"{"gyro": {"tau_s": 0.005, "angle_random_walk": 0.1}}"#,
            "s.json",
        )
        .expect("valid");
        assert!((ok.limits[&Block::Gyro][&Quantity::Noise(NoiseTerm::RandomWalk)] - 0.1).abs() < 1e-15);
        let e =
            Spec::parse(br#"{"gyro": {"velocity_random_walk": 1}}"#, "s.json").expect_err("gyro has no VRW");
        assert!(
            e.to_string().contains("unknown quantity 'velocity_random_walk'")
                && e.to_string().contains("angle_random_walk"),
            "{e}"
        );
        let e = Spec::parse(br#"{"mag": {}}"#, "s.json").expect_err("unknown block");
        assert!(e.to_string().contains("unknown block 'mag'"), "{e}");
        let e = Spec::parse(br#"{"gyro": {"tau_s": -1}}"#, "s.json").expect_err("negative");
        assert!(e.to_string().contains("not a positive number"), "{e}");
        let e = Spec::parse(b"{\n \"gyro\": {\"tau_s\": 0.1,}}", "s.json").expect_err("bad JSON");
        assert!(e.to_string().starts_with("s.json:2:"), "{e}");
    }
}
