//! Numerical edges of the identifier on spectra built by hand: an input direction without power
//! is refused by name; near-singular input and residual spectra are regularised with a warning.

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;

use super::IdentError;
use super::excitation::{MIN_EXCITATION, check_excitation, excitation};
use super::factorisation::{FactorisationSettings, factorise, factorise_from};
use super::settings::Estimate;
use super::spectra::BlockSpectra;
use super::warnings::{IdentWarning, Spectrum, block_warnings, cached_block_warnings};
use crate::block::Block;

const BINS: usize = 65;
const RATE: f64 = 128.0;

fn c(v: f64) -> Complex64 {
    Complex64::from(v)
}

/// A system `x = H u + noise` with input spectra `s_uu(k)` on a one-sided grid of [`BINS`] bins.
fn spectra(s_uu: impl Fn(usize) -> Matrix3<Complex64>, noise: f64) -> BlockSpectra {
    let fft_len = 2 * (BINS - 1);
    let h = Matrix3::new(1.01, 0.02, 0.0, -0.01, 0.99, 0.03, 0.0, 0.01, 1.0).map(c);
    let s_uu: Vec<Matrix3<Complex64>> = (0..BINS).map(s_uu).collect();
    BlockSpectra {
        aligned_samples: 0,
        centroid_hz: Vec::new(),
        centroid_offset_hz: Vec::new(),
        gyro_witnessed: false,
        left_out_noise: None,
        frequency_hz: (0..BINS).map(|k| k as f64 * RATE / fft_len as f64).collect(),
        s_xu: s_uu.iter().map(|s| h * s).collect(),
        s_xx: s_uu
            .iter()
            .map(|s| h * s * h.adjoint() + Matrix3::identity() * c(noise))
            .collect(),
        s_uu,
        n_averages: 40,
        equivalent_averages: 38.0,
        bin_correlation: 1.0,
        stretches: Vec::new(),
        finer_stretches: None,
        stationarity_cache: crate::ident::stretches::StationarityCache::default(),
        held_out_cache: crate::ident::holdout::HeldOutCache::default(),
        usable_band_cache: crate::ident::band_cache::BandCache::default(),
        sample_rate_hz: RATE,
        fft_len,
        segment_len: fft_len,
    }
}

/// Every number of the factorisation stage is finite.
fn all_finite(fact: &super::factorisation::Factorisation) -> bool {
    let causal = fact.causal.as_ref().map(|c| c.causal_wiener.as_slice());
    [
        Some(fact.h1.as_slice()),
        causal,
        Some(fact.s_uu_inv.as_slice()),
        Some(fact.noise_psd.as_slice()),
        Some(fact.shaping_filter.as_slice()),
    ]
    .iter()
    .flatten()
    .all(|v| v.iter().flatten().all(|z| z.re.is_finite() && z.im.is_finite()))
}

fn diagonal(d: [f64; 3]) -> Matrix3<Complex64> {
    Matrix3::from_diagonal(&Vector3::from(d)).map(c)
}

/// The weakest direction is named by its largest component, whatever the axes' mixing.
#[test]
fn an_input_direction_without_power_is_named() {
    let band = [1.0, 60.0];
    for (weak, axis) in [(0, "wx"), (1, "wy"), (2, "wz")] {
        let mut d = [1.0, 2.0, 0.5];
        d[weak] = 1e-7;
        let sp = spectra(|_| diagonal(d), 1e-2);
        let err = check_excitation(&sp, Block::Gyro, band).unwrap_err();
        let IdentError::NotExcited {
            block,
            axis: named,
            relative_power,
            ..
        } = &err
        else {
            panic!("{err}")
        };
        assert_eq!((*block, *named), ("gyro", axis));
        let strongest = d.iter().copied().fold(0.0, f64::max);
        assert!(
            (relative_power - 1e-7 / strongest).abs() < 1e-12,
            "{relative_power}"
        );
        assert!(
            err.to_string()
                .contains(&format!("axis {axis} not excited between 1 and 60 Hz")),
            "{err}"
        );
    }
    // A deficient direction that is no axis, mostly along y.
    let v = Vector3::new(0.2, 1.0, -0.3).normalize();
    let p = Matrix3::identity() - v * v.transpose();
    let sp = spectra(|_| (p * 3.0).map(c), 1e-2);
    let err = check_excitation(&sp, Block::Accel, band).unwrap_err();
    assert!(err.to_string().contains("axis fy not excited"), "{err}");
}

#[test]
fn weak_but_present_excitation_passes() {
    let sp = spectra(|_| diagonal([1.0, 1.0, 3.0 * MIN_EXCITATION]), 1e-2);
    assert!(check_excitation(&sp, Block::Gyro, [1.0, 60.0]).is_ok());
    // Power outside the band does not count: axis z is driven only below 1 Hz.
    let sp = spectra(|k| diagonal([1.0, 1.0, if k == 0 { 1.0 } else { 1e-9 }]), 1e-2);
    assert!(check_excitation(&sp, Block::Gyro, [0.0, 60.0]).is_ok());
    assert!(matches!(
        check_excitation(&sp, Block::Gyro, [1.0, 60.0]),
        Err(IdentError::NotExcited { axis: "wz", .. })
    ));
    let e = excitation(&sp, [1.0, 60.0]).unwrap();
    assert!(e.principal_power.windows(2).all(|w| w[0] <= w[1]));
    assert!(excitation(&sp, [61.2, 61.8]).is_none(), "empty band");
}

#[test]
fn well_conditioned_spectra_give_no_warning() {
    let sp = spectra(|k| diagonal([1.0, 1.5 + (k as f64 * 0.1).sin(), 0.8]), 1e-2);
    let fact = factorise(&sp, &FactorisationSettings::default()).unwrap();
    let band: Vec<usize> = (1..BINS).collect();
    let w = block_warnings(
        &sp,
        &fact,
        &FactorisationSettings::default(),
        &band,
        Estimate::CausalWiener,
    );
    assert!(w.is_empty(), "{w:?}");
}

/// `S_uu` loses a direction in four bins only: inverted with the floor, reported with the bins.
#[test]
fn near_singular_input_bins_are_regularised_with_a_warning() {
    let sp = spectra(
        |k| diagonal([1.0, 1.0, if (20..24).contains(&k) { 1e-14 } else { 1.0 }]),
        1e-2,
    );
    let settings = FactorisationSettings::default();
    let fact = factorise(&sp, &settings).unwrap();
    assert!(all_finite(&fact), "regularised: every number finite");
    let band: Vec<usize> = (1..BINS).collect();
    let w = block_warnings(&sp, &fact, &settings, &band, Estimate::CausalWiener);
    let Some(IdentWarning::Regularised { bins, band_bins, .. }) = w.iter().find(|w| {
        matches!(
            w,
            IdentWarning::Regularised {
                spectrum: Spectrum::Input,
                ..
            }
        )
    }) else {
        panic!("no input warning in {w:?}")
    };
    assert_eq!((*bins, *band_bins), (4, BINS - 1));
    assert!(
        w[0].to_string()
            .contains("near-singular in 4 of 64 band bins: regularised (factor reconstruction error"),
        "{}",
        w[0]
    );
    // An H1 fit's factorisation has no input factor: the warning says what was regularised and
    // carries no factor error (absent from the model file, which allows no null but the
    // deviations'), and reads back the same.
    let h1_fact = factorise_from(&sp, &settings, None, Estimate::H1).unwrap();
    let h1 = block_warnings(&sp, &h1_fact, &settings, &band, Estimate::H1);
    let input = IdentWarning::Regularised {
        spectrum: Spectrum::Input,
        bins: 4,
        band_bins: BINS - 1,
        factor_error: None,
    };
    assert!(h1.contains(&input), "{h1:?}");
    assert!(
        input
            .to_string()
            .ends_with("near-singular in 4 of 64 band bins: regularised"),
        "{input}"
    );
    let json = serde_json::to_value(&input).unwrap();
    assert!(json.get("factor_error").is_none(), "{json}");
    assert_eq!(serde_json::from_value::<IdentWarning>(json).unwrap(), input);
}

/// A system without disturbance: the residual spectrum is zero and only the loading factors it.
#[test]
fn a_vanishing_residual_is_regularised_with_a_warning() {
    let sp = spectra(|_| diagonal([1.0, 2.0, 0.5]), 0.0);
    let settings = FactorisationSettings::default();
    let fact = factorise(&sp, &settings).unwrap();
    assert!(all_finite(&fact));
    let band: Vec<usize> = (1..BINS).collect();
    let w = block_warnings(&sp, &fact, &settings, &band, Estimate::CausalWiener);
    assert!(
        w.iter().any(|w| matches!(
            w,
            IdentWarning::Regularised {
                spectrum: Spectrum::Residual,
                ..
            }
        )),
        "{w:?}"
    );
}

/// The warnings of a retune come from counts cached per band: each band asked gives what
/// `block_warnings` gives on it, also when asked again after another band, and a factorisation
/// the causal stage was added to after the counts were cached (it carries them) still gives its
/// own estimate's warnings.
#[test]
fn cached_warnings_are_each_bands_own() {
    let sp = spectra(
        |k| diagonal([1.0, 1.0, if (20..24).contains(&k) { 1e-14 } else { 1.0 }]),
        1e-2,
    );
    let settings = FactorisationSettings::default();
    let h1 = factorise_from(&sp, &settings, None, Estimate::H1).unwrap();
    let bands = [(1, BINS - 1), (1, 21), (30, BINS - 1), (1, BINS - 1)];
    let check = |fact: &super::factorisation::Factorisation, estimate: Estimate| {
        for (low, high) in bands {
            let band: Vec<usize> = (low..=high).collect();
            let band_hz = [sp.frequency_hz[low], sp.frequency_hz[high]];
            let cached = cached_block_warnings(&sp, fact, band_hz, estimate);
            assert_eq!(
                cached,
                block_warnings(&sp, fact, &settings, &band, estimate),
                "{low}-{high}"
            );
            let input_bins = cached.iter().find_map(|w| match w {
                IdentWarning::Regularised {
                    spectrum: Spectrum::Input,
                    bins,
                    ..
                } => Some(*bins),
                _ => None,
            });
            let expected = (low..=high).filter(|k| (20..24).contains(k)).count();
            assert_eq!(input_bins.unwrap_or(0), expected, "{low}-{high}");
        }
    };
    check(&h1, Estimate::H1);
    // Added after the counts were cached: the causal estimate's warnings are still its own.
    let causal = h1.with_causal_stage(super::causal_stage::causal_stage(&sp, &settings, None).unwrap());
    check(&causal, Estimate::CausalWiener);
}
