//! Development sweep of the missing-effect workflow on simulated runs:
//! `cargo run --release --example diagnose_sweep -- REGIME SEED DURATION [EFFECT_SPEC...]`.
//! Prints the findings next to what the simulator hid (read here, never by the workflow).
#![expect(clippy::unwrap_used, clippy::print_stderr, reason = "development tool")]

use imu_attest::diagnose::DiagnoseOptions;
use imu_attest::diagnose::diagnose_run;
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let regime: Regime = args[0].parse().unwrap();
    let mut config = SimConfig::new(regime);
    config.seed = args[1].parse().unwrap();
    config.duration_s = args[2].parse().unwrap();
    config.effects = args[3..].iter().map(|s| s.parse().unwrap()).collect();
    let sim = simulate(&config).unwrap();
    let dir = std::env::temp_dir().join(format!("diag-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("run.csv");
    write_run(&sim, &path).unwrap();
    let run = load(&path, &LoadOptions::default()).unwrap();
    let t0 = std::time::Instant::now();
    let report = diagnose_run(&run, &Settings::default(), &DiagnoseOptions::default()).unwrap();
    eprintln!(
        "diagnosis {:.2} s, verdict {:?}",
        t0.elapsed().as_secs_f64(),
        report.verdict
    );
    for f in &report.findings {
        eprintln!("  {} {}: {} | {}", f.block, f.effect, f.parameters, f.evidence);
    }
    for (name, b) in &report.blocks {
        let c: Vec<String> = b
            .candidates
            .iter()
            .map(|c| format!("{}={:.0}", c.effect, c.criterion_gain))
            .collect();
        eprintln!(
            "  {name} bands {:?}",
            b.map[0]
                .bands_hz
                .iter()
                .map(|b| format!("{:.1}", b[0]))
                .collect::<Vec<_>>()
        );
        for (i, z) in b.map[0].ratio_db.iter().enumerate() {
            eprintln!(
                "    ch{i} ratio_db {:?}",
                z.iter().map(|v| format!("{v:.2}")).collect::<Vec<_>>()
            );
        }
        eprintln!(
            "  {name}: chi2/dof {:.3} -> {:.3}; round 1: {}",
            b.chi2_per_dof[0],
            b.chi2_per_dof[1],
            c.join(" ")
        );
    }
    for (name, t) in [
        ("gyro", &sim.sidecar.truth.gyro),
        ("accel", &sim.sidecar.truth.accel),
    ] {
        if let Some(t) = t {
            eprintln!("  truth {name}: tau {:.5} {:?}", t.tau_s, t.effects);
        }
    }
    eprintln!(
        "  truth accel lever arm {:?}",
        sim.sidecar.truth.accel_lever_arm_true_m
    );
    std::fs::remove_dir_all(&dir).ok();
}
