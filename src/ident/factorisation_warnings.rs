//! How the warnings of a block's factorisation are found ([`super::warnings`] defines them):
//! the bins of the band where `S_uu` or the residual `S_psi` is near-singular, the factors'
//! reconstruction errors and convergence, the input factor's causality. The near-singular counts
//! depend on the spectra, the residual and the band alone; [`cached_block_warnings`] keeps them
//! with the factorisation per band, so a retune (a change of A, Lambda or the order) does not
//! compute them again.
//!
//! Contracts: a band bin outside the spectra is not counted; a NaN smallest eigenvalue counts as
//! near-singular; a NaN factor error or negative-lag fraction is said (never taken as small).

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::factorisation::{Factorisation, FactorisationSettings, input_floor, residual_loading};
use super::settings::Estimate;
use super::spectra::BlockSpectra;
use super::warnings::{FACTOR_ERROR_LIMIT, IdentWarning, Spectrum};

/// Smallest eigenvalue of the Hermitian part of `m`.
fn min_eigenvalue(m: &Matrix3<Complex64>) -> f64 {
    let h = (m + m.adjoint()) * Complex64::from(0.5);
    h.symmetric_eigenvalues().min()
}

/// The warnings of a block's factorisation over the `band` bins (indices into the spectra), for
/// a fit to `estimate`: the input factor `D_u` only enters the causal Wiener estimate (and is
/// only computed for it), so its inexactness and its non-causality are said only when the fit
/// goes through it.
#[must_use]
pub fn block_warnings(
    spectra: &BlockSpectra,
    fact: &Factorisation,
    settings: &FactorisationSettings,
    band: &[usize],
    estimate: Estimate,
) -> Vec<IdentWarning> {
    let near_singular = near_singular_bins(spectra, fact, settings, band);
    warnings_of(fact, settings, band.len(), near_singular, estimate)
}

/// [`block_warnings`] with the default settings over the native bins of `band_hz`
/// ([`super::band::native_bins`]), the near-singular counts and the band's size cached in `fact`
/// per band (they depend on the spectra, the residual and the band alone, so a retune, a change
/// of A, Lambda or the order, reuses them; the band's bins are found here, so the key is all the
/// counts depend on).
#[must_use]
pub fn cached_block_warnings(
    spectra: &BlockSpectra,
    fact: &Factorisation,
    band_hz: [f64; 2],
    estimate: Estimate,
) -> Vec<IdentWarning> {
    let settings = FactorisationSettings::default();
    let [input, residual, band_bins] = *fact.near_singular_cache.get_or_insert_with(band_hz, || {
        let band = super::band::native_bins(spectra, band_hz);
        let [input, residual] = near_singular_bins(spectra, fact, &settings, &band);
        [input, residual, band.len()]
    });
    warnings_of(fact, &settings, band_bins, [input, residual], estimate)
}

/// The bins of `band` where `S_uu` (first) and the residual `S_psi` (second) are near-singular:
/// the smallest eigenvalue of the Hermitian part below the input floor, or below the residual's
/// loading (at least the rounding of the outputs' power); a NaN eigenvalue counts.
#[must_use]
pub fn near_singular_bins(
    spectra: &BlockSpectra,
    fact: &Factorisation,
    settings: &FactorisationSettings,
    band: &[usize],
) -> [usize; 2] {
    let near_singular = |s: &[Matrix3<Complex64>], floor: &dyn Fn(usize) -> f64| {
        band.iter()
            .filter(|&&k| {
                s.get(k).is_some_and(|m| {
                    let smallest = min_eigenvalue(m);
                    smallest.is_nan() || smallest < floor(k)
                })
            })
            .count()
    };
    let floor = input_floor(&spectra.s_uu);
    // A residual vanishes below its loading, or at the rounding of the outputs' power where
    // `explained::InputEigen::residual` floors its diagonal.
    let loading = residual_loading(spectra, &fact.noise_psd, settings);
    let residual_floor = |k: usize| {
        let power = spectra
            .s_xx
            .get(k)
            .map_or(0.0, |m| (0..3).map(|i| m[(i, i)].re).fold(0.0, f64::max));
        loading.max(2.0 * super::explained::RESOLUTION * power)
    };
    [
        near_singular(&spectra.s_uu, &|_| floor),
        near_singular(&fact.noise_psd, &residual_floor),
    ]
}

/// The warnings of [`block_warnings`] from the near-singular counts over `band_bins` bins.
fn warnings_of(
    fact: &Factorisation,
    settings: &FactorisationSettings,
    band_bins: usize,
    near_singular: [usize; 2],
    estimate: Estimate,
) -> Vec<IdentWarning> {
    let causal = fact.causal_for(estimate);
    let mut warnings = Vec::new();
    for (spectrum, bins, factor) in [
        (
            Spectrum::Input,
            near_singular[0],
            causal.map(|c| (c.input_factor_error, c.input_factor_converged)),
        ),
        (
            Spectrum::Residual,
            near_singular[1],
            Some((fact.noise_factor_error, fact.noise_factor_converged)),
        ),
    ] {
        if bins > 0 {
            warnings.push(IdentWarning::Regularised {
                spectrum,
                bins,
                band_bins,
                factor_error: factor.map(|(error, _)| error),
            });
        }
        if let Some((error, converged)) = factor
            && (error.is_nan() || error > FACTOR_ERROR_LIMIT || !converged)
        {
            warnings.push(IdentWarning::FactorInexact {
                spectrum,
                factor_error: error,
                converged,
            });
        }
    }
    if let Some(c) = causal {
        let negative = c.input_factor_negative_lags;
        if negative.is_nan() || negative > settings.causality_tolerance {
            warnings.push(IdentWarning::FactorNotCausal {
                negative_lags: negative,
                refinement: c.input_refinement,
            });
        }
    }
    warnings
}
