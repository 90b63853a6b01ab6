//! The identifier's stages on synthetic systems whose answer is known exactly.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::causal_stage::{CausalStage, causal_stage};
use super::factorisation::{Factorisation, FactorisationSettings, factorise, factorise_from};
use super::settings::{Estimate, LambdaSetting};
use super::signals::BlockSignals;
use super::spectra::{BlockSpectra, block_spectra};
use super::wiener::{WienerEstimate, band_bins, regularised_wiener};
use crate::block::Block;
use crate::rng::Rng;
use crate::spectral::{WelchPlanner, WelchSettings};

const RATE: f64 = 200.0;
const DELAY: usize = 3;

/// Inputs: three cross-correlated, mildly coloured noises; outputs `K u(n - DELAY) + noise`.
fn synthetic(seed: u64, n: usize, k: Matrix3<f64>, noise: f64) -> BlockSignals {
    let mut rng = Rng::new(seed);
    let white: Vec<[f64; 3]> = (0..n + 8)
        .map(|_| [rng.normal(), rng.normal(), rng.normal()])
        .collect();
    let mut input: [Vec<f64>; 3] = Default::default();
    for t in 2..n + 2 {
        let mix = |i: usize| white[t][i] + 0.5 * white[t - 1][i] - 0.2 * white[t - 2][i];
        let (a, b, c) = (mix(0), mix(1), mix(2));
        input[0].push(a);
        input[1].push(0.6 * a + 0.8 * b);
        input[2].push(0.3 * b + 0.9 * c);
    }
    let output = std::array::from_fn(|i| {
        (0..n)
            .map(|t| {
                if t >= DELAY {
                    (0..3).map(|j| k[(i, j)] * input[j][t - DELAY]).sum::<f64>() + noise * rng.normal()
                } else {
                    0.0
                }
            })
            .collect()
    });
    BlockSignals {
        block: Block::Gyro,
        input,
        output,
    }
}

/// The spectra (256-sample segments) and the factorisation of a synthetic record.
fn short_segment_stages(seed: u64, n: usize, noise: f64) -> (BlockSpectra, Factorisation) {
    let sig = synthetic(seed, n, k_true(), noise);
    let settings = WelchSettings {
        segment_len: 256,
        ..WelchSettings::default()
    };
    let sp = block_spectra(&mut WelchPlanner::new(), &sig, RATE, &settings).expect("spectra");
    let fact = factorise(&sp, &FactorisationSettings::default()).expect("factorised");
    (sp, fact)
}

/// The causal Wiener stage of these synthetic records over 1-80 Hz.
fn causal_over_band(
    sp: &BlockSpectra,
    fact: &Factorisation,
    a: &Matrix3<f64>,
    lambda: LambdaSetting,
) -> WienerEstimate {
    regularised_wiener(sp, fact, Estimate::CausalWiener, a, lambda, [1.0, 80.0]).expect("estimated")
}

fn k_true() -> Matrix3<f64> {
    Matrix3::new(
        1.001, 0.002, -0.001, -0.0015, 0.998, 0.0005, 0.003, -0.002, 1.0005,
    )
}

#[test]
fn causal_wiener_recovers_a_causal_system_and_the_noise_spectrum() {
    let k = k_true();
    let sig = synthetic(1, 120_000, k, 0.05);
    // Long segments: a delay d within a Hann segment of N samples leaks ~(d/N)^2 of the coherent
    // power into the residual (the Welch time-delay bias), which would inflate the noise estimate.
    let settings = WelchSettings {
        segment_len: 2048,
        ..WelchSettings::default()
    };
    let sp = block_spectra(&mut WelchPlanner::new(), &sig, RATE, &settings).unwrap();
    let fact = factorise(&sp, &FactorisationSettings::default()).unwrap();
    assert!(fact.converged());
    let band = band_bins(&sp.frequency_hz, [1.0, 80.0]);
    let w = causal_over_band(&sp, &fact, &Matrix3::identity(), LambdaSetting::Values([0.0; 3]));
    let mut worst: f64 = 0.0;
    for &b in &band {
        let phase = Complex64::from_polar(
            1.0,
            -2.0 * std::f64::consts::PI * sp.frequency_hz[b] * DELAY as f64 / RATE,
        );
        let expected = k.map(|v| Complex64::from(v) * phase);
        worst = worst.max((w.w_u(b) - expected).norm() / expected.norm());
        // H1 agrees as well, and the stated uncertainty covers the error.
        assert!((fact.h1[b] - expected).norm() < 0.02 * expected.norm());
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (w.w_u(b)[(i, j)] - expected[(i, j)]).norm() < 6.0 * w.w_u_std[b][(i, j)] + 1e-3,
                    "bin {b} ({i},{j})"
                );
            }
        }
    }
    assert!(worst < 0.02, "worst relative error of W_u in band {worst}");
    // The disturbance is white with variance 0.0025: one-sided density 2 * 0.0025 / RATE.
    let expected_psd = 2.0 * 0.05f64.powi(2) / RATE;
    let mean_psd: f64 = band.iter().map(|&b| fact.noise_psd[b][(0, 0)].re).sum::<f64>() / band.len() as f64;
    assert!(
        (mean_psd / expected_psd - 1.0).abs() < 0.05,
        "noise psd {mean_psd:e} vs {expected_psd:e}"
    );
    // 2 W_psi W_psi^H reproduces the one-sided noise density.
    for &b in &band {
        let r = fact.shaping_filter[b] * fact.shaping_filter[b].adjoint() * Complex64::from(2.0);
        assert!((r - fact.noise_psd[b]).norm() < 1e-6 * fact.noise_psd[b].norm());
    }
    // Coherence is near 1 (signal power ~1, noise 0.0025).
    assert!(band.iter().all(|&b| w.coherence[b].iter().all(|&c| c > 0.99)));
}

#[test]
fn auto_lambda_minimises_the_constraint_residual() {
    let (sp, fact) = short_segment_stages(2, 40_000, 0.3);
    for a in [
        Matrix3::identity(),
        Matrix3::new(2.0, 0.3, 0.0, 0.3, 1.0, 0.1, 0.0, 0.1, 0.5),
    ] {
        let auto = causal_over_band(&sp, &fact, &a, LambdaSetting::Auto);
        assert!(auto.lambda_auto);
        assert!(auto.constraint_residual <= auto.constraint_residual_unregularised + 1e-15);
        // Brute force: every perturbation of the solved Lambda is worse.
        for i in 0..3 {
            for delta in [-1e-3, 1e-3, -1e-2, 1e-2] {
                let mut l = auto.lambda;
                l[i] += delta;
                let other = causal_over_band(&sp, &fact, &a, LambdaSetting::Values(l));
                assert!(
                    other.constraint_residual >= auto.constraint_residual - 1e-14,
                    "A={a}, lambda[{i}]+{delta}"
                );
            }
        }
        // With Lambda = 0 the weight A has no effect on W_u.
        let w0 = causal_over_band(&sp, &fact, &a, LambdaSetting::Values([0.0; 3]));
        let w1 = causal_over_band(&sp, &fact, &Matrix3::identity(), LambdaSetting::Values([0.0; 3]));
        assert_eq!(every_bin(&w0), every_bin(&w1));
    }
}

/// The `H1` estimate (the default) is `S_xu S_uu^-1` bin by bin: it meets the regularising
/// constraint `W S_uu = S_xu` to rounding, so auto-Lambda solves to 0 and leaves it unchanged,
/// and a hand-set Lambda shrinks it exactly as it shrinks `W0`.
#[test]
fn the_h1_estimate_meets_the_constraint_and_lambda_shrinks_it() {
    let (sp, fact) = short_segment_stages(4, 40_000, 0.3);
    let a = Matrix3::new(2.0, 0.3, 0.0, 0.3, 1.0, 0.1, 0.0, 0.1, 0.5);
    let auto = regularised_wiener(&sp, &fact, Estimate::H1, &a, LambdaSetting::Auto, [1.0, 80.0]).unwrap();
    assert!(auto.constraint_residual < 1e-12, "{}", auto.constraint_residual);
    assert!(auto.lambda.iter().all(|l| l.abs() < 1e-12), "{:?}", auto.lambda);
    assert_eq!(
        auto.bins(),
        sp.frequency_hz.len(),
        "W_u on the whole one-sided grid"
    );
    // The same bins by a direct solve (a naive reference: S_uu^-1 by nalgebra's LU).
    let band = band_bins(&sp.frequency_hz, [1.0, 80.0]);
    for &b in &band {
        let direct = sp.s_xu[b] * sp.s_uu[b].try_inverse().unwrap();
        assert!((auto.w_u(b) - direct).norm() < 1e-9 * direct.norm(), "bin {b}");
    }
    // The causal estimate of the same spectra does not meet it exactly (the projection's
    // leakage), which is what auto-Lambda is for.
    let causal = causal_over_band(&sp, &fact, &a, LambdaSetting::Auto);
    assert!(causal.constraint_residual_unregularised > 1e3 * auto.constraint_residual_unregularised);
    // Lambda = 0.1 on the first output with A = I scales that row by 0.9 and leaves the others.
    let shrunk = regularised_wiener(
        &sp,
        &fact,
        Estimate::H1,
        &Matrix3::identity(),
        LambdaSetting::Values([0.1, 0.0, 0.0]),
        [1.0, 80.0],
    )
    .unwrap();
    for &b in &band {
        for j in 0..3 {
            assert!((shrunk.w_u(b)[(0, j)] - fact.h1[b][(0, j)] * 0.9).norm() < 1e-12 * auto.w_u(b).norm());
            assert_eq!(shrunk.w_u(b)[(1, j)], fact.h1[b][(1, j)]);
        }
    }
}

#[test]
fn empty_band_and_singular_weight_are_errors() {
    let (sp, fact) = short_segment_stages(3, 8_000, 0.1);
    let none = regularised_wiener(
        &sp,
        &fact,
        Estimate::CausalWiener,
        &Matrix3::identity(),
        LambdaSetting::Auto,
        [0.05, 0.1],
    );
    assert!(matches!(none, Err(super::IdentError::EmptyBand { .. })));
    let singular = regularised_wiener(
        &sp,
        &fact,
        Estimate::CausalWiener,
        &Matrix3::zeros(),
        LambdaSetting::Auto,
        [1.0, 80.0],
    );
    assert!(matches!(singular, Err(super::IdentError::Singular(_))));
}

#[test]
fn refactorising_after_an_overlap_change_starts_from_the_previous_factors() {
    let sig = synthetic(5, 60_000, k_true(), 0.05);
    let welch = |overlap| WelchSettings {
        segment_len: 1024,
        overlap,
        ..WelchSettings::default()
    };
    let mut planner = WelchPlanner::new();
    let before = block_spectra(&mut planner, &sig, RATE, &welch(0.5)).unwrap();
    let after = block_spectra(&mut planner, &sig, RATE, &welch(0.6)).unwrap();
    let settings = FactorisationSettings::default();
    let previous = factorise(&before, &settings).unwrap();
    let cold = factorise(&after, &settings).unwrap();
    let warm = factorise_from(&after, &settings, Some(&previous), Estimate::CausalWiener).unwrap();
    assert!(
        previous.from_scratch_for(Estimate::CausalWiener) && cold.from_scratch_for(Estimate::CausalWiener)
    );
    assert!(
        !warm.from_scratch_for(Estimate::CausalWiener),
        "started from the previous factors"
    );
    assert!(warm.converged());
    let (w0, w0_cold, w0_previous) = (causal(&warm), causal(&cold), causal(&previous));
    assert!(
        !w0.from_scratch && !warm.noise_from_scratch,
        "both factors warm-started"
    );
    assert!(w0.input_factor_error < 1e-9 && warm.noise_factor_error < 1e-9);
    // Within the factor's own indeterminacy on this grid (about 1e-4), far below the estimate's
    // noise.
    let band = band_bins(&after.frequency_hz, [1.0, 80.0]);
    for &k in &band {
        let d = (w0.causal_wiener[k] - w0_cold.causal_wiener[k]).norm();
        assert!(d < 1e-3 * w0_cold.causal_wiener[k].norm(), "bin {k}: {d:e}");
    }
    // A warm causal stage beside a cold disturbance factor makes the factorisation provisional for
    // the causal estimate only: an H1 fit does not go through it.
    let mixed = factorise_from(&after, &settings, None, Estimate::H1)
        .unwrap()
        .with_causal_stage(w0.clone());
    assert!(mixed.from_scratch_for(Estimate::H1));
    assert!(!mixed.from_scratch_for(Estimate::CausalWiener));
    // The overlap changed the spectra: the previous factors are not the answer.
    let moved = band
        .iter()
        .map(|&k| (w0_previous.causal_wiener[k] - w0_cold.causal_wiener[k]).norm())
        .fold(0.0, f64::max);
    assert!(moved > 1e-4, "{moved:e}");
}

/// `W_u` at every bin of the grid.
fn every_bin(w: &WienerEstimate) -> Vec<Matrix3<Complex64>> {
    (0..w.bins()).map(|k| w.w_u(k)).collect()
}

/// The causal stage [`factorise`] computed.
fn causal(f: &Factorisation) -> &CausalStage {
    f.causal.as_deref().expect("factorise computes the causal stage")
}

/// The `H1` fit's factorisation has no causal stage and is otherwise the whole one to the bit;
/// the causal estimate is refused on it (not silently replaced), and the causal stage added
/// afterwards is the one the whole factorisation computes.
#[test]
fn the_h1_factorisation_skips_the_causal_stage_and_it_can_be_added() {
    let sig = synthetic(6, 40_000, k_true(), 0.05);
    let welch = WelchSettings {
        segment_len: 1024,
        ..WelchSettings::default()
    };
    let sp = block_spectra(&mut WelchPlanner::new(), &sig, RATE, &welch).unwrap();
    let settings = FactorisationSettings::default();
    let whole = factorise(&sp, &settings).unwrap();
    let h1_only = factorise_from(&sp, &settings, None, Estimate::H1).unwrap();
    assert!(h1_only.causal.is_none());
    assert!(h1_only.from_scratch_for(Estimate::H1) && h1_only.converged());
    assert_eq!(h1_only.h1, whole.h1);
    assert_eq!(h1_only.noise_psd, whole.noise_psd);
    assert_eq!(h1_only.noise_factor, whole.noise_factor);
    assert_eq!(h1_only.shaping_filter, whole.shaping_filter);
    assert!(h1_only.causal_for(Estimate::CausalWiener).is_none());
    assert!(
        whole.causal_for(Estimate::H1).is_none(),
        "an H1 fit does not use it"
    );

    let fit = |fact: &Factorisation, estimate| {
        regularised_wiener(
            &sp,
            fact,
            estimate,
            &Matrix3::identity(),
            LambdaSetting::Auto,
            [1.0, 80.0],
        )
    };
    assert!(matches!(
        fit(&h1_only, Estimate::CausalWiener),
        Err(super::IdentError::Factor(super::FactorStageError::NoCausalStage))
    ));
    assert_eq!(
        every_bin(&fit(&h1_only, Estimate::H1).unwrap()),
        every_bin(&fit(&whole, Estimate::H1).unwrap())
    );

    let added = h1_only.with_causal_stage(causal_stage(&sp, &settings, None).unwrap());
    assert!(added.from_scratch_for(Estimate::CausalWiener));
    assert!(std::sync::Arc::ptr_eq(&added.noise_factor, &h1_only.noise_factor));
    assert_eq!(causal(&added).causal_wiener, causal(&whole).causal_wiener);
    assert_eq!(causal(&added).input_refinement, causal(&whole).input_refinement);
    assert_eq!(
        every_bin(&fit(&added, Estimate::CausalWiener).unwrap()),
        every_bin(&fit(&whole, Estimate::CausalWiener).unwrap())
    );
}
