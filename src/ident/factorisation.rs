//! The factorisation stage (everything that does not depend on A, Lambda or the order):
//! - `H1 = S_xu S_uu^-1` and the residual (disturbance) spectrum `S_psi = S_xx - S_xu S_uu^-1 S_ux`
//!   on the one-sided grid ([`super::explained`]: along `S_uu`'s eigenvectors, its diagonal
//!   floored at the output's rounding); this `S_psi` is the model's `noise_psd`;
//! - the minimum-phase factor `W_psi` of the two-sided `S_psi` (Wilson), so
//!   `S_psi(f) = 2 W_psi W_psi^H` for `0 < f < fs/2` (`W_psi` is the shaping filter for white
//!   noise of unit two-sided intensity);
//! - when the causal estimate is asked for, the causal stage ([`super::causal_stage`]): the
//!   minimum-phase factor `D_u` of the two-sided `S_uu` and the causal multichannel Wiener filter
//!   `W0 = [S_xu D_u^-H]_+ D_u^-1` (Lambda = 0). The default `H1` fit does not go through it.
//!
//! The spectra are zero-padded (`spectra::ZERO_PAD`): the Welch estimate's correlation then fits
//! the grid, so a minimum-phase factor is an exact causal FIR, free of wrap-around. The residual is
//! loaded uniformly before its factorisation ([`residual_loading`]) so that a vanishing residual is
//! still factored. Non-finite, empty or odd-grid spectra are refused ([`IdentError::Factor`]),
//! never propagated; `S_uu` is inverted bin by bin with an eigenvalue floor
//! ([`INVERSE_FLOOR`] of its largest trace), and the bins that needed it are counted.

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::FactorStageError::{NonFiniteInput, NonFiniteResidual};
use super::causal_stage::{CausalStage, causal_stage};
use super::explained::InputEigen;
use super::settings::Estimate;
use super::spectra::BlockSpectra;
use super::{FactorStageError, IdentError};
use crate::spectral::factor::{SpectralFactor, WilsonSettings, wilson_from};
use crate::spectral::grid::two_sided_from_one_sided;

/// Relative eigenvalue floor used to invert `S_uu` bin by bin for H1 and the residual.
pub const INVERSE_FLOOR: f64 = 1e-9;

/// Settings of the factorisation stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FactorisationSettings {
    /// Wilson's iteration.
    pub wilson: WilsonSettings,
    /// Uniform loading relative to the largest trace (`super::causal_stage`, item 1, and
    /// [`residual_loading`]).
    pub loading: f64,
    /// Fixed-lag allowance of the causal projection, samples.
    pub lag_allowance: usize,
    /// Largest fraction of the input factor's energy allowed at negative lags before the causal
    /// stage moves to a finer grid (`super::causal_stage`, item 3).
    pub causality_tolerance: f64,
    /// First grid of the causal stage tried, as a multiple of the spectra's grid (a power of 2):
    /// 2, as no run measured was causal on the spectra's own grid (`super::causal_stage`, item 3).
    pub min_refinement: usize,
    /// Finest grid of the causal stage, as a multiple of the spectra's grid (a power of 2).
    pub max_refinement: usize,
}

impl Default for FactorisationSettings {
    fn default() -> Self {
        Self {
            wilson: WilsonSettings {
                eigen_floor: 1e-13,
                ..WilsonSettings::default()
            },
            loading: 1e-9,
            lag_allowance: 64,
            causality_tolerance: 1e-9,
            min_refinement: 2,
            max_refinement: 16,
        }
    }
}

/// Results of the factorisation stage, one-sided grid unless said otherwise.
#[derive(Clone, Debug)]
pub struct Factorisation {
    /// `S_xu S_uu^-1` per bin (the unconstrained, non-causal estimate), shared with the Wiener
    /// estimates made from it.
    pub h1: Arc<Vec<Matrix3<Complex64>>>,
    /// `S_uu^-1` per bin (floored).
    pub s_uu_inv: Vec<Matrix3<Complex64>>,
    /// One-sided disturbance spectral density `S_psi`, output units^2/Hz.
    pub noise_psd: Vec<Matrix3<Complex64>>,
    /// Minimum-phase shaping filter `W_psi` (unit two-sided white input) per one-sided bin.
    pub shaping_filter: Vec<Matrix3<Complex64>>,
    /// Standard deviation of each element of the frequency-response estimate per bin,
    /// `sqrt(S_psi,ii (S_uu^-1)_jj / (n_eq - 3))` (complex magnitude): what A and Lambda leave
    /// alone, so every Wiener estimate of these spectra shares it.
    pub estimate_std: Arc<Vec<Matrix3<f64>>>,
    /// Multiple coherence of each output with the three inputs per bin, `1 - S_psi,ii / S_xx,ii`
    /// (0 for a silent output), shared the same way.
    pub coherence: Arc<Vec<[f64; 3]>>,
    /// Reconstruction error of `W_psi W_psi^H = S_psi + eps I` (relative, worst bin).
    pub noise_factor_error: f64,
    /// Bins whose `S_uu` needed the eigenvalue floor to be inverted for H1.
    pub floored_input_bins: usize,
    /// `W_psi` on the whole two-sided grid: the start of a refactorisation (shared with the
    /// factorisation the causal stage is later added to: [`Factorisation::with_causal_stage`]).
    pub noise_factor: Arc<Vec<Matrix3<Complex64>>>,
    /// Whether the disturbance factor `W_psi`'s iteration converged.
    pub noise_factor_converged: bool,
    /// Whether `W_psi` was computed from Wilson's standard start.
    pub noise_from_scratch: bool,
    /// The causal stage (`D_u`, `W0`), computed only when the causal estimate is asked for
    /// ([`factorise_from`]); shared between the factorisations it was added to.
    pub causal: Option<Arc<CausalStage>>,
    /// The near-singular bins of `S_uu` and `S_psi` and the band's size, per band
    /// ([`super::warnings::cached_block_warnings`]): they do not depend on the causal stage, so a
    /// factorisation it is added to keeps them. A copy whose `noise_psd` (or whose spectra) is
    /// then changed must be given an empty cache (`BandCache::default()`).
    pub near_singular_cache: super::band_cache::BandCache<[usize; 3]>,
}

impl Factorisation {
    /// Whether the factorisations computed (the disturbance's, and the input's if the causal
    /// stage was) converged.
    #[must_use]
    pub fn converged(&self) -> bool {
        self.noise_factor_converged && self.causal.as_ref().is_none_or(|c| c.input_factor_converged)
    }

    /// Whether every factor `estimate` goes through (the disturbance's, and the input's for the
    /// causal estimate) was computed from Wilson's standard start, i.e. is what [`factorise_from`]
    /// gives without a previous factorisation; false when one started from a previous one. A
    /// causal stage an `H1` fit does not use does not count.
    #[must_use]
    pub fn from_scratch_for(&self, estimate: Estimate) -> bool {
        self.noise_from_scratch && self.causal_for(estimate).is_none_or(|c| c.from_scratch)
    }

    /// The causal stage when `estimate` goes through it (the causal estimate) and it was
    /// computed; `None` for an `H1` fit, whatever was computed.
    #[must_use]
    pub fn causal_for(&self, estimate: Estimate) -> Option<&CausalStage> {
        match estimate {
            Estimate::H1 => None,
            Estimate::CausalWiener => self.causal.as_deref(),
        }
    }

    /// The frequency-response estimate `estimate` per one-sided bin.
    ///
    /// # Errors
    /// [`FactorStageError::NoCausalStage`] for the causal estimate of a factorisation computed
    /// without its causal stage.
    pub fn estimate(&self, estimate: Estimate) -> Result<&Arc<Vec<Matrix3<Complex64>>>, IdentError> {
        match estimate {
            Estimate::H1 => Ok(&self.h1),
            Estimate::CausalWiener => self
                .causal
                .as_deref()
                .map(|c| &c.causal_wiener)
                .ok_or(IdentError::Factor(FactorStageError::NoCausalStage)),
        }
    }
}

pub(super) fn factor_error(e: impl Into<super::FactorStageError>) -> IdentError {
    IdentError::Factor(e.into())
}

/// Runs the factorisation stage on a block's spectra, the causal stage included.
///
/// # Errors
/// [`IdentError::Factor`] when a spectral factorisation is refused (empty or non-finite spectra,
/// a bin that is entirely zero, an odd grid) or its factor cannot be inverted.
pub fn factorise(
    spectra: &BlockSpectra,
    settings: &FactorisationSettings,
) -> Result<Factorisation, IdentError> {
    factorise_from(spectra, settings, None, Estimate::CausalWiener)
}

/// The factorisation stage `estimate` needs (the causal stage only for the causal estimate),
/// Wilson's iterations started from `previous` (a factorisation of the same block on the same
/// grid, e.g. before a change of the Welch overlap; see [`wilson_from`]): about a third of the
/// Newton steps. On a finite grid the minimum-phase factor is only determined up to its residual
/// non-causality, so the result can differ from a cold one at that level: on the 30-minute, 1 kHz
/// cruise run the input factors differ by up to 7e-5 (relative), which moves the identified K of
/// a causal fit by up to about one standard deviation. Such a result is provisional
/// ([`Factorisation::from_scratch_for`] false): the app shows it while the settings move and then
/// refactorises from scratch. A `previous` on another grid is ignored.
///
/// # Errors
/// Those of [`factorise`].
pub fn factorise_from(
    spectra: &BlockSpectra,
    settings: &FactorisationSettings,
    previous: Option<&Factorisation>,
    estimate: Estimate,
) -> Result<Factorisation, IdentError> {
    let floor = input_floor(&spectra.s_uu);
    // One decomposition of S_uu per bin gives its inverse and, along its eigenvectors (resolved
    // where S_uu is ill-conditioned, unlike `h1 S_ux`), the residual.
    let mut floored_input_bins = 0;
    let mut s_uu_inv = Vec::with_capacity(spectra.s_uu.len());
    let mut noise_psd = Vec::with_capacity(spectra.s_uu.len());
    for (k, s) in spectra.s_uu.iter().enumerate() {
        let eig = InputEigen::new(s, floor).ok_or_else(|| factor_error(NonFiniteInput { bin: k }))?;
        floored_input_bins += usize::from(eig.floored());
        s_uu_inv.push(eig.inverse());
        let residual = eig.residual(&spectra.s_xx[k], &spectra.s_xu[k]);
        noise_psd.push(residual.ok_or_else(|| factor_error(NonFiniteResidual { bin: k }))?);
    }
    let h1: Arc<Vec<Matrix3<Complex64>>> = Arc::new(
        spectra
            .s_xu
            .iter()
            .zip(&s_uu_inv)
            .map(|(sxu, inv)| sxu * inv)
            .collect(),
    );

    // The disturbance's factorisation and the causal stage (the input's) are independent: one per
    // core when both are computed.
    let residual_eps = residual_loading(spectra, &noise_psd, settings);
    let (causal, w_psi) = rayon::join(
        || match estimate {
            Estimate::H1 => Ok(None),
            Estimate::CausalWiener => {
                let start = previous.and_then(|p| p.causal.as_deref());
                causal_stage(spectra, settings, start).map(|c| Some(Arc::new(c)))
            }
        },
        || {
            let start = previous.map(|p| p.noise_factor.as_slice());
            loaded_factor(&noise_psd, residual_eps, &settings.wilson, start)
        },
    );
    let (causal, w_psi) = (causal?, w_psi?);
    let bins = spectra.frequency_hz.len();
    let estimate_std = Arc::new(estimate_std(spectra, &noise_psd, &s_uu_inv));
    let coherence = Arc::new(coherence(spectra, &noise_psd));
    Ok(Factorisation {
        estimate_std,
        coherence,
        h1,
        s_uu_inv,
        noise_psd,
        shaping_filter: w_psi.factor[..bins].to_vec(),
        noise_factor_error: w_psi.reconstruction_error,
        floored_input_bins,
        noise_factor_converged: w_psi.converged,
        noise_from_scratch: !w_psi.from_start,
        noise_factor: Arc::new(w_psi.factor),
        causal,
        near_singular_cache: super::band_cache::BandCache::default(),
    })
}

/// `sqrt(S_psi,ii (S_uu^-1)_jj / (n_eq - 3))` per bin (see [`Factorisation::estimate_std`]).
fn estimate_std(
    spectra: &BlockSpectra,
    noise_psd: &[Matrix3<Complex64>],
    s_uu_inv: &[Matrix3<Complex64>],
) -> Vec<Matrix3<f64>> {
    let dof = (spectra.equivalent_averages - 3.0).max(1.0);
    noise_psd
        .iter()
        .zip(s_uu_inv)
        .map(|(noise, inv)| {
            Matrix3::from_fn(|i, j| (noise[(i, i)].re.max(0.0) * inv[(j, j)].re.max(0.0) / dof).sqrt())
        })
        .collect()
}

/// `1 - S_psi,ii / S_xx,ii` per bin, clamped to `[0, 1]`, 0 where `S_xx,ii` is 0.
fn coherence(spectra: &BlockSpectra, noise_psd: &[Matrix3<Complex64>]) -> Vec<[f64; 3]> {
    noise_psd
        .iter()
        .zip(&spectra.s_xx)
        .map(|(noise, s_xx)| {
            std::array::from_fn(|i| {
                let sxx = s_xx[(i, i)].re;
                if sxx > 0.0 {
                    (1.0 - noise[(i, i)].re / sxx).clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
        })
        .collect()
}

/// Largest trace over all bins (0 for none).
#[must_use]
pub fn max_trace(s: &[Matrix3<Complex64>]) -> f64 {
    s.iter().map(|m| m.trace().re).fold(0.0, f64::max)
}

/// The eigenvalue floor below which `S_uu` is near-singular and floored to be inverted:
/// [`INVERSE_FLOOR`] times its largest trace (never 0).
#[must_use]
pub fn input_floor(s_uu: &[Matrix3<Complex64>]) -> f64 {
    INVERSE_FLOOR * max_trace(s_uu).max(f64::MIN_POSITIVE)
}

/// The uniform loading added to the residual spectrum before its factorisation:
/// `loading * max_f tr S_psi / 3`, but never below `loading * INVERSE_FLOOR * max_f tr S_xx / 3`,
/// so that a residual that vanishes (an output explained exactly by the inputs) is still factored
/// (as a tiny white disturbance) instead of refused; the warnings report it.
#[must_use]
pub fn residual_loading(
    spectra: &BlockSpectra,
    noise_psd: &[Matrix3<Complex64>],
    settings: &FactorisationSettings,
) -> f64 {
    let scale = max_trace(noise_psd).max(INVERSE_FLOOR * max_trace(&spectra.s_xx));
    settings.loading * scale / 3.0
}

/// Wilson factor of the two-sided `s + eps I` (loading added after the one-/two-sided conversion,
/// so it is exactly a lag-0 term).
fn loaded_factor(
    one_sided: &[Matrix3<Complex64>],
    eps: f64,
    settings: &WilsonSettings,
    start: Option<&[Matrix3<Complex64>]>,
) -> Result<SpectralFactor<3>, IdentError> {
    wilson_from(&loaded_two_sided(one_sided, eps)?, settings, start).map_err(factor_error)
}

/// The two-sided `s + eps I` (loading added after the one-/two-sided conversion, so it is exactly
/// a lag-0 term).
pub(super) fn loaded_two_sided(
    one_sided: &[Matrix3<Complex64>],
    eps: f64,
) -> Result<Vec<Matrix3<Complex64>>, IdentError> {
    let mut two = two_sided_from_one_sided(one_sided).map_err(factor_error)?;
    let load = Matrix3::identity() * Complex64::from(eps.max(f64::MIN_POSITIVE));
    for s in &mut two {
        *s += load;
    }
    Ok(two)
}
