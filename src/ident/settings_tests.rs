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
    assert_eq!(parse(&text).unwrap(), s);
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
        ("[1, 2]", 1, "invalid type"),
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
