use serde_json::{Value, json};

use super::*;

fn finding(effect: Effect, parameters: Value, std: Value) -> Finding {
    Finding {
        block: Block::Gyro,
        effect,
        name: effect.name_on(Block::Gyro),
        parameters,
        parameter_std: std,
        gap_before_db: -20.0,
        gap_after_db: -21.0,
        evidence: String::new(),
        delta_chi2: 100.0,
        added_parameters: 3,
        criterion_gain: 60.0,
        halves: None,
        search_band: None,
    }
}

fn k2(v: [f64; 3], sd: [f64; 3]) -> Finding {
    finding(Effect::ScaleNonlinearity, json!({ "k2": v }), json!({ "k2": sd }))
}

fn names() -> Vec<String> {
    ["fast.csv", "slow.csv", "tapping.csv"]
        .map(str::to_owned)
        .to_vec()
}

#[test]
fn sizes_within_their_deviations_agree_and_beyond_them_differ() {
    // The real runs' k2 (1e-3 s/rad): broad07 against broad11 agree (x 1.7, z 1.0 sd apart),
    // broad07 against broad25 do not (z 5.4 sd apart).
    let fast = [k2([-0.78e-3, -0.95e-3, -0.59e-3], [0.19e-3, 0.13e-3, 0.14e-3])];
    let slow = [k2([14.3e-3, -0.93e-3, 45.3e-3], [8.8e-3, 3.8e-3, 45.0e-3])];
    let tapping = [k2([10.9e-3, -0.55e-3, 6.8e-3], [2.8e-3, 0.81e-3, 1.35e-3])];
    let out = compare_findings(&[&fast, &slow, &tapping], &names());
    assert_eq!(out.len(), 3, "{out:?}");
    let pair = |a: usize, b: usize| out.iter().find(|d| d.runs == [a, b]).expect("pair");
    let agree = pair(0, 1);
    assert_eq!(agree.presence, Presence::Both);
    assert_eq!(agree.consistent, Some(true), "{}", agree.words);
    assert_eq!(agree.sizes.len(), 3);
    assert_eq!(agree.sizes[2].name, "k2[2]");
    assert!((agree.sizes[2].delta.diff - (45.3e-3 + 0.59e-3)).abs() < 1e-12);
    assert!(agree.words.contains("agree"), "{}", agree.words);
    let differ = pair(0, 2);
    assert_eq!(differ.consistent, Some(false));
    assert!(
        differ.words.contains("k2[2]") && differ.words.contains("5.4 standard deviations"),
        "{}",
        differ.words
    );
}

#[test]
fn an_effect_on_one_run_only_is_listed_not_judged() {
    let lag = finding(Effect::SensorLag, json!({"T_s": 0.004}), json!({"T_s": 0.0001}));
    let a = [lag];
    let b: [Finding; 0] = [];
    let out = compare_findings(&[&a, &b], &names());
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].presence, Presence::OnlyA);
    assert_eq!(out[0].consistent, None);
    assert!(out[0].sizes.is_empty());
    assert!(
        out[0].words.starts_with("named on fast.csv only"),
        "{}",
        out[0].words
    );
    let reversed = compare_findings(&[&b, &a], &names());
    assert_eq!(reversed[0].presence, Presence::OnlyB);
    assert!(
        reversed[0].words.starts_with("named on slow.csv only"),
        "{}",
        reversed[0].words
    );
}

#[test]
fn unknown_deviations_and_nested_sizes() {
    // G is 3x3: every element compared under its two indices; a null sd is not judged.
    let g = |v: f64, sd: Value| {
        finding(
            Effect::GSensitivity,
            json!({"G": [[v, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]}),
            json!({ "G": [[sd, null, null], [null, null, null], [null, null, null]] }),
        )
    };
    let a = [g(1e-4, json!(1e-5))];
    let b = [g(2e-4, Value::Null)];
    let out = compare_findings(&[&a, &b], &names());
    assert_eq!(out[0].sizes.len(), 9);
    assert_eq!(out[0].sizes[0].name, "G[0][0]");
    assert_eq!(out[0].sizes[0].delta.significant, None);
    assert_eq!(out[0].consistent, None);
    assert!(out[0].words.contains("not judged"), "{}", out[0].words);
    let c = [g(1.2e-4, json!(1e-5))];
    let out = compare_findings(&[&a, &c], &names());
    assert_eq!(out[0].consistent, Some(true));
    let d = [g(2e-4, json!(1e-5))];
    assert_eq!(compare_findings(&[&a, &d], &names())[0].consistent, Some(false));
}

#[test]
fn a_run_sized_over_its_usable_band_is_compared_over_the_band_searched_with_one_that_is_not() {
    // Run A's size over its usable band differs from run B's (band searched), its band searched's
    // agrees: compared like for like, they agree; two runs both sized over their usable bands
    // compare those sizes.
    let mut usable = k2([5.0e-3, 0.0, 0.0], [0.2e-3, 0.2e-3, 0.2e-3]);
    usable.search_band = Some(json!({
        "band_hz": [0.1, 40.0],
        "parameters": {"k2": [1.0e-3, 0.0, 0.0]},
        "parameter_std": {"k2": [0.2e-3, 0.2e-3, 0.2e-3]},
    }));
    let searched = [k2([1.1e-3, 0.0, 0.0], [0.2e-3, 0.2e-3, 0.2e-3])];
    let a = [usable.clone()];
    let out = compare_findings(&[&a, &searched], &names());
    assert_eq!(out[0].consistent, Some(true), "{}", out[0].words);
    assert!((out[0].sizes[0].a - 1.0e-3).abs() < 1e-15);
    let out = compare_findings(&[&searched, &a], &names());
    assert_eq!(out[0].consistent, Some(true), "{}", out[0].words);
    let both = [usable.clone()];
    let out = compare_findings(&[&a, &both], &names());
    assert!((out[0].sizes[0].a - 5.0e-3).abs() < 1e-15, "{:?}", out[0].sizes);
    // Against the usable band's size, as before the change, they would differ.
    let mut plain = usable;
    plain.search_band = None;
    let out = compare_findings(&[&[plain], &searched], &names());
    assert_eq!(out[0].consistent, Some(false), "{}", out[0].words);
}

#[test]
fn band_limits_of_other_shapes_are_not_compared_by_their_time_constants() {
    let band_limit = |shape: Value, t: f64| {
        let mut p = json!({ "T_s": t, "causal": false });
        for (k, v) in shape.as_object().expect("shape") {
            p[k] = v.clone();
        }
        finding(Effect::ReferenceBandLimit, p, json!({ "T_s": 1e-5 }))
    };
    // A 120 Hz reference read once as interpolated (T = 1 / 120 s), once as order 1 (T about
    // sqrt 6 times shorter): 400 deviations apart as figures, one stand.
    let interpolated = [band_limit(json!({ "shape": "interpolated" }), 1.0 / 120.0)];
    let order_one = [band_limit(
        json!({ "shape": "zero_phase", "order": 1 }),
        1.0 / (6f64.sqrt() * 120.0),
    )];
    let out = compare_findings(&[&interpolated, &order_one], &names());
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].presence, Presence::Both);
    assert!(
        out[0].sizes.is_empty() && out[0].consistent.is_none(),
        "{:?}",
        out[0]
    );
    assert!(
        out[0].words.contains("interpolated against zero_phase order 1"),
        "{}",
        out[0].words
    );
    // A report written before findings named their shape: order 1, zero phase, compared.
    let unnamed = [band_limit(json!({ "order": 1 }), 1.0 / (6f64.sqrt() * 120.0))];
    let out = compare_findings(&[&order_one, &unnamed], &names());
    assert_eq!(out[0].sizes.len(), 1, "{}", out[0].words);
    // The same shape: compared as before.
    let again = [band_limit(json!({ "shape": "interpolated" }), 1.0 / 120.0 + 2e-5)];
    let out = compare_findings(&[&interpolated, &again], &names());
    assert_eq!(out[0].sizes.len(), 1);
    assert_eq!(out[0].consistent, Some(true), "{}", out[0].words);
}

#[test]
fn lags_of_other_shapes_are_not_compared_and_second_orders_by_their_damping_too() {
    let first = |t: f64| finding(Effect::SensorLag, json!({ "T_s": t }), json!({ "T_s": 2e-5 }));
    let second = |t: f64, zeta: f64| {
        finding(
            Effect::SensorLag,
            json!({ "T_s": t, "damping": zeta, "shape": "second_order", "corner_hz": 20.0 }),
            json!({ "T_s": 2e-5, "damping": 0.01, "corner_hz": 0.02 }),
        )
    };
    // A 20 Hz section read on one run as a second order (T = 1 / w_n) and on another as a
    // first-order lag: T is another figure in each shape, so not compared.
    let a = [second(7.96e-3, 0.71)];
    let b = [first(7.96e-3)];
    let out = compare_findings(&[&a, &b], &names());
    assert_eq!(out.len(), 1);
    assert!(
        out[0].sizes.is_empty() && out[0].consistent.is_none(),
        "{:?}",
        out[0]
    );
    assert!(
        out[0]
            .words
            .contains("second-order low-pass against first-order lag"),
        "{}",
        out[0].words
    );
    // Two second orders of the same T: the damping tells a Butterworth (0.71) from a Bessel
    // (0.87) section, 11 combined deviations apart.
    let bessel = [second(7.96e-3, 0.87)];
    let out = compare_findings(&[&a, &bessel], &names());
    let names_compared: Vec<&str> = out[0].sizes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names_compared, ["T_s", "damping"]);
    assert_eq!(out[0].consistent, Some(false), "{}", out[0].words);
    assert!(
        out[0].words.contains("its shape differs (damping"),
        "{}",
        out[0].words
    );
    // Within their deviations: consistent.
    let again = [second(7.97e-3, 0.72)];
    let out = compare_findings(&[&a, &again], &names());
    assert_eq!(out[0].consistent, Some(true), "{}", out[0].words);
    // First-order lags are compared by T alone, as before.
    let out = compare_findings(&[&b, &[first(8.5e-3)]], &names());
    let names_compared: Vec<&str> = out[0].sizes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names_compared, ["T_s"]);
    assert_eq!(out[0].consistent, Some(false), "{}", out[0].words);
    // A second order's damping is not a size: its T near zero is within noise whatever the
    // damping (the diagnosis's `size_within_noise` reads sizes only).
    assert!(crate::diagnose::describe::size_within_noise(&second(1e-5, 0.7)));
}
