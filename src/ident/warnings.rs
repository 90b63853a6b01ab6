//! Warnings of an identification: results that were computed, but only after regularising a
//! near-singular spectrum, or whose spectral factors are inexact. They travel with the result
//! ([`super::identify::BlockIdentification::warnings`]) into the model file's `fit.warnings`.
//!
//! - **Input regularised**: in some band bins `S_uu` has an eigenvalue below the inversion floor
//!   ([`super::factorisation::INVERSE_FLOOR`] times the largest trace) and was inverted with its
//!   eigenvalues floored.
//! - **Residual regularised**: in some band bins the residual spectrum `S_psi` has an eigenvalue
//!   below the uniform loading its factorisation adds (the loading then dominates there).
//! - **Factor inexact**: a spectral factor reconstructs its (loaded) spectrum with a relative error
//!   above [`FACTOR_ERROR_LIMIT`], or its iteration did not converge.
//!
//! Each warning carries its figures (bins affected, bins in the band, the factor's reconstruction
//! error), so a reader can judge it; `Display` is one plain sentence.

use std::fmt;

use nalgebra::{Matrix3, SymmetricEigen};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::factorisation::{Factorisation, FactorisationSettings, INVERSE_FLOOR, residual_loading};
use super::spectra::BlockSpectra;

/// Relative reconstruction error of a spectral factor above which it is reported.
pub const FACTOR_ERROR_LIMIT: f64 = 1e-6;

/// Which spectral matrix a warning is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spectrum {
    /// The input spectral matrix `S_uu` (factor `D_u`).
    Input,
    /// The residual (disturbance) spectrum `S_psi` (factor `W_psi`).
    Residual,
}

impl Spectrum {
    fn name(self) -> &'static str {
        match self {
            Spectrum::Input => "input spectrum S_uu",
            Spectrum::Residual => "residual spectrum S_psi",
        }
    }
}

/// One warning of a block's identification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum IdentWarning {
    /// A near-singular spectrum was regularised in some band bins.
    Regularised {
        /// Which spectrum.
        spectrum: Spectrum,
        /// Band bins where it was near-singular.
        bins: usize,
        /// Bins in the band.
        band_bins: usize,
        /// Relative reconstruction error of its spectral factor.
        factor_error: f64,
    },
    /// A spectral factor is inexact or did not converge.
    FactorInexact {
        /// Which spectrum.
        spectrum: Spectrum,
        /// Relative reconstruction error (worst bin).
        factor_error: f64,
        /// Whether both factorisations converged.
        converged: bool,
    },
}

impl fmt::Display for IdentWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IdentWarning::Regularised {
                spectrum,
                bins,
                band_bins,
                factor_error,
            } => write!(
                f,
                "{} near-singular in {bins} of {band_bins} band bins: regularised \
                 (factor reconstruction error {factor_error:.1e})",
                spectrum.name()
            ),
            IdentWarning::FactorInexact {
                spectrum,
                factor_error,
                converged,
            } => write!(
                f,
                "factor of the {} is inexact: reconstruction error {factor_error:.1e}{}",
                spectrum.name(),
                if *converged { "" } else { " (not converged)" }
            ),
        }
    }
}

/// Smallest eigenvalue of the Hermitian part of `m`.
fn min_eigenvalue(m: &Matrix3<Complex64>) -> f64 {
    let h = (m + m.adjoint()) * Complex64::from(0.5);
    SymmetricEigen::new(h).eigenvalues.min()
}

/// Largest trace over all bins.
fn max_trace(s: &[Matrix3<Complex64>]) -> f64 {
    s.iter().map(|m| m.trace().re).fold(0.0, f64::max)
}

/// The warnings of a block's factorisation over the `band` bins (indices into the spectra).
#[must_use]
pub fn block_warnings(
    spectra: &BlockSpectra,
    fact: &Factorisation,
    settings: &FactorisationSettings,
    band: &[usize],
) -> Vec<IdentWarning> {
    let mut warnings = Vec::new();
    let near_singular = |s: &[Matrix3<Complex64>], floor: f64| {
        band.iter()
            .filter(|&&k| {
                s.get(k).is_some_and(|m| {
                    let smallest = min_eigenvalue(m);
                    smallest.is_nan() || smallest < floor
                })
            })
            .count()
    };
    let input_floor = INVERSE_FLOOR * max_trace(&spectra.s_uu).max(f64::MIN_POSITIVE);
    let residual_floor = residual_loading(spectra, &fact.noise_psd, settings);
    for (spectrum, bins, error) in [
        (
            Spectrum::Input,
            near_singular(&spectra.s_uu, input_floor),
            fact.input_factor_error,
        ),
        (
            Spectrum::Residual,
            near_singular(&fact.noise_psd, residual_floor),
            fact.noise_factor_error,
        ),
    ] {
        if bins > 0 {
            warnings.push(IdentWarning::Regularised {
                spectrum,
                bins,
                band_bins: band.len(),
                factor_error: error,
            });
        }
        if error.is_nan() || error > FACTOR_ERROR_LIMIT || !fact.converged {
            warnings.push(IdentWarning::FactorInexact {
                spectrum,
                factor_error: error,
                converged: fact.converged,
            });
        }
    }
    warnings
}
