use super::explains_through;
use crate::block::Block;
use crate::diagnose::structure::{Filters, LagShape, Structure, Theta};
use crate::effect::Effect;
use crate::model::band_limit::{BandLimitShape, FittedBandLimit};
use crate::model::effects::{AcceptedEffect, Identified, ModelEffects, Resonance};

#[test]
fn the_model_files_response_is_the_fitted_structures() {
    // The model file's formula against the diagnosis's filters, term by term.
    let structure = Structure {
        lag: Some(LagShape::FirstOrder),
        skew: true,
        resonance_axes: vec![2, 0],
        band_limit: Some(BandLimitShape::Causal2),
        ..Structure::default()
    };
    let theta = Theta {
        tau_s: 0.0042,
        skew_s: [0.0003, -0.0001],
        lag_s: 0.0015,
        lag_damping: 0.0,
        band_limit_t_s: 0.002,
        resonances: vec![(23.0, 0.05), (31.0, 0.2)],
    };
    let k = [
        [1.01, 0.002, -0.003],
        [0.001, 0.99, 0.004],
        [-0.002, 0.003, 1.002],
    ];
    let effects = ModelEffects {
        lag_s: Some(theta.lag_s),
        lag_damping: None,
        channel_skew_s: Some(theta.channel_skew_s()),
        resonances: vec![
            Resonance {
                axis: 2,
                frequency_hz: 23.0,
                damping: 0.05,
            },
            Resonance {
                axis: 0,
                frequency_hz: 31.0,
                damping: 0.2,
            },
        ],
        reference_band_limit: Some(FittedBandLimit {
            shape: BandLimitShape::Causal2,
            t_s: theta.band_limit_t_s,
        }),
        ..accepted(&[])
    };
    for f in [0.3, 5.0, 22.9, 30.0, 39.0] {
        let filters = Filters::at(&structure, &theta, f);
        let h = effects.response(&k, theta.tau_s, f);
        for i in 0..3 {
            for j in 0..3 {
                let want = filters.channel[i] * filters.resonant[j] * k[i][j];
                assert!(
                    (h[(i, j)] - want).norm() < 1e-12 * want.norm().max(1.0),
                    "{f} {i} {j}"
                );
            }
        }
    }
    // Poles: the lag's and each resonance's pair.
    let poles = effects.poles();
    assert_eq!(poles.len(), 5);
    assert!((poles[0][0] + 1.0 / 0.0015).abs() < 1e-9);
    let w = std::f64::consts::TAU * 23.0;
    assert!((poles[1][0] + 0.05 * w).abs() < 1e-9 && (poles[1][0].hypot(poles[1][1]) - w).abs() < 1e-9);
}

/// A second-order lag in the model file: its response the diagnosis's filter's, `1 / 2 zeta`
/// at its corner with a phase of -90 degrees, and its poles the roots of
/// `(T s)^2 + 2 zeta T s + 1`, a pair when underdamped, two real ones when overdamped.
#[test]
fn a_second_order_lag_is_the_same_in_the_model_file() {
    let structure = Structure {
        lag: Some(LagShape::SecondOrder),
        ..Structure::default()
    };
    let k = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for zeta in [0.5, 1.0 / 2f64.sqrt(), 1.6] {
        let theta = Theta {
            lag_s: 1.0 / (std::f64::consts::TAU * 20.0),
            lag_damping: zeta,
            ..Theta::delay_only(0.0)
        };
        let effects = ModelEffects {
            lag_s: Some(theta.lag_s),
            lag_damping: Some(zeta),
            ..accepted(&[])
        };
        for f in [0.3, 5.0, 20.0, 39.0] {
            let want = Filters::at(&structure, &theta, f).channel[0];
            let h = effects.response(&k, 0.0, f)[(0, 0)];
            assert!((h - want).norm() < 1e-12, "{zeta} {f}: {h} {want}");
        }
        let at_corner = effects.response(&k, 0.0, 20.0)[(1, 1)];
        assert!(
            (at_corner.norm() - 1.0 / (2.0 * zeta)).abs() < 1e-12,
            "{at_corner}"
        );
        assert!((at_corner.arg() + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let poles = effects.poles();
        assert_eq!(poles.len(), 2);
        for [re, im] in poles {
            let p = num_complex::Complex64::new(re, im) * theta.lag_s;
            assert!((p * p + 2.0 * zeta * p + 1.0).norm() < 1e-9, "{zeta}: {p}");
        }
    }
}

/// The mode's gain is the resonant low-pass's: 1 at DC, `1 / 2 zeta` at the mode, and each
/// element of the model's response (`Filters`) has it in its column.
#[test]
fn a_mode_s_gain_is_its_low_pass_s() {
    let r = Resonance {
        axis: 1,
        frequency_hz: 23.0,
        damping: 0.05,
    };
    assert!((r.gain(0.0) - 1.0).abs() < 1e-15);
    assert!((r.gain(23.0) - 10.0).abs() < 1e-12);
    // Far above: (f_n / f)^2.
    assert!((r.gain(2300.0) / 1e-4 - 1.0).abs() < 1e-3);
    let structure = Structure {
        resonance_axes: vec![1],
        ..Structure::default()
    };
    let theta = Theta {
        resonances: vec![(23.0, 0.05)],
        ..Theta::delay_only(0.0)
    };
    for f in [1.0, 20.0, 31.0] {
        let m = Filters::at(&structure, &theta, f).resonant[1].norm();
        assert!((m - r.gain(f)).abs() < 1e-12 * m, "{f}: {m} {}", r.gain(f));
    }
}

fn accepted(effects: &[Effect]) -> ModelEffects {
    ModelEffects {
        accepted: effects
            .iter()
            .map(|&effect| AcceptedEffect {
                effect,
                name: effect.name_on(Block::Gyro),
                parameters: serde_json::Value::Null,
                parameter_std: serde_json::json!({ "T_s": [null, 1e-4] }),
            })
            .collect(),
        not_added: Vec::new(),
        lag_s: None,
        lag_damping: None,
        channel_skew_s: None,
        resonances: Vec::new(),
        reference_band_limit: None,
        identified: Identified {
            k: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            tau_s: 0.004,
            order: 0,
            band_hz: None,
        },
        band_hz: [0.1, 40.0],
        chi2_per_dof: [100.0, 1.0],
        gap_db: [[0.0; 3]; 2],
    }
}

/// A fit through the band the identified model's misfit cut replaces the cut band's where
/// it holds a filter it determines (the mode, a band limit, a lag) and every effect the cut
/// band's holds, explains the data, and so does the stretch it adds (the chi2 it adds over
/// its own below the cut, per degree of freedom added, at most 2), each condition alone
/// deciding.
#[test]
fn a_fit_through_the_cut_band_is_kept_where_it_explains_it() {
    let mode = Effect::PlatformResonance;
    let with = |effects: &[Effect], chi2: f64| ModelEffects {
        chi2_per_dof: [100.0, chi2],
        ..accepted(effects)
    };
    let narrow = with(&[mode], 0.7);
    // 600 degrees of freedom below the cut (its own chi2 there 0.7 per), 400 added.
    let (dof, below) = ([600.0, 1000.0], 420.0);
    assert!(explains_through(&with(&[mode], 0.8), &narrow, below, dof));
    // Whole band at 1.58 (under 2), but the stretch added at 2.9: the cut stays.
    assert!(!explains_through(&with(&[mode], 1.58), &narrow, below, dof));
    assert!(!explains_through(&with(&[mode], f64::NAN), &narrow, below, dof));
    assert!(!explains_through(&with(&[mode], 0.8), &narrow, f64::NAN, dof));
    // The stretch judged on the wider fit's own chi2 below, not the narrow fit's: a mode
    // above the cut that the narrow fit could not hold (its chi2/dof 50), the wider fit at
    // 1.9 over the whole band and 0.8 below: the stretch at 3.55.
    assert!(!explains_through(
        &with(&[mode], 1.9),
        &with(&[], 50.0),
        480.0,
        dof
    ));
    assert!(explains_through(
        &with(&[mode], 1.0),
        &with(&[], 50.0),
        480.0,
        dof
    ));
    // The whole band above 2 with the stretch at 2.0 (the fit worse below, 2.33 per).
    assert!(!explains_through(&with(&[mode], 2.2), &narrow, 1400.0, dof));
    // Without a filter it was tried for (a g-sensitivity and a tone shape no band top), or
    // without an effect the cut band's fit holds.
    assert!(!explains_through(
        &with(&[Effect::GSensitivity, Effect::VibrationTone], 0.8),
        &with(&[], 0.7),
        below,
        dof
    ));
    // Any filter whose misfit grows towards the top may take the band back: the stand's
    // band limit or lag, the block's lag or channel delays.
    for filter in [
        Effect::ReferenceBandLimit,
        Effect::ReferenceLag,
        Effect::SensorLag,
        Effect::AxisTimeSkew,
    ] {
        assert!(explains_through(
            &with(&[filter], 0.8),
            &with(&[], 0.7),
            below,
            dof
        ));
        assert!(!explains_through(
            &with(&[filter], 1.58),
            &with(&[], 0.7),
            below,
            dof
        ));
    }
    // A filter the wider fit does not determine (held at its bound or unseen: its deviations
    // `null`) does not take the band back, whatever the chi2.
    let mut held = with(&[Effect::ReferenceBandLimit], 0.8);
    held.accepted[0].parameter_std = serde_json::json!({ "T_s": null, "corner_hz": [null] });
    assert!(!explains_through(&held, &with(&[], 0.7), below, dof));
    assert!(!explains_through(
        &with(&[mode], 0.8),
        &with(&[mode, Effect::SensorLag], 0.7),
        below,
        dof
    ));
    assert!(explains_through(
        &with(&[mode, Effect::SensorLag], 0.8),
        &narrow,
        below,
        dof
    ));
    // No band added (fewer or as many degrees of freedom).
    assert!(!explains_through(
        &with(&[mode], 0.8),
        &narrow,
        below,
        [1000.0, 600.0]
    ));
    assert!(!explains_through(
        &with(&[mode], 0.6),
        &narrow,
        below,
        [600.0, 600.0]
    ));
}
