//! The causal stage's grid (`causal_stage`, item 3): an input whose power sits far below the band's
//! top, as a slow manoeuvre gives, makes the input factor non-causal on the spectra's own grid;
//! the refined grid gives the causal Wiener estimate back, and where refinement is not allowed
//! the warning says so.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::causal_stage::CausalStage;
use super::factorisation::{Factorisation, FactorisationSettings, factorise};
use super::settings::Estimate;
use super::signals::BlockSignals;
use super::spectra::block_spectra;
use super::warnings::{IdentWarning, block_warnings};
use super::wiener::band_bins;
use crate::block::Block;
use crate::rng::Rng;
use crate::spectral::{WelchPlanner, WelchSettings};

const RATE: f64 = 500.0;

/// Inputs: three mixed, strongly low-passed noises (a resonance at `f0` Hz, damping 0.5, far below
/// Nyquist, plus a little white motion); outputs `K u` exactly plus `noise`.
fn slow_motion(seed: u64, n: usize, f0: f64, noise: f64) -> (BlockSignals, Matrix3<f64>) {
    let mut rng = Rng::new(seed);
    let w = 2.0 * std::f64::consts::PI * f0 / RATE;
    let (a1, a2) = (2.0 * (-0.5 * w).exp() * (w * 0.75f64.sqrt()).cos(), -(-w).exp());
    let mut state = [[0.0f64; 2]; 3];
    let mut raw: [Vec<f64>; 3] = Default::default();
    for _ in 0..n {
        for (c, s) in state.iter_mut().enumerate() {
            let x = a1 * s[0] + a2 * s[1] + rng.normal();
            *s = [x, s[0]];
            raw[c].push(x + 0.02 * rng.normal());
        }
    }
    let input: [Vec<f64>; 3] = [
        raw[0].clone(),
        raw[0]
            .iter()
            .zip(&raw[1])
            .map(|(a, b)| 0.6 * a + 0.8 * b)
            .collect(),
        raw[1]
            .iter()
            .zip(&raw[2])
            .map(|(b, c)| 0.3 * b + 0.9 * c)
            .collect(),
    ];
    let k = Matrix3::new(
        1.001, 0.002, -0.001, -0.0015, 0.998, 0.0005, 0.003, -0.002, 1.0005,
    );
    let output = std::array::from_fn(|i| {
        (0..n)
            .map(|t| (0..3).map(|j| k[(i, j)] * input[j][t]).sum::<f64>() + noise * rng.normal())
            .collect()
    });
    (
        BlockSignals {
            block: Block::Gyro,
            input,
            output,
        },
        k,
    )
}

/// The causal stage [`factorise`] computed.
fn causal(f: &Factorisation) -> &CausalStage {
    f.causal.as_deref().expect("factorise computes the causal stage")
}

/// Worst relative error of `W0` against `K` over the bins from `low` to `high` Hz.
fn worst_error(w0: &[Matrix3<Complex64>], f: &[f64], k: &Matrix3<f64>, low: f64, high: f64) -> f64 {
    let k = k.map(Complex64::from);
    band_bins(f, [low, high])
        .into_iter()
        .map(|b| (w0[b] - k).norm() / k.norm())
        .fold(0.0, f64::max)
}

#[test]
fn a_slow_input_needs_a_finer_grid_and_gets_it() {
    let (sig, k) = slow_motion(3, 60_000, 0.1, 1e-3);
    let welch = WelchSettings {
        segment_len: 2048,
        ..WelchSettings::default()
    };
    let sp = block_spectra(&mut WelchPlanner::new(), &sig, RATE, &welch).unwrap();
    let coarse_settings = FactorisationSettings {
        min_refinement: 1,
        max_refinement: 1,
        ..FactorisationSettings::default()
    };
    let coarse = factorise(&sp, &coarse_settings).unwrap();
    let fine = factorise(&sp, &FactorisationSettings::default()).unwrap();
    let (f, low, high) = (&sp.frequency_hz, 0.2, 5.0);
    let coarse_error = worst_error(&causal(&coarse).causal_wiener, f, &k, low, high);
    let fine_error = worst_error(&causal(&fine).causal_wiener, f, &k, low, high);
    let h1_error = worst_error(&fine.h1, f, &k, low, high);
    eprintln!(
        "refinement {} (negative lags {:.1e}, on the spectra's grid {:.1e}); worst error W0 {fine_error:.1e}, \
         on the spectra's grid {coarse_error:.1e}, H1 {h1_error:.1e}",
        causal(&fine).input_refinement,
        causal(&fine).input_factor_negative_lags,
        causal(&coarse).input_factor_negative_lags
    );
    assert_eq!(causal(&coarse).input_refinement, 1);
    assert!(
        causal(&coarse).input_factor_negative_lags > 1e-7,
        "the case must be a hard one"
    );
    assert!(causal(&fine).input_refinement > 1);
    assert!(causal(&fine).input_factor_negative_lags <= FactorisationSettings::default().causality_tolerance);
    // On the spectra's grid the projection cuts part of the gain (measured 13 %, where the per-bin
    // H1 is within 1e-5: the outputs are K u plus little noise); refined, W0 is within 1e-4.
    assert!(h1_error < 1e-4, "{h1_error}");
    assert!(coarse_error > 0.02, "{coarse_error}");
    assert!(fine_error < 2e-4, "{fine_error}");
    // The warning: raised where the grid could not be refined, absent where it was.
    let band = band_bins(f, [low, high]);
    let not_causal = |w: &[IdentWarning]| {
        w.iter()
            .any(|w| matches!(w, IdentWarning::FactorNotCausal { .. }))
    };
    let coarse_warnings = block_warnings(&sp, &coarse, &coarse_settings, &band, Estimate::CausalWiener);
    assert!(not_causal(&coarse_warnings), "{coarse_warnings:?}");
    // A fit to H1 does not go through the input factor: nothing to say about it.
    let h1_warnings = block_warnings(&sp, &coarse, &coarse_settings, &band, Estimate::H1);
    assert!(!not_causal(&h1_warnings), "{h1_warnings:?}");
    assert!(
        coarse_warnings
            .iter()
            .any(|w| w.to_string().contains("not causal even on a grid 1 times finer"))
    );
    let fine_warnings = block_warnings(
        &sp,
        &fine,
        &FactorisationSettings::default(),
        &band,
        Estimate::CausalWiener,
    );
    assert!(!not_causal(&fine_warnings), "{fine_warnings:?}");
}

/// A broadband input is causal at once: the first grid tried is kept (the spectra's own with
/// `min_refinement` 1, twice as fine by default).
#[test]
fn a_broadband_input_stays_on_the_first_grid() {
    let (sig, k) = slow_motion(4, 60_000, 60.0, 1e-3);
    let welch = WelchSettings {
        segment_len: 512,
        ..WelchSettings::default()
    };
    let sp = block_spectra(&mut WelchPlanner::new(), &sig, RATE, &welch).unwrap();
    for (min, want) in [(1, 1), (FactorisationSettings::default().min_refinement, 2)] {
        let settings = FactorisationSettings {
            min_refinement: min,
            ..FactorisationSettings::default()
        };
        let fact = factorise(&sp, &settings).unwrap();
        assert_eq!(
            causal(&fact).input_refinement,
            want,
            "negative lags {:.1e}",
            causal(&fact).input_factor_negative_lags
        );
        assert!(worst_error(&causal(&fact).causal_wiener, &sp.frequency_hz, &k, 1.0, 100.0) < 0.01);
    }
}
