use super::*;

/// The effects' JSON with `lag` spliced in among their fields.
fn effects_json(lag: &str) -> String {
    format!(
        r#"{{"accepted": [], {lag} "identified": {{"K": [[1,0,0],[0,1,0],[0,0,1]], "tau_s": 0.004,
        "order": 0}}, "band_hz": [0.5, 40], "chi2_per_dof": [1, 1], "gap_db": [[0,0,0],[0,0,0]]}}"#
    )
}

#[test]
fn sizes_that_are_no_filter_are_refused_when_read() {
    let good = r#""lag_s": 0.002, "lag_damping": 0.7, "channel_skew_s": [0, 1e-4, -1e-4],
        "resonances": [{"axis": 2, "frequency_hz": 30, "damping": 0.05}],"#;
    let e: ModelEffects = serde_json::from_str(&effects_json(good)).expect("read");
    assert_eq!((e.lag_s, e.lag_damping), (Some(0.002), Some(0.7)));
    assert_eq!(e.resonances[0].axis, 2);
    // Absent fields stay absent.
    let e: ModelEffects = serde_json::from_str(&effects_json("")).expect("read");
    assert_eq!((e.lag_s, e.lag_damping, e.channel_skew_s), (None, None, None));
    for (bad, said) in [
        (r#""lag_s": -0.002,"#, "lag_s"),
        (r#""lag_s": 0.002, "lag_damping": 0,"#, "lag_damping"),
        (r#""lag_s": 0.002, "lag_damping": -0.5,"#, "lag_damping"),
        (
            r#""resonances": [{"axis": 3, "frequency_hz": 30, "damping": 0.05}],"#,
            "axis",
        ),
        (
            r#""resonances": [{"axis": 0, "frequency_hz": 0, "damping": 0.05}],"#,
            "frequency_hz",
        ),
        (
            r#""resonances": [{"axis": 0, "frequency_hz": 30, "damping": -0.05}],"#,
            "damping",
        ),
    ] {
        let error = serde_json::from_str::<ModelEffects>(&effects_json(bad))
            .expect_err(bad)
            .to_string();
        assert!(error.contains(said), "{bad}: {error}");
    }
}

#[test]
fn a_damping_without_its_lag_is_refused_by_the_check() {
    let e: ModelEffects = serde_json::from_str(&effects_json(r#""lag_damping": 0.7,"#)).expect("read");
    assert!(e.check().expect_err("no lag").contains("lag_damping"));
    let e: ModelEffects =
        serde_json::from_str(&effects_json(r#""lag_s": 0.002, "lag_damping": 0.7,"#)).expect("read");
    assert_eq!(e.check(), Ok(()));
    let e: ModelEffects = serde_json::from_str(&effects_json(r#""lag_s": 0.002,"#)).expect("read");
    assert_eq!(e.check(), Ok(()));
}
