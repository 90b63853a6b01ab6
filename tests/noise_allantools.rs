//! The Allan deviation, its degrees of freedom and intervals, and the chi-square quantiles
//! against values computed once with allantools and scipy (`tests/data/make_allan_refs.py`).

use imu_attest::noise::allan::{ONE_SIGMA, PowerLaw, confidence_interval, edf, overlapping_adev};
use imu_attest::noise::chi2::chi2_quantile;
use serde::Deserialize;

#[derive(Deserialize)]
struct Series {
    name: String,
    rate_hz: f64,
    y: Vec<f64>,
    m: Vec<usize>,
    adev: Vec<f64>,
}

#[derive(Deserialize)]
struct EdfRef {
    n: usize,
    m: usize,
    alpha: i32,
    edf: f64,
}

#[derive(Deserialize)]
struct Interval {
    adev: f64,
    edf: f64,
    lo: f64,
    hi: f64,
}

#[derive(Deserialize)]
struct Quantile {
    p: f64,
    dof: f64,
    x: f64,
}

#[derive(Deserialize)]
struct Refs {
    series: Vec<Series>,
    edf: Vec<EdfRef>,
    ci: Vec<Interval>,
    chi2_quantiles: Vec<Quantile>,
}

fn load() -> Refs {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/allan_refs.json");
    let text = std::fs::read_to_string(path).expect("tests/data/allan_refs.json is readable");
    serde_json::from_str(&text).expect("tests/data/allan_refs.json parses")
}

#[test]
fn overlapping_allan_deviation_matches_allantools_to_1e_9() {
    let refs = load();
    for s in &refs.series {
        let points = overlapping_adev(&s.y, s.rate_hz, &s.m, |_| PowerLaw::WhiteRate);
        assert_eq!(points.len(), s.m.len(), "{}", s.name);
        for ((p, want), m) in points.iter().zip(&s.adev).zip(&s.m) {
            assert!(
                (p.adev / want - 1.0).abs() < 1e-9,
                "{} m {m}: {} vs {want}",
                s.name,
                p.adev
            );
            assert!((p.tau_s - *m as f64 / s.rate_hz).abs() < 1e-15);
        }
    }
}

#[test]
fn degrees_of_freedom_and_intervals_match_allantools() {
    let refs = load();
    for e in &refs.edf {
        let law = match e.alpha {
            2 => PowerLaw::WhitePhase,
            0 => PowerLaw::WhiteRate,
            _ => PowerLaw::RandomWalkRate,
        };
        let got = edf(e.n, e.m, law);
        let want = e.edf.max(1.0);
        assert!(
            (got / want - 1.0).abs() < 1e-12,
            "alpha {} m {}: {got} vs {want}",
            e.alpha,
            e.m
        );
    }
    for c in &refs.ci {
        let (lo, hi) = confidence_interval(c.adev, c.edf, ONE_SIGMA);
        assert!(
            (lo / c.lo - 1.0).abs() < 1e-9,
            "edf {}: lo {lo} vs {}",
            c.edf,
            c.lo
        );
        assert!(
            (hi / c.hi - 1.0).abs() < 1e-9,
            "edf {}: hi {hi} vs {}",
            c.edf,
            c.hi
        );
    }
}

#[test]
fn chi_square_quantiles_match_scipy() {
    for q in load().chi2_quantiles {
        let got = chi2_quantile(q.p, q.dof);
        assert!(
            (got / q.x - 1.0).abs() < 1e-9,
            "p {} dof {}: {got} vs {}",
            q.p,
            q.dof,
            q.x
        );
    }
}
