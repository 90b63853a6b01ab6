//! `imu-attest batch`: a folder with a bad run among good ones gives every good run's rows and
//! one row naming the bad run's fault; the table's numbers are `identify`'s, bit for bit.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::Path;

use imu_attest::model::Model;

use crate::binary;
use binary::imu_attest;

fn simulate(dir: &Path, name: &str, regime: &str, seed: &str) {
    let out = dir.join(name);
    let o = imu_attest(&[
        "simulate",
        "--regime",
        regime,
        "--duration",
        "60",
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Splits a CSV line (quotes as the table writes them).
fn fields(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                let _ = chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

#[test]
fn a_bad_run_is_its_own_row_and_the_numbers_are_identifys() {
    let dir = tempfile::tempdir().unwrap();
    let runs = dir.path().join("campaign");
    std::fs::create_dir(&runs).unwrap();
    simulate(&runs, "a_cruise.csv", "cruise", "5");
    simulate(&runs, "c_approach.csv", "approach", "6");
    let bad = runs.join("b_broken.csv");
    let good = std::fs::read_to_string(runs.join("a_cruise.csv")).unwrap();
    let mut lines: Vec<&str> = good.lines().take(400).collect();
    lines[200] = "0.4,not-a-number,0,0,0,0,0,0,0,0,0,0,0";
    std::fs::write(&bad, lines.join("\n")).unwrap();

    let table = dir.path().join("table.csv");
    let o = imu_attest(&["batch", runs.to_str().unwrap(), "--out", table.to_str().unwrap()]);
    // A failed run: the whole table written, exit status 2 for a script to notice.
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("3 runs, 5 rows, 1 failed"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&table).unwrap();
    let mut lines = text.lines();
    let header = fields(lines.next().unwrap());
    let rows: Vec<Vec<String>> = lines.map(fields).collect();
    assert!(
        rows.iter().all(|r| r.len() == header.len()),
        "every row has every column"
    );
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let order: Vec<(&str, &str, &str)> = rows
        .iter()
        .map(|r| {
            (
                r[col("run")].as_str(),
                r[col("block")].as_str(),
                r[col("status")].as_str(),
            )
        })
        .collect();
    assert_eq!(
        order,
        [
            ("a_cruise.csv", "accel", "ok"),
            ("a_cruise.csv", "gyro", "ok"),
            ("b_broken.csv", "", "error"),
            ("c_approach.csv", "accel", "ok"),
            ("c_approach.csv", "gyro", "ok"),
        ]
    );
    let error = &rows[2][col("error")];
    assert!(
        error.contains("b_broken.csv:201:2") && error.contains("not a number"),
        "{error}"
    );

    // The same numbers as identify's model file.
    let model_path = dir.path().join("a_model.json");
    let o = imu_attest(&[
        "identify",
        runs.join("a_cruise.csv").to_str().unwrap(),
        "--out",
        model_path.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let model: Model = serde_json::from_str(&std::fs::read_to_string(&model_path).unwrap()).unwrap();
    for (row, block) in [(&rows[0], "accel"), (&rows[1], "gyro")] {
        let b = &model.blocks[block];
        let num = |name: &str| row[col(name)].parse::<f64>().unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(
                    num(&format!("K_{}{}", i + 1, j + 1)).to_bits(),
                    b.k[i][j].to_bits()
                );
            }
            assert_eq!(
                num(&format!("scale_factor_error_ppm_{}", i + 1)).to_bits(),
                b.fit.scale_factor_error_ppm[i].to_bits()
            );
            let arw =
                b.noise.as_ref().unwrap().channels[i].term(imu_attest::noise::terms::NoiseTerm::RandomWalk);
            let cell = &row[col(&format!("random_walk_{}", i + 1))];
            match arw {
                Some(t) => assert_eq!(cell.parse::<f64>().unwrap().to_bits(), t.value.to_bits()),
                None => assert!(cell.is_empty()),
            }
        }
        assert_eq!(num("tau_s").to_bits(), b.tau_s.to_bits());
        assert_eq!(row[col("sha256")], model.source.sha256);
    }
}

#[test]
fn a_json_table_with_the_diagnosis_and_bad_arguments() {
    let dir = tempfile::tempdir().unwrap();
    simulate(dir.path(), "run.csv", "cruise", "7");
    let run = dir.path().join("run.csv");
    let table = dir.path().join("t.json");
    let o = imu_attest(&[
        "batch",
        run.to_str().unwrap(),
        "--diagnose",
        "--out",
        table.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&table).unwrap()).unwrap();
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        let verdict = r["verdict"].as_str().unwrap();
        assert!(
            verdict == "no_missing_effect" || verdict.starts_with("effect_found"),
            "{verdict}"
        );
        assert!(r["tau_s"].as_f64().unwrap() > 0.0);
    }
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    for (args, needle) in [
        (
            vec!["batch", "--out", table.to_str().unwrap()],
            "at least one RUN",
        ),
        (
            vec!["batch", empty.to_str().unwrap(), "--out", table.to_str().unwrap()],
            "no run files",
        ),
        (
            vec!["batch", run.to_str().unwrap(), "--out", run.to_str().unwrap()],
            "refusing",
        ),
    ] {
        let o = imu_attest(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}
