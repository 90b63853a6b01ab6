//! The campaign table: one row per run and block, the same columns on every row (empty where a
//! figure does not apply), written as CSV (a header line, shortest round-trip numbers, text
//! quoted where needed) or as a JSON array of objects with the columns in the same order.
//!
//! Per-channel columns are numbered by output channel (`_1.._3`, the row's `outputs` names
//! them) and input axis (`K_12`: output 1 from input 2), so gyro and accelerometer rows share a
//! header. Noise terms are in their display unit, named in the `*_unit` column.

use std::io::Write as _;
use std::path::Path;

use crate::model::{BlockModel, Model};
use crate::noise::terms::NoiseTerm;
use crate::output::{OutputError, write_atomic};

/// One cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Text.
    Text(String),
    /// A number (`None`: undetermined or not applicable; empty in CSV, `null` in JSON).
    Number(Option<f64>),
}

/// One row: named cells in column order.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchRow {
    /// `(column, cell)` in order.
    pub cells: Vec<(String, Cell)>,
}

const NOISE_COLUMNS: [(NoiseTerm, &str); 3] = [
    (NoiseTerm::RandomWalk, "random_walk"),
    (NoiseTerm::BiasInstability, "bias_instability"),
    (NoiseTerm::RateRandomWalk, "rate_random_walk"),
];

impl BatchRow {
    fn text(&mut self, name: &str, v: impl Into<String>) {
        self.cells.push((name.to_owned(), Cell::Text(v.into())));
    }

    fn number(&mut self, name: &str, v: Option<f64>) {
        self.cells
            .push((name.to_owned(), Cell::Number(v.filter(|x| x.is_finite()))));
    }

    /// The cell of `column`, if the row has it.
    #[must_use]
    pub fn get(&self, column: &str) -> Option<&Cell> {
        self.cells.iter().find(|(n, _)| n == column).map(|(_, c)| c)
    }

    /// A run that could not be processed: its file, `error` and every other column empty.
    #[must_use]
    pub fn failed(file: &str, error: &str) -> Self {
        let mut row = Self { cells: Vec::new() };
        fill(&mut row, file, "", "", "", None, None, "error", error);
        row
    }
}

/// The rows of an identified model (one per block), with the diagnosis's `verdict` if any, then
/// one row per block the identification refused (status `refused`, the reason as its error).
#[must_use]
pub fn rows_of(model: &Model, verdict: Option<&str>) -> Vec<BatchRow> {
    let s = &model.source;
    let row = |name: &str, b: Option<&BlockModel>, verdict: Option<&str>, status: &str, error: &str| {
        let mut row = BatchRow { cells: Vec::new() };
        fill(
            &mut row, &s.file, &s.sha256, &s.regime, name, b, verdict, status, error,
        );
        row
    };
    let identified = model
        .blocks
        .iter()
        .map(|(name, b)| row(name, Some(b), verdict, "ok", ""));
    let refused = model
        .refused_blocks
        .iter()
        .map(|(name, r)| row(name, None, None, "refused", &r.reason));
    identified.chain(refused).collect()
}

#[expect(clippy::too_many_arguments, reason = "one row's identity, in column order")]
fn fill(
    row: &mut BatchRow,
    file: &str,
    sha256: &str,
    regime: &str,
    block: &str,
    b: Option<&BlockModel>,
    verdict: Option<&str>,
    status: &str,
    error: &str,
) {
    row.text("run", file);
    row.text("sha256", sha256);
    row.text("regime", regime);
    row.text("block", block);
    row.text("status", status);
    row.text("error", error);
    row.text("outputs", b.map_or(String::new(), |b| b.outputs.join(" ")));
    row.text("inputs", b.map_or(String::new(), |b| b.inputs.join(" ")));
    for i in 0..3 {
        for j in 0..3 {
            row.number(&format!("K_{}{}", i + 1, j + 1), b.map(|b| b.k[i][j]));
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            row.number(
                &format!("K_std_{}{}", i + 1, j + 1),
                b.and_then(|b| b.fit.k_std[i][j]),
            );
        }
    }
    for i in 0..3 {
        row.number(
            &format!("scale_factor_error_ppm_{}", i + 1),
            b.map(|b| b.fit.scale_factor_error_ppm[i]),
        );
        row.number(
            &format!("scale_factor_error_std_ppm_{}", i + 1),
            b.and_then(|b| b.fit.scale_factor_error_std_ppm[i]),
        );
    }
    for i in 0..3 {
        for j in (0..3).filter(|&j| j != i) {
            row.number(
                &format!("misalignment_mrad_{}{}", i + 1, j + 1),
                b.map(|b| b.fit.misalignment_mrad[i][j]),
            );
            row.number(
                &format!("misalignment_std_mrad_{}{}", i + 1, j + 1),
                b.and_then(|b| b.fit.misalignment_std_mrad[i][j]),
            );
        }
    }
    row.number("tau_s", b.map(|b| b.tau_s));
    row.number("tau_std_s", b.and_then(|b| b.fit.tau_std_s));
    row.number("order", b.map(|b| b.order as f64));
    row.number("band_low_hz", b.map(|b| b.band_hz[0]));
    row.number("band_high_hz", b.map(|b| b.band_hz[1]));
    row.number("chi2_per_dof", b.map(|b| b.fit.chi2_per_dof));
    let block_kind = crate::block::Block::BOTH.into_iter().find(|k| k.name() == block);
    for (term, column) in NOISE_COLUMNS {
        for i in 0..3 {
            let value = b
                .and_then(|b| b.noise.as_ref())
                .and_then(|n| n.channels[i].term(term))
                .map(|t| t.value);
            row.number(&format!("{column}_{}", i + 1), value);
        }
        row.text(
            &format!("{column}_unit"),
            block_kind.map_or("", |k| term.unit_on(k).0),
        );
    }
    let mut warnings: Vec<String> = b.map_or_else(Vec::new, |b| {
        b.fit.warnings.iter().map(ToString::to_string).collect()
    });
    if let Some(n) = b.and_then(|b| b.noise.as_ref()) {
        warnings.extend(n.warnings.iter().map(ToString::to_string));
    }
    row.text("warnings", warnings.join(" | "));
    row.text("verdict", verdict.unwrap_or(""));
}

fn csv_field(cell: &Cell) -> String {
    match cell {
        Cell::Number(Some(v)) => format!("{v}"),
        Cell::Number(None) => String::new(),
        Cell::Text(t) if t.contains([',', '"', '\n', '\r']) => format!("\"{}\"", t.replace('"', "\"\"")),
        Cell::Text(t) => t.clone(),
    }
}

/// Writes `rows` to `path` atomically: JSON when the name ends in `.json`, CSV otherwise.
///
/// # Errors
/// [`write_atomic`]'s.
pub fn write_table(path: &Path, rows: &[BatchRow]) -> Result<(), OutputError> {
    let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    write_atomic(path, |w| {
        if json {
            w.write_all(b"[\n")?;
            for (k, row) in rows.iter().enumerate() {
                let fields: Vec<String> = row
                    .cells
                    .iter()
                    .map(|(name, cell)| {
                        let value = match cell {
                            Cell::Text(t) => serde_json::Value::from(t.as_str()),
                            Cell::Number(v) => v.map_or(serde_json::Value::Null, serde_json::Value::from),
                        };
                        format!("{}: {value}", serde_json::Value::from(name.as_str()))
                    })
                    .collect();
                let sep = if k + 1 < rows.len() { "," } else { "" };
                writeln!(w, "  {{{}}}{sep}", fields.join(", "))?;
            }
            w.write_all(b"]\n")
        } else {
            if let Some(first) = rows.first() {
                let header: Vec<&str> = first.cells.iter().map(|(n, _)| n.as_str()).collect();
                writeln!(w, "{}", header.join(","))?;
            }
            for row in rows {
                let line: Vec<String> = row.cells.iter().map(|(_, c)| csv_field(c)).collect();
                writeln!(w, "{}", line.join(","))?;
            }
            Ok(())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_row_has_every_column_and_csv_quotes_what_it_must() {
        let ok_columns = BatchRow::failed("a.csv", "x").cells.len();
        let row = BatchRow::failed("b, \"c\".csv", "line 3, column 2: not a number");
        assert_eq!(row.cells.len(), ok_columns);
        assert_eq!(csv_field(row.get("run").expect("run")), "\"b, \"\"c\"\".csv\"");
        assert_eq!(csv_field(&Cell::Number(Some(0.1))), "0.1");
        assert_eq!(csv_field(&Cell::Number(None)), "");
        let dir = tempfile::tempdir().expect("tempdir");
        for name in ["t.csv", "t.json"] {
            let path = dir.path().join(name);
            write_table(&path, std::slice::from_ref(&row)).expect("written");
            let text = std::fs::read_to_string(&path).expect("read");
            if std::path::Path::new(name)
                .extension()
                .is_some_and(|e| e == "json")
            {
                let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
                assert_eq!(v[0]["status"], "error");
                assert!(v[0]["tau_s"].is_null());
            } else {
                assert_eq!(text.lines().count(), 2);
                assert!(text.starts_with("run,sha256,regime,block,status,error,"));
            }
        }
    }
}
