use super::*;

fn empty_model() -> Model {
    Model {
        schema: MODEL_SCHEMA.to_owned(),
        source: Source {
            file: "run.csv".to_owned(),
            sha256: "0".repeat(64),
            regime: "cruise".to_owned(),
            sample_rate_hz: 500.0,
        },
        settings: Settings::default(),
        blocks: BTreeMap::new(),
        recording_faults: Vec::new(),
        refused_blocks: BTreeMap::new(),
    }
}

#[test]
fn poles_are_described_by_time_constant_or_frequency_and_damping() {
    assert_eq!(
        describe_pole([-100.0, 0.0]),
        "-100.0000 rad/s (time constant 10.000 ms)"
    );
    // -10 +- 100j: |p| = 100.499 rad/s = 15.995 Hz, damping 10 / 100.499 = 0.0995.
    assert_eq!(
        describe_pole([-10.0, -100.0]),
        "-10.0000 ± 100.0000j rad/s (15.995 Hz, damping 0.10)"
    );
}

/// A model file written before the `estimate` setting reads back as fitted to the causal
/// estimate; one that names its estimate keeps it.
#[test]
fn an_older_model_file_reads_back_as_fitted_to_the_causal_estimate() {
    let written = serde_json::to_value(empty_model()).expect("serialises");
    assert_eq!(written["settings"]["estimate"], "h1");
    let mut older = written.clone();
    older["settings"]
        .as_object_mut()
        .expect("settings object")
        .remove("estimate");
    for (value, expected) in [(older, Estimate::CausalWiener), (written.clone(), Estimate::H1)] {
        let bytes = serde_json::to_vec(&value).expect("bytes");
        let mut model: Model = serde_json::from_slice(&bytes).expect("reads");
        model.settle_estimate(&bytes);
        assert_eq!(model.settings.estimate, expected, "{}", value["settings"]);
    }
    let mut causal = written;
    causal["settings"]["estimate"] = "causal_wiener".into();
    let bytes = serde_json::to_vec(&causal).expect("bytes");
    let mut model: Model = serde_json::from_slice(&bytes).expect("reads");
    model.settle_estimate(&bytes);
    assert_eq!(model.settings.estimate, Estimate::CausalWiener);
}

#[test]
fn non_finite_numbers_never_reach_the_file() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("model.json");
    empty_model()
        .write_file(&path)
        .expect("a finite model is written");
    let written = std::fs::read(&path).expect("written");
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut model = empty_model();
        model.source.sample_rate_hz = bad;
        let err = model.write_file(&path).expect_err("refused");
        assert!(err.to_string().contains("source.sample_rate_hz"), "{err}");
        let mut model = empty_model();
        model.settings.band_hz = crate::ident::band::BandSetting::Fixed([0.1, bad]);
        let err = model.write_file(&path).expect_err("refused");
        assert!(err.to_string().contains("settings.band_hz[1]"), "{err}");
        assert_eq!(
            std::fs::read(&path).expect("kept"),
            written,
            "the old file is untouched"
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).expect("listed").count(), 1);
}
