//! An implausible `K` that reads as a lab's bookkeeping says which (`gain_pattern`,
//! `imu_attest::ident::gain_pattern`): a real recording's gyro written in deg/s, the same with two
//! axes swapped and one reversed, a simulated accelerometer written in g. The unchanged recording
//! says neither. The identifier sees only the loaded run.

use crate::common::real::{gyro, real};
use crate::common::sim::simulated_run_of;

use imu_attest::block::Block;
use imu_attest::ident::gain_pattern::{AxisFollows, GainPattern, UnitSlip};
use imu_attest::ident::identify::{BlockIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::sim::regime::Regime;

fn pattern(b: &BlockIdentification) -> Option<&GainPattern> {
    b.warnings.iter().find_map(|w| match w {
        IdentWarning::GainPattern(p) => Some(p),
        _ => None,
    })
}

fn implausible(b: &BlockIdentification) -> bool {
    b.warnings
        .iter()
        .any(|w| matches!(w, IdentWarning::ImplausibleGain { .. }))
}

#[test]
fn a_real_gyro_in_deg_per_s_or_with_axes_swapped_says_so() {
    let settings = Settings::default();
    let plain = gyro(&real("broad07_fast_rotation"), &settings);
    assert!(
        !implausible(&plain) && pattern(&plain).is_none(),
        "{:?}",
        plain.warnings
    );

    let mut run = real("broad07_fast_rotation");
    for c in run.gyro.as_mut().expect("a gyro").iter_mut() {
        for v in c.iter_mut() {
            *v = v.to_degrees();
        }
    }
    let b = gyro(&run, &settings);
    assert!(implausible(&b));
    let p = pattern(&b).expect("a pattern");
    assert_eq!(p.units, Some(UnitSlip::OutputsInDegPerS), "{p:?}");
    assert!(p.axes.is_empty(), "{p:?}");
    assert!((p.scale / 57.2958 - 1.0).abs() < 0.01, "{}", p.scale);
    // The cause is said before the elements it makes implausible.
    let first = |f: fn(&IdentWarning) -> bool| b.warnings.iter().position(f).expect("said");
    assert!(
        first(|w| matches!(w, IdentWarning::GainPattern(_)))
            < first(|w| matches!(w, IdentWarning::ImplausibleGain { .. }))
    );

    let mut run = real("broad07_fast_rotation");
    let [gx, gy, _] = run.gyro.as_mut().expect("a gyro");
    std::mem::swap(gx, gy);
    for v in gy.iter_mut() {
        *v = -*v;
    }
    let b = gyro(&run, &settings);
    let p = pattern(&b).expect("a pattern");
    assert_eq!(p.units, None);
    let follows = |output: &str, input: &str, reversed| AxisFollows {
        output: output.to_owned(),
        input: input.to_owned(),
        reversed,
    };
    assert_eq!(
        p.axes,
        vec![follows("gx", "wy", false), follows("gy", "wx", true)]
    );
}

#[test]
fn a_simulated_accelerometer_in_g_says_so() {
    let (_, mut run) = simulated_run_of(120.0, Regime::Cruise, 5, &[]);
    for c in run.accel.as_mut().expect("an accelerometer").iter_mut() {
        for v in c.iter_mut() {
            *v /= 9.80665;
        }
    }
    let id = identify_run(&run, &Settings::default()).expect("identified");
    let accel = id.blocks.iter().find(|b| b.block == Block::Accel).expect("accel");
    let p = pattern(accel).expect("a pattern");
    assert_eq!(p.units, Some(UnitSlip::OutputsInG), "{p:?}");
    let gyro = id.blocks.iter().find(|b| b.block == Block::Gyro).expect("gyro");
    assert!(pattern(gyro).is_none(), "{:?}", gyro.warnings);
}
