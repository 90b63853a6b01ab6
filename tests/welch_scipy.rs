//! `welch_matrix` against `scipy.signal.csd`, from values stored once by
//! `tests/data/make_welch_refs.py` in `tests/data/welch_scipy_refs.json`.

use imu_attest::spectral::{WelchPlanner, WelchSettings};
use serde::Deserialize;

/// Required agreement, relative to the largest |S| of the matrix at that frequency.
const REL_TOL: f64 = 1e-9;
/// That scale is floored at this fraction of the case's largest |S|: bins that are pure rounding
/// noise in both (DC after mean removal with a rectangular window is ~1e-31) are compared absolutely.
const FLOOR: f64 = 1e-12;

#[derive(Deserialize)]
struct Refs {
    sample_rate_hz: f64,
    signals: Vec<Vec<f64>>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    settings: WelchSettings,
    noverlap: usize,
    n_segments: usize,
    frequency_hz: Vec<f64>,
    /// `pxy[f][a][b] = scipy.signal.csd(x_a, x_b)[f]`.
    pxy_re: Vec<Vec<Vec<f64>>>,
    pxy_im: Vec<Vec<Vec<f64>>>,
}

fn load() -> Refs {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/welch_scipy_refs.json");
    let text = std::fs::read_to_string(path).expect("tests/data/welch_scipy_refs.json is readable");
    serde_json::from_str(&text).expect("tests/data/welch_scipy_refs.json parses")
}

#[test]
fn matches_scipy_csd_for_every_stored_case() {
    let refs = load();
    assert!(refs.cases.len() >= 10, "the reference file lost cases");
    let channels: Vec<&[f64]> = refs.signals.iter().map(Vec::as_slice).collect();
    let n = channels.len();
    let mut planner = WelchPlanner::new();
    for (c, case) in refs.cases.iter().enumerate() {
        let s = &case.settings;
        let label = format!("case {c}: {s:?}");
        assert_eq!(s.noverlap(), case.noverlap, "{label}");
        let got = planner.welch_matrix(&channels, refs.sample_rate_hz, s).unwrap();
        assert_eq!(got.n_averages, case.n_segments, "{label}");
        assert_eq!(got.n_bins(), case.frequency_hz.len(), "{label}");
        let bin_max = |f: usize| {
            (0..n * n)
                .map(|k| f64::hypot(case.pxy_re[f][k / n][k % n], case.pxy_im[f][k / n][k % n]))
                .fold(0.0, f64::max)
        };
        let case_max = (0..case.frequency_hz.len()).map(bin_max).fold(0.0, f64::max);
        assert!(case_max > 0.0, "{label}: reference is all zero");
        for (f, &hz) in case.frequency_hz.iter().enumerate() {
            assert!(
                (got.frequency_hz[f] - hz).abs() <= 1e-12 * refs.sample_rate_hz,
                "{label} f{f}"
            );
            let scale = bin_max(f).max(FLOOR * case_max);
            for i in 0..n {
                for j in 0..n {
                    // Ours is E[X_i conj(X_j)]; scipy's csd(a, b) is conj(A) B: transpose.
                    let (re, im) = (case.pxy_re[f][j][i], case.pxy_im[f][j][i]);
                    let v = got.get(f, i, j).unwrap();
                    let err = f64::hypot(v.re - re, v.im - im) / scale;
                    assert!(
                        err <= REL_TOL,
                        "{label} bin {f} S[{i}][{j}] = {v} vs scipy {re}{im:+}i: {err:e}"
                    );
                }
            }
        }
    }
}

#[test]
fn convention_is_the_transpose_of_scipy_csd() {
    // Guards the orientation: the stored cross terms are not real, so S[i][j] != pxy[i][j].
    let refs = load();
    let channels: Vec<&[f64]> = refs.signals.iter().map(Vec::as_slice).collect();
    let case = &refs.cases[2];
    let got = WelchPlanner::new()
        .welch_matrix(&channels, refs.sample_rate_hz, &case.settings)
        .unwrap();
    let mut worst_untransposed: f64 = 0.0;
    for f in 1..case.frequency_hz.len() - 1 {
        let v = got.get(f, 0, 1).unwrap();
        let (re, im) = (case.pxy_re[f][0][1], case.pxy_im[f][0][1]);
        assert!(
            im.abs() > 1e-9 * re.abs(),
            "bin {f}: the reference cross term is real"
        );
        worst_untransposed = worst_untransposed.max(f64::hypot(v.re - re, v.im - im) / f64::hypot(re, im));
        // scipy's csd(x0, x1) = conj(X0) X1 = conj(S01).
        let conj_err = f64::hypot(v.re - re, v.im + im) / f64::hypot(re, im);
        assert!(
            conj_err < 1e-9,
            "bin {f}: S01 should be conj(csd(x0, x1)): {conj_err:e}"
        );
    }
    assert!(worst_untransposed > 1e-3, "S01 and csd(x0, x1) should differ");
}
