//! `imu-attest report`: the certificate of the bundled sample run holds every section, names
//! nothing outside itself and renders in headless Chromium with the network cut; a specification
//! with one failing limit fails that figure and nothing else; bad input exits with status 2.
#![expect(clippy::unwrap_used, reason = "tests")]

use std::path::{Path, PathBuf};
use std::process::Command;

use imu_attest::model::Model;

use crate::binary;
use binary::imu_attest;

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample_runs")
        .join(name)
}

fn report(args: &[&str]) -> (std::process::Output, String) {
    let o = imu_attest(args);
    let out = args
        .iter()
        .position(|a| *a == "--out")
        .map(|i| args[i + 1])
        .unwrap();
    let html = std::fs::read_to_string(out).unwrap_or_default();
    (o, html)
}

/// Every section of the certificate, by the ids and classes the page gives them.
const SECTIONS: [&str; 12] = [
    "Dynamic certification report",
    "class=\"run\"",
    "class=\"settings\"",
    "id=\"block-gyro\"",
    "id=\"block-accel\"",
    "class=\"equation\"",
    "class=\"misalignment\"",
    "class=\"grid bode\"",
    "class=\"noise\"",
    "overlapping Allan deviation",
    "class=\"correlation\"",
    "id=\"diagnosis\"",
];

#[test]
fn the_sample_runs_certificate_holds_every_section_and_nothing_external() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cruise_report.html");
    let run = sample("cruise.csv.gz");
    let (o, html) = report(&["report", run.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for s in SECTIONS {
        assert!(html.contains(s), "section {s} missing");
    }
    // 9 Bode panels per block and one Allan plot per block.
    assert_eq!(html.matches("<svg").count(), 2 * 9 + 2);
    let sha = {
        use sha2::Digest as _;
        let digest = sha2::Sha256::digest(std::fs::read(&run).unwrap());
        digest.iter().fold(String::new(), |mut s, b| {
            use std::fmt::Write as _;
            let _ = write!(s, "{b:02x}");
            s
        })
    };
    assert!(html.contains(&sha), "the run's sha256");
    // Self-contained: no script, no stylesheet or image fetched, no link anywhere.
    for external in [
        "<script", "<link", "src=", "href=", "@import", "url(http", "https://",
    ] {
        assert!(
            !html.contains(external),
            "the page refers to something outside itself: {external}"
        );
    }
    // The only URL is the SVG namespace, which is a name and never fetched.
    assert_eq!(
        html.matches("http://").count(),
        html.matches("http://www.w3.org/2000/svg").count()
    );
    // No spec given: no verdicts.
    assert!(!html.contains("class=\"spec\"") && o.stdout.is_empty());
}

/// Headless Chromium, installed by `.ci/run`; elsewhere the test says it is skipped unless
/// `IMU_ATTEST_REQUIRE_CHROMIUM` is set (CI sets it, so a missing browser fails there).
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        });
    if found.is_none() {
        assert!(
            std::env::var_os("IMU_ATTEST_REQUIRE_CHROMIUM").is_none(),
            "IMU_ATTEST_REQUIRE_CHROMIUM is set and no chromium was found"
        );
        eprintln!("skipped: no headless chromium on this machine (.ci/run installs it)");
    }
    found
}

#[test]
fn the_certificate_renders_in_headless_chromium_without_network() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report.html");
    let run = sample("approach.csv.gz");
    let (o, _) = report(&["report", run.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let shot = dir.path().join("shot.png");
    let args = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        // Every request would go to a closed local port: a page needing the network would not
        // render what it needs.
        "--proxy-server=http://127.0.0.1:9",
        "--proxy-bypass-list=<-loopback>",
        "--window-size=1100,3000",
        "--virtual-time-budget=5000",
    ];
    let url = format!("file://{}", out.display());
    // Without a network namespace when the machine allows one (`unshare -n`, as root).
    let isolated = Command::new("unshare")
        .args(["-n", "true"])
        .status()
        .is_ok_and(|s| s.success());
    let run_browser = |extra: &str| {
        let mut c = if isolated {
            let mut c = Command::new("unshare");
            c.args(["-n", browser]);
            c
        } else {
            Command::new(browser)
        };
        c.args(args).arg(extra).arg(&url).output().unwrap()
    };
    let dom = run_browser("--dump-dom");
    assert!(dom.status.success(), "{}", String::from_utf8_lossy(&dom.stderr));
    let dom = String::from_utf8_lossy(&dom.stdout);
    for s in SECTIONS {
        assert!(dom.contains(s), "the rendered page lacks {s}");
    }
    let shot_run = run_browser(&format!("--screenshot={}", shot.display()));
    assert!(
        shot_run.status.success(),
        "{}",
        String::from_utf8_lossy(&shot_run.stderr)
    );
    let size = std::fs::metadata(&shot).unwrap().len();
    assert!(
        size > 50_000,
        "a screenshot of a rendered page, not a blank one ({size} bytes)"
    );
}

#[test]
fn one_failing_limit_fails_that_figure_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let run = sample("cruise.csv.gz");
    let model_path = dir.path().join("model.json");
    let o = imu_attest(&[
        "identify",
        run.to_str().unwrap(),
        "--out",
        model_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model: Model = serde_json::from_str(&std::fs::read_to_string(&model_path).unwrap()).unwrap();
    let gyro = &model.blocks["gyro"];
    // The delay's limit at half the measured delay (far below its band); everything else loose.
    let spec = serde_json::json!({
        "gyro": {"tau_s": gyro.tau_s / 2.0, "scale_factor_error_ppm": 1e5, "misalignment_mrad": 100.0,
                 "angle_random_walk": 1e3},
        "accel": {"tau_s": 1.0, "scale_factor_error_ppm": 1e5, "velocity_random_walk": 1e3}
    });
    let spec_path = dir.path().join("spec.json");
    std::fs::write(&spec_path, spec.to_string()).unwrap();
    let out = dir.path().join("report.html");
    let (o, html) = report(&[
        "report",
        run.to_str().unwrap(),
        "--model",
        model_path.to_str().unwrap(),
        "--spec",
        spec_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        o.status.success(),
        "a failed limit is not an error: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(summary.starts_with("1 fail"), "summary line: {summary}");
    let fails: Vec<&str> = html.split("<tr class=\"fail\">").skip(1).collect();
    assert_eq!(fails.len(), 1, "exactly one failing figure");
    assert!(
        fails[0].contains(">gyro<") && fails[0].contains(">tau_s<"),
        "{}",
        fails[0]
    );
    // Loose limits on figures with a known band all pass.
    let passes = html.matches("<tr class=\"pass\">").count();
    // Gyro scale factors and misalignments, the accelerometer's delay and scale factors.
    let loose = 3 + 6 + 1 + 3;
    assert!(passes >= loose, "{passes} passes");
    assert!(html.contains("id=\"spec-summary\""));
}

#[test]
fn two_runs_give_one_report_with_a_comparison() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("both.html");
    let (a, b) = (sample("cruise.csv.gz"), sample("approach.csv.gz"));
    let (o, html) = report(&[
        "report",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(html.contains("id=\"comparison\""));
    assert!(html.contains("<th>cruise.csv.gz</th><th>approach.csv.gz</th>"));
    assert_eq!(html.matches("id=\"block-gyro\"").count(), 2);
}

#[test]
fn bad_input_exits_with_status_2_and_a_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = sample("cruise.csv.gz");
    let out = dir.path().join("r.html");
    let bad_spec = dir.path().join("spec.json");
    std::fs::write(&bad_spec, "{\n  \"gyro\": {\"tau_s\": \"5 ms\"}\n}").unwrap();
    let unknown = dir.path().join("unknown.json");
    std::fs::write(&unknown, r#"{"gyro": {"angle_random_wlak": 0.1}}"#).unwrap();
    let other_model = dir.path().join("other.json");
    let o = imu_attest(&[
        "identify",
        sample("approach.csv.gz").to_str().unwrap(),
        "--out",
        other_model.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    for (args, needle) in [
        (
            vec![
                "report",
                run.to_str().unwrap(),
                "--spec",
                bad_spec.to_str().unwrap(),
            ],
            "spec.json",
        ),
        (
            vec![
                "report",
                run.to_str().unwrap(),
                "--spec",
                unknown.to_str().unwrap(),
            ],
            "unknown quantity 'angle_random_wlak'",
        ),
        (
            vec![
                "report",
                run.to_str().unwrap(),
                "--model",
                other_model.to_str().unwrap(),
            ],
            "identified from another file",
        ),
        (
            vec!["report", run.to_str().unwrap(), "--out", run.to_str().unwrap()],
            "refusing",
        ),
        (vec!["report"], "at least one RUN"),
    ] {
        let mut args = args;
        if !args.contains(&"--out") {
            args.extend(["--out", out.to_str().unwrap()]);
        }
        let o = imu_attest(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(!out.exists(), "nothing written");
    }
}

#[test]
fn a_model_with_accepted_effects_lists_them_in_the_certificate() {
    let dir = tempfile::tempdir().unwrap();
    let run = sample("cruise.csv.gz");
    let effects = dir.path().join("effects.json");
    std::fs::write(
        &effects,
        r#"{"effects": [{"block": "gyro", "effect": "sensor_lag"}, {"block": "accel", "effect": "platform_resonance"}]}"#,
    )
    .unwrap();
    let model_path = dir.path().join("model.json");
    let o = imu_attest(&[
        "identify",
        run.to_str().unwrap(),
        "--effects",
        effects.to_str().unwrap(),
        "--out",
        model_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("report.html");
    let (o, html) = report(&[
        "report",
        run.to_str().unwrap(),
        "--model",
        model_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        html.contains("Accepted effects (the model above is the paper"),
        "gyro's list"
    );
    assert!(html.contains("<b>gyro first-order lag</b>: first-order lag, time constant T = "));
    // The extended gyro's fit is the joint fit's, the accelerometer's as identified.
    assert_eq!(
        html.matches("(whole-record fit with the accepted effects; ")
            .count(),
        1,
        "the gyro's chi2/dof is the joint fit's"
    );
    // The accelerometer's accepted mode is not in this clean run: its fit parks at the band's
    // top, so it is not added, the model stays as identified and the certificate says why.
    assert_eq!(
        html.matches("Accepted effects: none could be added (the model above is as identified)")
            .count(),
        1,
        "the accelerometer has none added"
    );
    assert!(html.contains("not added: accelerometer mount resonance (the band the block is identified over"));
}

/// An order whose unstable best fit was set aside for its best stable one says so, in the model
/// file (the unstable fit's chi2 below the candidate's, the data's preference for it at most
/// three deviations) and in the certificate's list of orders tried; a candidate without one says
/// nothing. Our simulator's gyro behind a 100 Hz anti-alias pair at 1 kHz, seed 1: the chosen
/// order 2 is such a candidate (measured: z 0.40), and order 0 never is.
#[test]
fn an_unstable_fit_set_aside_is_said_in_the_model_and_the_certificate() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let (run, model, page) = (path("f.csv"), path("m.json"), path("r.html"));
    let sim = imu_attest(&[
        "simulate",
        "--regime",
        "cruise",
        "--duration",
        "120",
        "--rate",
        "1000",
        "--sensor-filter-hz",
        "100",
        "--seed",
        "1",
        "--out",
        &run,
    ]);
    assert!(sim.status.success(), "{}", String::from_utf8_lossy(&sim.stderr));
    let o = imu_attest(&["identify", &run, "--out", &model]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: Model = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let gyro = &m.blocks["gyro"];
    let candidates = &gyro.fit.candidates;
    assert_eq!(candidates[0].unstable_set_aside, None);
    let chosen = &candidates[gyro.order];
    let aside = chosen
        .unstable_set_aside
        .expect("the chosen order's unstable fit set aside");
    assert!(chosen.stable && aside.chi2 < chosen.chi2, "{chosen:?}");
    assert!(aside.vuong_z > 0.0 && aside.vuong_z <= 3.0, "{aside:?}");
    let (o, html) = report(&["report", &run, "--model", &model, "--out", &page]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let orders = html
        .split("id=\"block-gyro\"")
        .nth(1)
        .and_then(|s| s.split("Orders tried: ").nth(1))
        .and_then(|s| s.split("</p>").next())
        .unwrap();
    let entries: Vec<&str> = orders.split("; ").filter(|e| e.starts_with("order ")).collect();
    let said = |order: usize| {
        entries
            .iter()
            .any(|e| e.starts_with(&format!("order {order}:")) && e.contains("set aside"))
    };
    assert!(said(gyro.order), "{orders}");
    assert!(!said(0), "{orders}");
}
