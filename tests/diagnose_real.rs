//! Issue 15 on the three real recordings (`tests/data/real`, BROAD, CC BY 4.0; see the README
//! there), default settings: every finding the diagnosis reports closes part of its block's
//! worst-channel gap, none is a resonance at the band's edge or damped beyond a peak, the
//! paper's model the search starts from is the unit's (K within 2 % of the identity, the delay
//! 3.9-4.5 ms: the slow run's band ends where the reference's noise takes over, and the report
//! says so), and where the two runs without disturbances (fast rotation, slow translation) name
//! the same effect its sizes agree within their standard deviations (the same
//! gyro on both; before the sandwich widening of `diagnose::uncertainty` the slow run's `k2` z
//! lay 3.7 of its standard deviations from the fast run's), and no run's quadratic scale factor
//! is presented as a size to certify without a caveat (undetermined, or not reproduced by the
//! record's halves or quarters: `diagnose::halves`). The tapping run (finger taps the reference does not
//! see) is compared too, and the comparison printed, not asserted.

use std::path::Path;
use std::sync::Arc;

use imu_attest::compare::findings::compare_findings;
use imu_attest::diagnose::describe::SIZE_WITHIN_NOISE;
use imu_attest::diagnose::{DiagnoseOptions, Finding, Report, diagnose_prepared, prepare};
use imu_attest::effect::Effect;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, load};

const RUNS: [&str; 3] = [
    "broad07_fast_rotation",
    "broad11_slow_translation",
    "broad25_tapping",
];

/// A resonance within this share of a band edge is parked there by the fit (`workflow.rs`).
const EDGE: f64 = 0.03;

fn diagnosed(name: &str) -> (Report, [f64; 2]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    let run = load(&path, &LoadOptions::default()).expect("the real run loads");
    let prepared = prepare(&mut Session::new(Arc::new(run)), &Settings::default()).expect("prepared");
    let band = prepared.blocks[0].band_hz;
    (diagnose_prepared(&prepared, &DiagnoseOptions::default()), band)
}

fn resonance(f: &Finding) -> Option<(f64, f64)> {
    let p = &f.parameters;
    Some((p.get("frequency_hz")?.as_f64()?, p.get("damping")?.as_f64()?))
}

#[test]
fn findings_on_real_runs_close_the_gap_stay_inside_the_band_and_agree_between_runs() {
    let mut reports = Vec::new();
    for name in RUNS {
        let (report, band) = diagnosed(name);
        for f in &report.findings {
            eprintln!(
                "{name}: {} {} {} ± {}; gap {:.2} -> {:.2} dB",
                f.block, f.effect, f.parameters, f.parameter_std, f.gap_before_db, f.gap_after_db
            );
            assert!(
                f.gap_after_db < f.gap_before_db,
                "{name}: {} does not close the gap: {:.3} -> {:.3} dB",
                f.effect,
                f.gap_before_db,
                f.gap_after_db
            );
            // What these runs call a quadratic scale factor is a rate-shaped misfit whose size
            // differs between runs and within them (README, "The missing-effect workflow"):
            // none of them may be presented as a size to certify without a caveat.
            if f.effect == Effect::ScaleNonlinearity {
                assert!(
                    f.evidence.contains(SIZE_WITHIN_NOISE)
                        || f.evidence
                            .contains("not one fixed property of the block over this run"),
                    "{name}: a k2 presented as certifiable: {}",
                    f.evidence
                );
            }
            if f.effect == Effect::PlatformResonance {
                let (hz, zeta) = resonance(f).expect("a resonance's frequency and damping");
                assert!(
                    hz > band[0] * (1.0 + EDGE) && hz < band[1] * (1.0 - EDGE),
                    "{name}: a resonance at {hz} Hz, band {band:?}"
                );
                assert!(zeta <= 0.5, "{name}: a resonance damped {zeta}");
            }
        }
        // The paper's model the search starts from is the unit's (README there: K close to the
        // identity, the delay about 4.2 ms). Fitted over 0.1-40 Hz, where the optical
        // reference's noise takes over from about 11 Hz, the slow run's read 0.88 / 1.00 / 0.85
        // and every cell of its disagreement map was a misfit: the band now ends where its
        // inputs are not the motion, and the report says so.
        let gyro = &report.blocks["gyro"];
        let k = gyro.k_base;
        let off = (0..9)
            .map(|e| (k[e / 3][e % 3] - f64::from(u8::from(e / 3 == e % 3))).powi(2))
            .sum::<f64>()
            .sqrt()
            / 3f64.sqrt();
        eprintln!(
            "{name}: searched {:?} Hz, K_base {off:.4} off identity, tau {:.3} ms",
            gyro.band_hz,
            gyro.tau_base_s * 1e3
        );
        assert!(
            off < 0.02,
            "{name}: the diagnosis's K_base is {off:.3} off identity: {k:?}"
        );
        assert!(
            (3.9e-3..4.5e-3).contains(&gyro.tau_base_s),
            "{name}: the diagnosis's delay {} s",
            gyro.tau_base_s
        );
        // A lag the search refuses here makes the residual power grow (the optical reference's
        // band limit, issue 15): said as a note, never a warning that a finding was lost.
        if let Some((words, warning)) = report.not_named_words("gyro") {
            eprintln!("{name}: {words}");
            assert!(!warning, "{name}: a refusal said as a warning: {words}");
        }
        if let Some(limit) = &gyro.input_limit {
            assert!(limit.band_ended, "{name}: the auto band's limit not applied");
            assert!(
                report.ended_bands().starts_with("gyro only up to "),
                "{name}: the verdict's scope not said: {:?}",
                report.ended_bands()
            );
        }
        reports.push(report);
    }
    assert!(
        reports[1].blocks["gyro"].input_limit.is_some(),
        "the slow run's reference noise above its motion not said"
    );
    let findings: Vec<&[Finding]> = reports.iter().map(|r| r.findings.as_slice()).collect();
    let names: Vec<String> = RUNS.iter().map(|s| (*s).to_owned()).collect();
    for d in compare_findings(&findings, &names) {
        eprintln!("{:?} {} {}: {}", d.runs, d.block, d.effect, d.words);
        if d.runs == [0, 1] {
            assert_ne!(
                d.consistent,
                Some(false),
                "the undisturbed runs name {} with sizes that differ: {}",
                d.effect,
                d.words
            );
        }
    }
}
