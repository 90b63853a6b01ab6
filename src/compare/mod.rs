//! Comparing identified models of several runs (regimes) of the same unit: K and tau side by side,
//! their pairwise differences, and whether each difference is significant
//! (`|diff| > SIGNIFICANCE_SIGMAS * sqrt(std_a^2 + std_b^2)`). Written by `imu-attest compare`
//! (schema [`COMPARISON_SCHEMA`]) and shown by the app's Compare tab.
//!
//! Units: K dimensionless, tau in s, as in the model file. A standard deviation the data cannot
//! determine is `None` (`null` in JSON); a difference involving one is not judged (`significant`
//! is `None`). Non-finite inputs propagate to `None` standard deviations and are never flagged.
//! Blocks are compared only where both runs have them.

use std::collections::BTreeMap;

pub mod findings;
pub mod mount;

use serde::{Deserialize, Serialize};

use crate::ident::settings::Settings;
use crate::model::{BlockModel, Model, Source};

/// The schema id of the comparison file.
pub const COMPARISON_SCHEMA: &str = "imu-attest/comparison/1";

/// How many combined standard deviations make a difference significant.
pub const SIGNIFICANCE_SIGMAS: f64 = 3.0;

/// A comparison file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Always [`COMPARISON_SCHEMA`].
    pub schema: String,
    /// The identifier settings as used on the first run (its model's echo). A run on which they
    /// were used otherwise (a segment the program fitted to a shorter record) carries its own
    /// ([`ComparedRun::settings`]).
    pub settings: Settings,
    /// The significance threshold, in combined standard deviations.
    pub significance_sigmas: f64,
    /// Each run, in the order given.
    pub runs: Vec<ComparedRun>,
    /// Every pair of runs `a < b`, per block both have.
    pub differences: Vec<Difference>,
    /// With `compare --diagnose` (or runs diagnosed in the app): every pair's findings compared
    /// ([`findings::compare_findings`]); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub findings: Option<Vec<findings::FindingDifference>>,
}

impl Comparison {
    /// Whether the runs' models of `block` have different structural orders (their `K` are then
    /// static gains of different structures, which the engineer should be told).
    #[must_use]
    pub fn orders_differ(&self, block: &str) -> bool {
        self.runs_differ(block, |b| b.order)
    }

    /// Whether some runs' `K` of `block` are the gain at low frequency (an even gain in the
    /// model) and others' the band's mean gain: their difference then holds the even gain's
    /// bias too, which the engineer should be told.
    #[must_use]
    pub fn gains_differ_in_kind(&self, block: &str) -> bool {
        self.runs_differ(block, |b| b.k_at_low_frequency)
    }

    /// Whether the runs that have `block` differ in `figure`.
    fn runs_differ<T: PartialEq>(&self, block: &str, figure: impl Fn(&BlockFigures) -> T) -> bool {
        let mut values = self.runs.iter().filter_map(|r| r.blocks.get(block)).map(figure);
        values.next().is_some_and(|first| values.any(|v| v != first))
    }

    /// A pair's label: `later - earlier`, by file (two runs of one regime differ).
    #[must_use]
    pub fn difference_header(&self, d: &Difference) -> String {
        let file = |i: usize| self.runs.get(i).map_or("?", |r| r.source.file.as_str());
        format!("{} - {}", file(d.runs[1]), file(d.runs[0]))
    }

    /// Per pair of runs with a split of `block`'s K ([`mount::MountSplit`]): the pair's label and
    /// whether the axes' rotation and the block's own figures differ, in words (the command line
    /// prints them, the Compare tab shows them).
    #[must_use]
    pub fn mount_lines(&self, block: &str) -> Vec<String> {
        self.differences
            .iter()
            .filter(|d| d.block == block)
            .filter_map(|d| {
                Some(format!(
                    "{}: {}",
                    self.difference_header(d),
                    d.mount.as_ref()?.words()
                ))
            })
            .collect()
    }
}

/// One run's figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ComparedRun {
    /// Where the model came from.
    pub source: Source,
    /// The settings as used on this run, when they differ from [`Comparison::settings`];
    /// absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settings: Option<Settings>,
    /// Per block (`"gyro"`, `"accel"`).
    pub blocks: BTreeMap<String, BlockFigures>,
    /// The run's blocks its identification refused (`Model::refused_blocks`): compared in no
    /// pair. Absent when none was.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub refused_blocks: BTreeMap<String, crate::model::RefusedBlock>,
    /// The diagnosis's verdict, when the runs' findings are compared.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<crate::diagnose::Verdict>,
}

/// A block's static gain and delay with their standard deviations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockFigures {
    /// Static gain.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Its standard deviation.
    #[serde(rename = "K_std")]
    pub k_std: [[Option<f64>; 3]; 3],
    /// Delay, s.
    pub tau_s: f64,
    /// Its standard deviation, s.
    pub tau_std_s: Option<f64>,
    /// Structural order.
    pub order: usize,
    /// Whether `K` is the gain at low frequency under an even gain in the model (the gain changes
    /// across the band with no phase, `gain_changes_across_band`); otherwise it is as fitted.
    #[serde(default)]
    pub k_at_low_frequency: bool,
}

impl BlockFigures {
    fn from_model(b: &BlockModel) -> Self {
        Self {
            k: b.k,
            k_std: b.fit.k_std,
            tau_s: b.tau_s,
            tau_std_s: b.fit.tau_std_s,
            order: b.order,
            k_at_low_frequency: b.even_gain.is_some(),
        }
    }
}

/// One figure's difference `b - a` between two runs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Delta {
    /// `b - a`.
    pub diff: f64,
    /// `sqrt(std_a^2 + std_b^2)`, when both are known.
    pub std: Option<f64>,
    /// `|diff| > SIGNIFICANCE_SIGMAS * std`; `None` when `std` is unknown.
    pub significant: Option<bool>,
}

impl Delta {
    /// The difference of `b - a` with standard deviations `sa`, `sb`.
    #[must_use]
    pub fn new(a: f64, sa: Option<f64>, b: f64, sb: Option<f64>) -> Self {
        let diff = b - a;
        let std = match (sa, sb) {
            (Some(x), Some(y)) => Some(x.hypot(y)).filter(|s| s.is_finite()),
            _ => None,
        };
        let significant = std
            .filter(|_| diff.is_finite())
            .map(|s| diff.abs() > SIGNIFICANCE_SIGMAS * s);
        Self {
            diff: if diff.is_finite() { diff } else { 0.0 },
            std,
            significant: if diff.is_finite() { significant } else { None },
        }
    }
}

/// Differences between two runs for one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Difference {
    /// The block.
    pub block: String,
    /// Indices into [`Comparison::runs`], `a < b`.
    pub runs: [usize; 2],
    /// Their regimes.
    pub regimes: [String; 2],
    /// Per element of K.
    #[serde(rename = "K")]
    pub k: [[Delta; 3]; 3],
    /// Of tau, s.
    pub tau_s: Delta,
    /// Any element of K or tau significantly different.
    pub significant: bool,
    /// The difference of `K` split into the mount's rotation and the block's own axes
    /// ([`mount::MountSplit`]); absent when either `K` is too far from the identity for it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount: Option<mount::MountSplit>,
}

/// Why a comparison cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// Fewer than two models.
    #[error("a comparison needs at least two runs, got {0}")]
    TooFewRuns(usize),
}

/// Compares `models` (at least two), pairwise in the order given.
///
/// # Errors
/// [`CompareError::TooFewRuns`] for fewer than two models.
pub fn compare(models: &[Model]) -> Result<Comparison, CompareError> {
    let [first, _, ..] = models else {
        return Err(CompareError::TooFewRuns(models.len()));
    };
    let runs: Vec<ComparedRun> = models
        .iter()
        .map(|m| ComparedRun {
            source: m.source.clone(),
            settings: (m.settings != first.settings).then(|| m.settings.clone()),
            blocks: m
                .blocks
                .iter()
                .map(|(name, b)| (name.clone(), BlockFigures::from_model(b)))
                .collect(),
            refused_blocks: m.refused_blocks.clone(),
            verdict: None,
        })
        .collect();
    let mut differences = Vec::new();
    for a in 0..runs.len() {
        for b in a + 1..runs.len() {
            for (name, fa) in &runs[a].blocks {
                if let Some(fb) = runs[b].blocks.get(name) {
                    differences.push(difference(name, [a, b], &runs, fa, fb));
                }
            }
        }
    }
    Ok(Comparison {
        schema: COMPARISON_SCHEMA.to_owned(),
        settings: first.settings.clone(),
        significance_sigmas: SIGNIFICANCE_SIGMAS,
        runs,
        differences,
        findings: None,
    })
}

impl Comparison {
    /// Adds the runs' diagnoses: each run's verdict and every pair's findings compared.
    /// `reports[i]` is run `i`'s; `names` labels the runs in the words. Reports of another
    /// count than the runs leave the comparison as it was.
    pub fn add_findings(&mut self, reports: &[&crate::diagnose::Report], names: &[String]) {
        if reports.len() != self.runs.len() {
            return;
        }
        for (run, report) in self.runs.iter_mut().zip(reports) {
            run.verdict = Some(report.verdict);
        }
        let findings: Vec<&[crate::diagnose::Finding]> =
            reports.iter().map(|r| r.findings.as_slice()).collect();
        let mut compared = findings::compare_findings(&findings, names);
        // A block one run of the pair could not identify was not diagnosed there: its findings
        // on the other run are not "named on one run only" (absence there says nothing).
        let refused = |i: usize, block: crate::block::Block| {
            self.runs[i].refused_blocks.contains_key(block.name())
                || reports[i].refused_blocks.contains_key(block.name())
        };
        compared.retain(|d| !refused(d.runs[0], d.block) && !refused(d.runs[1], d.block));
        self.findings = Some(compared);
    }
}

fn difference(
    block: &str,
    [a, b]: [usize; 2],
    runs: &[ComparedRun],
    fa: &BlockFigures,
    fb: &BlockFigures,
) -> Difference {
    let k: [[Delta; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| Delta::new(fa.k[i][j], fa.k_std[i][j], fb.k[i][j], fb.k_std[i][j]))
    });
    let tau_s = Delta::new(fa.tau_s, fa.tau_std_s, fb.tau_s, fb.tau_std_s);
    let significant = k
        .iter()
        .flatten()
        .chain([&tau_s])
        .any(|d| d.significant == Some(true));
    let mount = mount::MountSplit::new(fa, fb, &k, &tau_s);
    Difference {
        block: block.to_owned(),
        runs: [a, b],
        regimes: [runs[a].source.regime.clone(), runs[b].source.regime.clone()],
        k,
        tau_s,
        significant,
        mount,
    }
}

#[cfg(test)]
mod tests;
