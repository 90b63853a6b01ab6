//! Noise terms on simulated runs whose sensor noise has a closed form: white rate noise of known
//! density (`simulate --sensor-noise white`) gives the angle random walk `N = asd / sqrt(2)`,
//! and a rate random walk (`--random-walk K`) gives `K`, each within its stated interval, over
//! several seeds and regimes. The truth is read from the simulator's sidecar by the test only.

use std::sync::Arc;

use imu_attest::diagnose::identified::identified_model;
use imu_attest::ident::session::Session;
use imu_attest::ident::settings::Settings;
use imu_attest::model::Model;
use imu_attest::noise::TermEstimate;
use imu_attest::noise::terms::NoiseTerm;
use imu_attest::run::{LoadOptions, load};
use imu_attest::sim::regime::Regime;
use imu_attest::sim::write::write_run;
use imu_attest::sim::{SimConfig, simulate};

/// Normalised error of `value` with one-sigma interval `[lo, hi]`: the half-width on the
/// truth's side.
fn z(value: f64, interval: [f64; 2], truth: f64) -> f64 {
    if truth >= value {
        (truth - value) / (interval[1] - value)
    } else {
        (value - truth) / (value - interval[0])
    }
}

/// Identifies a simulated run and returns its model (noise attached) with the sidecar's truth.
fn identified(regime: Regime, seed: u64, random_walk: f64) -> (Model, serde_json::Value) {
    let mut config = SimConfig::new(regime);
    config.seed = seed;
    config.duration_s = 300.0;
    config.sensor_noise.white_only = true;
    config.sensor_noise.random_walk = random_walk;
    let sim = simulate(&config).expect("simulated");
    let truth = serde_json::to_value(&sim.sidecar.truth).expect("truth serialises");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("run.csv");
    write_run(&sim, &path).expect("written");
    (model_of(&path), truth)
}

/// The run at `path` identified with the default settings, noise attached (as `identify`).
fn model_of(path: &std::path::Path) -> Model {
    let run = Arc::new(load(path, &LoadOptions::default()).expect("loads"));
    let settings = Settings {
        blocks: Settings::default().blocks_for(&run.blocks()),
        ..Settings::default()
    };
    identified_model(&mut Session::new(run), &settings, &mut |_| {}).expect("identified")
}

/// The normalised error of `term` against the truth `truth_si` (SI units).
fn z_of(term: &TermEstimate, truth_si: f64) -> f64 {
    z(term.value, term.interval, truth_si * term.value / term.value_si)
}

fn rms(zs: &[f64]) -> f64 {
    (zs.iter().map(|v| v * v).sum::<f64>() / zs.len() as f64).sqrt()
}

fn truth_of(truth: &serde_json::Value, block: &str, field: &str, channel: usize) -> f64 {
    truth[block]["noise"][field][channel].as_f64().expect("a number")
}

#[test]
fn white_gyro_noise_gives_its_angle_random_walk_within_the_stated_interval() {
    let mut zs = Vec::new();
    for (regime, seed) in [
        (Regime::Cruise, 1),
        (Regime::Approach, 2),
        (Regime::TurbulentCruise, 3),
        (Regime::Cruise, 4),
    ] {
        let (model, truth) = identified(regime, seed, 0.0);
        let noise = model.blocks["gyro"].noise.as_ref().expect("noise figures");
        for (i, ch) in noise.channels.iter().enumerate() {
            let arw = ch.term(NoiseTerm::RandomWalk).expect("white noise is seen");
            let n = truth_of(&truth, "gyro", "white_asd", i) / 2.0_f64.sqrt();
            let e = z_of(arw, n);
            assert!(
                e.abs() < 3.0,
                "{regime:?} seed {seed} {}: N {} vs {n} (z {e})",
                ch.channel,
                arw.value_si
            );
            zs.push(e);
        }
    }
    let rms = rms(&zs);
    eprintln!("ARW normalised errors over {} channels: rms {rms:.2}", zs.len());
    assert!(
        (0.2..1.4).contains(&rms),
        "ARW normalised errors rms {rms}: {zs:?}"
    );
}

/// On runs whose model explains the data (the terms of a misfitting model are upper bounds, tested
/// below). The approach regime's gyro does not yet (chi2/dof 3-4 on clean runs, worst at the Dutch
/// roll; README, issue 13): its residual's low-frequency part is the model's misfit, which the
/// term fit may take as a Markov process instead of the walk (approach seed 12, channel gx, since
/// the coloured angle-noise model moved that misfit).
#[test]
fn a_rate_random_walk_is_found_with_its_strength() {
    let k = 2e-5;
    let mut zs = Vec::new();
    for (regime, seed) in [(Regime::Cruise, 11), (Regime::TurbulentCruise, 12)] {
        let (model, _) = identified(regime, seed, k);
        let chi2 = model.blocks["gyro"].fit.chi2_per_dof;
        assert!(
            chi2 < 1.5,
            "{regime:?} seed {seed}: the model explains the data (chi2/dof {chi2})"
        );
        let noise = model.blocks["gyro"].noise.as_ref().expect("noise figures");
        for ch in &noise.channels {
            let rrw = ch.term(NoiseTerm::RateRandomWalk).expect("the walk is seen");
            let e = z_of(rrw, k);
            assert!(
                e.abs() < 3.0,
                "{regime:?} seed {seed} {}: K {} vs {k} (z {e})",
                ch.channel,
                rrw.value_si
            );
            zs.push(e);
        }
    }
    let rms = rms(&zs);
    eprintln!("RRW normalised errors over {} channels: rms {rms:.2}", zs.len());
    assert!(rms < 1.5, "RRW normalised errors rms {rms}: {zs:?}");
}

/// A model that does not explain the data (a real run over the former default band, 0.1-40 Hz,
/// where its reference is noise above about 15 Hz: chi2/dof about 4.5) marks its noise terms as
/// upper bounds; a clean simulated run does not.
#[test]
fn noise_terms_of_a_misfitting_model_are_marked_as_upper_bounds() {
    use imu_attest::ident::band::BandSetting;
    use imu_attest::ident::warnings::IdentWarning;
    use imu_attest::noise::NoiseWarning;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/broad07_fast_rotation.csv.gz");
    let run = Arc::new(load(&path, &LoadOptions::default()).expect("loads"));
    let settings = Settings {
        blocks: Settings::default().blocks_for(&run.blocks()),
        band_hz: BandSetting::Fixed([0.1, 40.0]),
        ..Settings::default()
    };
    let model = identified_model(&mut Session::new(run), &settings, &mut |_| {}).expect("identified");
    let gyro = &model.blocks["gyro"];
    assert!(
        gyro.fit
            .warnings
            .iter()
            .any(|w| matches!(w, IdentWarning::PoorFit { .. }))
    );
    let noise = gyro.noise.as_ref().expect("noise figures");
    assert!(
        matches!(noise.warnings.first(), Some(NoiseWarning::ModelMisfit { chi2_per_dof }) if *chi2_per_dof > 1.5),
        "{:?}",
        noise.warnings
    );
    let (clean, _) = identified(Regime::Cruise, 21, 0.0);
    for b in clean.blocks.values() {
        let n = b.noise.as_ref().expect("noise figures");
        assert!(
            !n.warnings
                .iter()
                .any(|w| matches!(w, NoiseWarning::ModelMisfit { .. })),
            "{:?}",
            n.warnings
        );
    }
}
