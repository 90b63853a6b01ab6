use super::{AxisFollows, GainPattern, UnitSlip, gain_pattern};
use crate::block::Block;
use crate::rng::Rng;

/// `scale` times the signed permutation `p` (`k[i][p[i].0] = p[i].1 scale`), with a calibrated
/// sensor's errors: each element moved by up to `err` of the scale.
fn pattern_k(scale: f64, p: [(usize, f64); 3], err: f64, rng: &mut Rng) -> [[f64; 3]; 3] {
    let mut k = [[0.0; 3]; 3];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let base = if p[i].0 == j { p[i].1 } else { 0.0 };
            *v = scale * (base + err * (2.0 * rng.uniform() - 1.0));
        }
    }
    k
}

const IDENTITY: [(usize, f64); 3] = [(0, 1.0), (1, 1.0), (2, 1.0)];

#[test]
fn a_unit_slip_is_named_by_its_factor() {
    let mut rng = Rng::new(7);
    for (block, unit) in [
        (Block::Gyro, UnitSlip::OutputsInDegPerS),
        (Block::Accel, UnitSlip::OutputsInG),
        (Block::Accel, UnitSlip::OutputsInMilliG),
    ] {
        for _ in 0..20 {
            // A sensor's own scale error of up to 1 % on top of the slip.
            let scale = unit.factor() * (1.0 + 0.01 * (2.0 * rng.uniform() - 1.0));
            let k = pattern_k(scale, IDENTITY, 0.005, &mut rng);
            let found = gain_pattern(block, &k).expect("a pattern");
            assert_eq!(found.units, Some(unit), "{k:?}");
            assert!(found.axes.is_empty(), "{found:?}");
            assert!(
                (found.scale / scale - 1.0).abs() < 0.01,
                "{} against {scale}",
                found.scale
            );
        }
    }
    // Not a slip of that block: a gyro at 1/g, an accelerometer at 180/pi.
    let k = pattern_k(UnitSlip::OutputsInG.factor(), IDENTITY, 0.0, &mut rng);
    assert_eq!(gain_pattern(Block::Gyro, &k), None);
    let k = pattern_k(UnitSlip::OutputsInDegPerS.factor(), IDENTITY, 0.0, &mut rng);
    assert_eq!(gain_pattern(Block::Accel, &k), None);
}

/// Every signed permutation at several scales, against a brute-force reading: the pattern
/// rebuilt from what is said matches `K` to the errors put on it.
#[test]
fn swapped_and_reversed_axes_are_named_and_rebuild_k() {
    let mut rng = Rng::new(11);
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    for perm in perms {
        for signs in 0..8_u32 {
            let p = [0, 1, 2].map(|i| (perm[i], if signs >> i & 1 == 1 { -1.0 } else { 1.0 }));
            for (unit, scale) in [(false, 1.0), (true, UnitSlip::OutputsInDegPerS.factor())] {
                let k = pattern_k(scale, p, 0.004, &mut rng);
                let found = gain_pattern(Block::Gyro, &k);
                let plain = perm == [0, 1, 2] && signs == 0 && !unit;
                if plain {
                    assert_eq!(found, None, "the identity is no pattern to say");
                    continue;
                }
                let found = found.expect("a pattern");
                assert_eq!(
                    found.units,
                    unit.then_some(UnitSlip::OutputsInDegPerS),
                    "{found:?}"
                );
                // Only the rows off their own axis or reversed are named.
                let moved = (0..3).filter(|&i| perm[i] != i || signs >> i & 1 == 1).count();
                assert_eq!(found.axes.len(), moved, "{perm:?} {signs}: {found:?}");
                let names = ["gx", "gy", "gz"];
                let inputs = ["wx", "wy", "wz"];
                let mut rebuilt = [[0.0; 3]; 3];
                for (i, row) in rebuilt.iter_mut().enumerate() {
                    row[i] = found.scale;
                }
                for a in &found.axes {
                    let i = names.iter().position(|n| *n == a.output).expect("output");
                    let j = inputs.iter().position(|n| *n == a.input).expect("input");
                    rebuilt[i] = [0.0; 3];
                    rebuilt[i][j] = if a.reversed { -found.scale } else { found.scale };
                }
                for i in 0..3 {
                    for j in 0..3 {
                        assert!(
                            (rebuilt[i][j] - k[i][j]).abs() <= 0.01 * scale,
                            "{perm:?} {signs} {scale}: {rebuilt:?} against {k:?}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn a_k_that_is_no_clean_pattern_says_nothing() {
    let mut rng = Rng::new(3);
    // A real misalignment of 0.2 (beyond the tolerance), a scale no unit explains, NaN.
    let mut k = pattern_k(1.0, IDENTITY, 0.0, &mut rng);
    k[0][1] = 0.2;
    assert_eq!(gain_pattern(Block::Gyro, &k), None);
    let k = pattern_k(2.0, IDENTITY, 0.002, &mut rng);
    assert_eq!(gain_pattern(Block::Gyro, &k), None);
    let mut k = pattern_k(57.3, IDENTITY, 0.0, &mut rng);
    k[2][2] = f64::NAN;
    assert_eq!(gain_pattern(Block::Gyro, &k), None);
    // One diagonal element 8 % from the others: no common size.
    let mut k = pattern_k(57.3, IDENTITY, 0.0, &mut rng);
    k[1][1] *= 1.08;
    assert_eq!(gain_pattern(Block::Gyro, &k), None);
    assert_eq!(gain_pattern(Block::Gyro, &[[0.0; 3]; 3]), None);
}

#[test]
fn the_words_say_the_unit_and_the_axes() {
    let both = GainPattern {
        scale: 57.41,
        units: Some(UnitSlip::OutputsInDegPerS),
        axes: vec![
            AxisFollows {
                output: "gx".to_owned(),
                input: "wy".to_owned(),
                reversed: false,
            },
            AxisFollows {
                output: "gy".to_owned(),
                input: "wx".to_owned(),
                reversed: true,
            },
        ],
    }
    .to_string();
    assert_eq!(
        both,
        "K reads as 57.4100 times the identity with axes swapped or reversed (its elements \
         within 5 % of that, the others below): the outputs look to be in deg/s (K near 180/pi = 57.30), where the \
         run format's unit is rad/s; gx follows wy, gy follows -wx: the outputs' axis order or \
         signs differ from the stand's axes. Convert or reorder the columns and identify again: \
         this model is of the run as recorded"
    );
    let json = serde_json::to_value(GainPattern {
        scale: 0.102,
        units: Some(UnitSlip::OutputsInG),
        axes: Vec::new(),
    })
    .expect("serialised");
    assert_eq!(json["units"], "outputs_in_g");
    assert!(json.get("axes").is_none(), "{json}");
}

/// The warning in the model file: its kind, its fields, and read back the same.
#[test]
fn the_warning_round_trips_through_the_model_file() {
    use crate::ident::warnings::IdentWarning;
    let w = IdentWarning::GainPattern(GainPattern {
        scale: 0.9986,
        units: None,
        axes: vec![AxisFollows {
            output: "gx".to_owned(),
            input: "wy".to_owned(),
            reversed: true,
        }],
    });
    let json = serde_json::to_value(&w).expect("serialised");
    assert_eq!(json["kind"], "gain_pattern");
    assert_eq!(json["axes"][0]["input"], "wy");
    assert!(json.get("units").is_none(), "{json}");
    let back: IdentWarning = serde_json::from_value(json).expect("read back");
    assert_eq!(back, w);
}
