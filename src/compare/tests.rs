//! Comparison arithmetic against hand-computed differences.

use std::collections::BTreeMap;

use super::{COMPARISON_SCHEMA, CompareError, Comparison, Delta, compare};
use crate::ident::settings::Settings;
use crate::model::{BlockModel, ComplexArray, Fit, MODEL_SCHEMA, Model, Source};

fn block(k00: f64, k_std: Option<f64>, tau_s: f64, tau_std_s: Option<f64>) -> BlockModel {
    let mut k = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    k[0][0] = k00;
    let empty = ComplexArray {
        re: Vec::new(),
        im: Vec::new(),
    };
    BlockModel {
        inputs: ["wx", "wy", "wz"].map(str::to_owned),
        outputs: ["gx", "gy", "gz"].map(str::to_owned),
        k,
        tau_s,
        order: 0,
        denominator: Vec::new(),
        numerator: vec![k],
        poles: Vec::new(),
        frequency_hz: Vec::new(),
        w_u: empty.clone(),
        w_u_std: Vec::new(),
        noise_psd: empty.clone(),
        shaping_filter: empty,
        coherence: Vec::new(),
        band_hz: [0.1, 40.0],
        stationarity: None,
        noise: None,
        effects: None,
        even_gain: None,
        fit: Fit {
            k_std: [[k_std; 3]; 3],
            tau_std_s,
            scale_factor_error_ppm: [0.0; 3],
            scale_factor_error_std_ppm: [None; 3],
            misalignment_mrad: [[0.0; 3]; 3],
            misalignment_std_mrad: [[None; 3]; 3],
            chi2: 0.0,
            dof: 1,
            stable: true,
            chi2_per_dof: 0.0,
            bin_correlation: 1.0,
            candidates: Vec::new(),
            lambda: [0.0; 3],
            lambda_auto: false,
            constraint_residual: 0.0,
            equivalent_averages: 10.0,
            noise_factor_error: Some(0.0),
            input_factor_error: Some(0.0),
            causal_grid_refinement: Some(1),
            k_shift_left_out_angle_noise: None,
            warnings: Vec::new(),
        },
    }
}

fn model(regime: &str, blocks: Vec<(&str, BlockModel)>) -> Model {
    Model {
        schema: MODEL_SCHEMA.to_owned(),
        source: Source {
            file: format!("{regime}.csv"),
            sha256: String::new(),
            regime: regime.to_owned(),
            sample_rate_hz: 500.0,
        },
        settings: Settings::default(),
        blocks: blocks
            .into_iter()
            .map(|(n, b)| (n.to_owned(), b))
            .collect::<BTreeMap<_, _>>(),
        recording_faults: Vec::new(),
        refused_blocks: std::collections::BTreeMap::new(),
    }
}

#[test]
fn differences_and_significance_follow_the_combined_std() {
    // K00 differs by 0.004 with stds 0.001 and 0.001: combined 0.001414, 2.83 sigma: not significant.
    // tau differs by 1 ms with stds 0.1 ms each: 7.07 sigma: significant.
    let a = model(
        "cruise",
        vec![("gyro", block(1.0, Some(0.001), 0.004, Some(1e-4)))],
    );
    let b = model(
        "approach",
        vec![
            ("gyro", block(1.004, Some(0.001), 0.005, Some(1e-4))),
            ("accel", block(1.0, Some(0.001), 0.0, Some(1e-4))),
        ],
    );
    let c = compare(&[a, b]).expect("two runs");
    assert_eq!(c.schema, COMPARISON_SCHEMA);
    assert_eq!(c.runs.len(), 2);
    assert_eq!(c.differences.len(), 1, "accel only in one run: not compared");
    let d = &c.differences[0];
    assert_eq!(d.regimes, ["cruise".to_owned(), "approach".to_owned()]);
    assert!((d.k[0][0].diff - 0.004).abs() < 1e-12);
    let combined = d.k[0][0].std.expect("both known");
    assert!((combined - 0.001 * 2f64.sqrt()).abs() < 1e-15);
    assert_eq!(d.k[0][0].significant, Some(false));
    assert!((d.tau_s.diff - 0.001).abs() < 1e-15);
    assert_eq!(d.tau_s.significant, Some(true));
    assert!(d.significant);
    assert!(!c.orders_differ("gyro"), "both order 0");
    let mut richer = block(1.0, Some(0.001), 0.004, Some(1e-4));
    richer.order = 1;
    let e = model("approach", vec![("gyro", richer)]);
    let c = compare(&[
        model(
            "cruise",
            vec![("gyro", block(1.0, Some(0.001), 0.004, Some(1e-4)))],
        ),
        e,
    ])
    .expect("two runs");
    assert!(c.orders_differ("gyro"));
    assert!(!c.orders_differ("accel"), "no such block: nothing differs");
    assert!(!c.gains_differ_in_kind("gyro"), "neither carries an even gain");
    // One run's K at low frequency (an even gain in its model), the other's a band's mean.
    let mut low = block(1.0, Some(0.001), 0.004, Some(1e-4));
    low.even_gain = Some(even_gain());
    let c = compare(&[
        model(
            "cruise",
            vec![("gyro", block(1.0, Some(0.001), 0.004, Some(1e-4)))],
        ),
        model("approach", vec![("gyro", low.clone())]),
    ])
    .expect("two runs");
    assert!(c.gains_differ_in_kind("gyro"));
    assert!(c.runs[1].blocks["gyro"].k_at_low_frequency && !c.runs[0].blocks["gyro"].k_at_low_frequency);
    let c = compare(&[
        model("cruise", vec![("gyro", low.clone())]),
        model("approach", vec![("gyro", low)]),
    ])
    .expect("two runs");
    assert!(!c.gains_differ_in_kind("gyro"), "both at low frequency");
}

fn even_gain() -> crate::ident::gain_curvature::EvenGain {
    crate::ident::gain_curvature::EvenGain {
        coefficients: [1e-5, 0.0],
        coefficients_std: [1e-6, 1e-11],
        k_change: [[0.004, 0.0, 0.0], [0.0, 0.004, 0.0], [0.0, 0.0, 0.004]],
        k_change_std: [[1e-4; 3]; 3],
        band_top_hz: 15.0,
    }
}

/// The comparison echoes the first run's settings; a run whose settings as used differ (the
/// program fitted a shorter segment to a shorter record) carries its own, and only such a run.
#[test]
fn a_run_whose_settings_as_used_differ_carries_its_own() {
    let gyro = || vec![("gyro", block(1.0, Some(0.001), 0.004, Some(1e-4)))];
    let mut short = model("short", gyro());
    short.settings.welch.segment_len = 1024;
    let c = compare(&[model("cruise", gyro()), short, model("approach", gyro())]).expect("three runs");
    assert_eq!(c.settings.welch.segment_len, 4096);
    let own: Vec<Option<usize>> = c
        .runs
        .iter()
        .map(|r| r.settings.as_ref().map(|s| s.welch.segment_len))
        .collect();
    assert_eq!(own, [None, Some(1024), None]);
    let json = serde_json::to_value(&c).expect("serialises");
    assert!(
        json["runs"][0].get("settings").is_none(),
        "written only where it differs"
    );
    assert_eq!(json["runs"][1]["settings"]["welch"]["segment_len"], 1024);
    let back: Comparison = serde_json::from_value(json).expect("reads back");
    assert_eq!(back, c);
}

#[test]
fn an_unknown_std_is_not_judged_and_too_few_runs_are_refused() {
    let d = Delta::new(1.0, None, 2.0, Some(0.1));
    assert_eq!((d.diff, d.std, d.significant), (1.0, None, None));
    let d = Delta::new(1.0, Some(f64::NAN), 2.0, Some(0.1));
    assert_eq!(d.significant, None);
    let d = Delta::new(1.0, Some(0.1), f64::INFINITY, Some(0.1));
    assert_eq!(d.significant, None, "a non-finite figure is never flagged");
    let one = model("cruise", vec![("gyro", block(1.0, None, 0.0, None))]);
    assert_eq!(compare(&[one]), Err(CompareError::TooFewRuns(1)));
    // Three runs: three pairs, in order.
    let runs: Vec<Model> = ["a", "b", "c"]
        .iter()
        .map(|r| model(r, vec![("gyro", block(1.0, None, 0.0, None))]))
        .collect();
    let pairs: Vec<[usize; 2]> = compare(&runs)
        .expect("three")
        .differences
        .iter()
        .map(|d| d.runs)
        .collect();
    assert_eq!(pairs, vec![[0, 1], [0, 2], [1, 2]]);
}
