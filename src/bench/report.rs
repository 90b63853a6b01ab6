//! The benchmark's result: a table for people, one JSON line for programs.
//!
//! JSON: `{"samples": N, "rate_hz": R, "channels": C, "segment_len": L, "stages_s": {"load": ..},
//! "peak_rss_mb": ..}` plus `load_peak_rss_mb` and `decoded_mb`; the stages keep their order.
//! Memory is `null` where it cannot be measured.

use serde::Serialize;
use serde::ser::SerializeMap as _;

/// One stage's time.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTime {
    /// Stage name.
    pub name: &'static str,
    /// Wall time (the median of the repeats), s.
    pub seconds: f64,
    /// How many times it ran.
    pub repeats: usize,
    /// CPU time of all threads per run (the mean of the repeats), s; `None` where unmeasurable.
    pub cpu_seconds: Option<f64>,
}

/// What `bench` reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchReport {
    /// Samples (rows) of the run.
    pub samples: usize,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Distinct channels whose spectra are computed.
    pub channels: usize,
    /// Welch segment length, samples.
    pub segment_len: usize,
    /// Every stage's time, in order.
    #[serde(rename = "stages_s", serialize_with = "stages_as_map")]
    pub stages: Vec<StageTime>,
    /// Peak resident memory over the stages, MB.
    pub peak_rss_mb: Option<f64>,
    /// Peak resident memory over the `load` stage, MB.
    pub load_peak_rss_mb: Option<f64>,
    /// Size of the loaded columns (rows x columns x 8 bytes), MB.
    pub decoded_mb: f64,
    /// Whole commands run on the same file in child processes (`identify`, `discrepancy`):
    /// wall time and peak resident memory of each.
    #[serde(serialize_with = "commands_as_map", skip_serializing_if = "Vec::is_empty")]
    pub commands: Vec<CommandFigure>,
}

/// A whole command's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CommandFigure {
    /// The command (`identify`, `discrepancy`).
    #[serde(skip)]
    pub name: &'static str,
    /// Wall time, s.
    pub wall_s: f64,
    /// Peak resident memory (`VmHWM` at its exit), MB; `None` where not reported.
    pub peak_rss_mb: Option<f64>,
}

fn commands_as_map<S: serde::Serializer>(commands: &[CommandFigure], s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(commands.len()))?;
    for c in commands {
        map.serialize_entry(c.name, c)?;
    }
    map.end()
}

fn stages_as_map<S: serde::Serializer>(stages: &[StageTime], s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(stages.len()))?;
    for stage in stages {
        map.serialize_entry(stage.name, &stage.seconds)?;
    }
    map.end()
}

/// The stages' CPU times as a second map, `stages_cpu_s`.
struct CpuTimes<'a>(&'a [StageTime]);

impl Serialize for CpuTimes<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for stage in self.0 {
            map.serialize_entry(stage.name, &stage.cpu_seconds)?;
        }
        map.end()
    }
}

impl BenchReport {
    /// The one-line JSON object (the report's fields plus `stages_cpu_s`).
    #[must_use]
    pub fn to_json(&self) -> String {
        #[derive(Serialize)]
        struct Json<'a> {
            #[serde(flatten)]
            report: &'a BenchReport,
            stages_cpu_s: CpuTimes<'a>,
        }
        serde_json::to_string(&Json {
            report: self,
            stages_cpu_s: CpuTimes(&self.stages),
        })
        .unwrap_or_default()
    }

    /// The table: one line per stage, then the run's size and memory.
    #[must_use]
    pub fn to_table(&self) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let _ = writeln!(out, "{:<16} {:>10} {:>10}", "stage", "time (s)", "cpu (s)");
        for s in &self.stages {
            let note = if s.repeats > 1 {
                format!("  (median of {})", s.repeats)
            } else {
                String::new()
            };
            let cpu = s
                .cpu_seconds
                .map_or_else(|| "n/a".to_owned(), |c| format!("{c:.2}"));
            let _ = writeln!(out, "{:<16} {:>10.4} {cpu:>10}{note}", s.name, s.seconds);
        }
        let mb = |v: Option<f64>| v.map_or_else(|| "n/a".to_owned(), |v| format!("{v:.0} MB"));
        for c in &self.commands {
            let _ = writeln!(
                out,
                "command {:<10} {:>8.3} s   peak {}",
                c.name,
                c.wall_s,
                mb(c.peak_rss_mb)
            );
        }
        let _ = writeln!(
            out,
            "{} samples at {} Hz, {} channels, segment {}; decoded {:.0} MB; peak memory {} (load {})",
            self.samples,
            self.rate_hz,
            self.channels,
            self.segment_len,
            self.decoded_mb,
            mb(self.peak_rss_mb),
            mb(self.load_peak_rss_mb)
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_keeps_stage_order_and_names_every_key() {
        let report = BenchReport {
            samples: 10,
            rate_hz: 200.0,
            channels: 12,
            segment_len: 256,
            stages: vec![
                StageTime {
                    name: "load",
                    seconds: 0.5,
                    repeats: 1,
                    cpu_seconds: Some(0.75),
                },
                StageTime {
                    name: "aaa",
                    seconds: 0.25,
                    repeats: 3,
                    cpu_seconds: None,
                },
            ],
            peak_rss_mb: None,
            load_peak_rss_mb: Some(3.0),
            decoded_mb: 0.1,
            commands: vec![CommandFigure {
                name: "identify",
                wall_s: 1.5,
                peak_rss_mb: Some(42.0),
            }],
        };
        let json = report.to_json();
        assert!(!json.contains('\n'));
        assert!(json.contains(r#""stages_s":{"load":0.5,"aaa":0.25}"#), "{json}");
        assert!(json.contains(r#""peak_rss_mb":null"#), "{json}");
        assert!(
            json.contains(r#""stages_cpu_s":{"load":0.75,"aaa":null}"#),
            "{json}"
        );
        assert!(
            json.contains(r#""commands":{"identify":{"wall_s":1.5,"peak_rss_mb":42.0}}"#),
            "{json}"
        );
        assert!(report.to_table().contains("(median of 3)"));
        assert!(report.to_table().contains("command identify"));
    }
}
