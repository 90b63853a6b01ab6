use super::*;

fn parse(s: &str) -> Result<Settings, SettingsError> {
    Settings::from_json(s.as_bytes(), Path::new("s.json"))
}

#[test]
fn empty_file_gives_defaults_and_round_trips() {
    let s = parse("{}").unwrap();
    assert_eq!(s, Settings::default());
    let text = serde_json::to_string(&s).unwrap();
    assert!(
        text.contains("\"weight_A\"") && text.contains("\"band_hz\"") && text.contains("\"order\":\"auto\"")
    );
    assert!(text.contains("\"segment_auto\":true"), "{text}");
    assert_eq!(parse(&text).unwrap(), s);
}

/// Segments of `len` with half overlap in `n` samples, counted by hand.
fn segments_by_hand(n: usize, len: usize) -> usize {
    if n < len { 0 } else { (n - len) / (len / 2) + 1 }
}

#[test]
fn a_segment_left_to_the_program_is_halved_until_the_record_holds_twelve() {
    let auto = Settings::default().welch;
    // Real and simulated record lengths: 30 s, 60 s and 128 s at 285.7 Hz, 60 s at 500 Hz,
    // 300 s at 500 Hz, 10 s at 100 Hz, and one too short for even the shortest segment.
    for (n, expected) in [
        (8_571, 1024),
        (17_142, 2048),
        (36_600, 4096),
        (30_000, 4096),
        (150_000, 4096),
        (1_000, 256),
    ] {
        let w = welch_for_record(auto, n);
        assert_eq!(w.segment_len, expected, "{n} samples");
        // The longest power of two that leaves 12 segments (the shortest allowed otherwise).
        assert!(
            expected == 256 || segments_by_hand(n, expected) >= AUTO_MIN_SEGMENTS,
            "{n}"
        );
        assert!(
            expected == 4096 || segments_by_hand(n, 2 * expected) < AUTO_MIN_SEGMENTS,
            "{n}"
        );
        assert_eq!(w.n_segments(n), segments_by_hand(n, expected));
        assert!(w.segment_auto, "still the program's");
        // Fitting it again changes nothing.
        assert_eq!(welch_for_record(w, n), w);
    }
    // At overlap 0.75 twelve segments are 6.5 equivalent averages: the segment is halved further
    // (30 s at 285.7 Hz: 1024 gives 30 segments, 16.6 averages; 2048 gives 13, 7.0).
    let overlapping = WelchSettings {
        overlap: 0.75,
        ..auto
    };
    let w = welch_for_record(overlapping, 8_571);
    assert_eq!(w.segment_len, 1024);
    assert!(equivalent_averages_of(&w, 8_571) >= AUTO_MIN_EQUIVALENT_AVERAGES);
    let longer = WelchSettings {
        segment_len: 2048,
        ..w
    };
    assert!(longer.n_segments(8_571) >= AUTO_MIN_SEGMENTS);
    assert!(equivalent_averages_of(&longer, 8_571) < AUTO_MIN_EQUIVALENT_AVERAGES);
    // A given segment is kept, whatever the record.
    let given = WelchSettings {
        segment_len: 4096,
        segment_auto: false,
        ..auto
    };
    assert_eq!(welch_for_record(given, 8_571), given);
}

#[test]
fn too_few_segments_are_refused_with_the_numbers_and_what_to_give() {
    let given = |segment_len, overlap| Settings {
        welch: WelchSettings {
            segment_len,
            segment_auto: false,
            overlap,
            ..WelchSettings::default()
        },
        ..Settings::default()
    };
    // 30 s at 285.7 Hz: 3 segments of 4096 (the crash this refusal replaces), 7 of 2048; 8 of 1024
    // at overlap 0.9 are 2.0 equivalent averages.
    for (len, overlap, segments, advice) in [
        (4096, 0.5, 3, "segment of 1024 samples"),
        (2048, 0.5, 7, "segment of 1024 samples"),
    ] {
        let err = given(len, overlap)
            .validate(8_571, 285.714, &[Block::Gyro])
            .unwrap_err();
        let SettingsError::TooFewSegments {
            segments: got,
            averages,
            ..
        } = &err
        else {
            panic!("{err}")
        };
        assert_eq!(*got, segments);
        assert!(*averages < MIN_EQUIVALENT_AVERAGES);
        let msg = err.to_string();
        assert!(
            msg.contains("too few samples for the chosen spectral segment")
                && msg.contains(&format!("{segments} segments of {len}"))
                && msg.contains(advice),
            "{msg}"
        );
    }
    assert!(given(1024, 0.5).validate(8_571, 285.714, &[Block::Gyro]).is_ok());
    // Overlap counts: at 0.9, 8 segments of 1024 (1738 samples) are 2.0 equivalent averages.
    let err = given(1024, 0.9)
        .validate(1_738, 285.714, &[Block::Gyro])
        .unwrap_err();
    assert!(
        matches!(err, SettingsError::TooFewSegments { segments: 8, averages, .. } if averages < 2.1),
        "{err}"
    );
    // The program's segment on the same record passes; on a record too short for 8 segments of
    // 256 the refusal says what record would do (8 segments of 256: 1152 samples).
    let auto = Settings::default().for_record(8_571, &[Block::Gyro]);
    assert!(auto.validate(8_571, 285.714, &[Block::Gyro]).is_ok());
    let short = Settings::default().for_record(1_000, &[Block::Gyro]);
    let msg = short
        .validate(1_000, 100.0, &[Block::Gyro])
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("6 segments of 256") && msg.contains("at least 1152 samples"),
        "{msg}"
    );
    let msg = given(8, 0.5)
        .validate(30, 100.0, &[Block::Gyro])
        .unwrap_err()
        .to_string();
    assert!(msg.contains("too short to identify"), "{msg}");
}
#[test]
fn contract_example_parses() {
    let s = parse(r#"{"welch": {"segment_len": 4096, "overlap": 0.5, "window": "hann"}, "band_hz": [0.1, 40.0],
        "weight_A": [[1,0,0],[0,1,0],[0,0,1]], "lambda": [0, 0, 0], "order": "auto", "blocks": ["gyro", "accel"]}"#).unwrap();
    assert_eq!(s.lambda, LambdaSetting::Values([0.0; 3]));
    assert_eq!(s.order, OrderSetting::Auto.into());
    let s = parse(r#"{"lambda": "auto", "order": 2, "blocks": ["accel"]}"#).unwrap();
    assert_eq!(
        (s.lambda, s.order, s.blocks.clone()),
        (
            LambdaSetting::Auto,
            OrderSetting::Fixed(2).into(),
            vec![Block::Accel]
        )
    );
    assert!(s.validate(100_000, 500.0, &Block::BOTH).is_ok());
}

#[test]
fn parse_errors_name_line_and_column() {
    let cases = [
        ("{\n  \"order\": 7\n}", 2, "above"),
        ("{\n \"lambda\": \"manual\"}", 2, "lambda"),
        ("{\"band_hz\": [1]}", 1, "band_hz"),
        ("{\"wieght_A\": 1}", 1, "unknown field"),
        ("{\"order\": -1}", 1, "negative"),
        ("{\"order\": 1", 1, "EOF"),
        ("[1, 2]", 1, "JSON object"),
        // An empty array read as a struct gave the defaults.
        ("\n  []", 2, "JSON object"),
        ("\"auto\"", 1, "JSON object"),
    ];
    for (text, line, needle) in cases {
        let e = parse(text).unwrap_err();
        let SettingsError::Parse { line: l, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(*l, line, "{text}: {e}");
        assert!(e.to_string().starts_with("s.json:"), "{e}");
        assert!(e.to_string().contains(needle), "{text}: {e}");
    }
}

#[test]
fn validation_refuses_each_bad_setting() {
    let blocks = Block::BOTH;
    let ok = Settings::default();
    assert!(ok.validate(100_000, 500.0, &blocks).is_ok());
    for band in [[0.0, 40.0], [50.0, 40.0], [0.1, 300.0], [f64::NAN, 1.0]] {
        let s = Settings {
            band_hz: crate::ident::band::BandSetting::Fixed(band),
            ..ok.clone()
        };
        assert!(
            matches!(
                s.validate(100_000, 500.0, &blocks),
                Err(SettingsError::Band { .. })
            ),
            "{band:?}"
        );
    }
    let not_sym = Settings {
        weight_a: [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        ..ok.clone()
    };
    assert!(
        matches!(not_sym.validate(100_000, 500.0, &blocks), Err(SettingsError::WeightNotSpd { reason }) if reason.contains("symmetric"))
    );
    let indefinite = Settings {
        weight_a: [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        ..ok.clone()
    };
    assert!(
        matches!(indefinite.validate(100_000, 500.0, &blocks), Err(SettingsError::WeightNotSpd { reason }) if reason.contains("eigenvalue"))
    );
    // A = 2 I, Lambda = (2, 0, 0): I - A^-1 Lambda has a zero on the diagonal.
    let singular = Settings {
        weight_a: [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]],
        lambda: LambdaSetting::Values([2.0, 0.0, 0.0]),
        ..ok.clone()
    };
    assert!(matches!(
        singular.validate(100_000, 500.0, &blocks),
        Err(SettingsError::SingularLambda { .. })
    ));
    let short = ok.validate(1000, 500.0, &blocks);
    assert!(matches!(short, Err(SettingsError::Welch(m)) if m.contains("1000")));
    let both = Settings {
        blocks: Block::BOTH.to_vec(),
        ..ok.clone()
    };
    assert!(matches!(
        both.validate(100_000, 500.0, &[Block::Gyro]),
        Err(SettingsError::MissingBlock("accel"))
    ));
    // Empty `blocks` means every block the run has; a run with none is refused.
    assert!(matches!(
        ok.validate(100_000, 500.0, &[]),
        Err(SettingsError::NoBlocks)
    ));
    assert_eq!(ok.blocks_for(&[Block::Accel]), vec![Block::Accel]);
    let gyro_only = Settings {
        blocks: vec![Block::Gyro],
        ..ok
    };
    assert_eq!(gyro_only.blocks_for(&blocks), vec![Block::Gyro]);
}
