//! The factorisation stage (everything that does not depend on A, Lambda or the order):
//! - `H1 = S_xu S_uu^-1` and the residual (disturbance) spectrum `S_psi = S_xx - S_xu S_uu^-1 S_ux`
//!   on the one-sided grid; this `S_psi` is the model's `noise_psd`;
//! - the minimum-phase factor `D_u` of the two-sided `S_uu` and `W_psi` of the two-sided `S_psi`
//!   (Wilson), so `S_psi(f) = 2 W_psi W_psi^H` for `0 < f < fs/2` (`W_psi` is the shaping filter for
//!   white noise of unit two-sided intensity);
//! - the causal multichannel Wiener filter `W0 = [S_xu D_u^-H]_+ D_u^-1` (Lambda = 0).
//!
//! Near-singular bins (an input axis with no power at that frequency, typically far outside the
//! analysis band) are regularised by an eigenvalue floor relative to the largest trace; the number
//! of such bins and the factorisations' reconstruction errors are reported.

use nalgebra::{Matrix3, SymmetricEigen};
use num_complex::Complex64;

use super::IdentError;
use super::spectra::BlockSpectra;
use crate::spectral::causal::CausalProjector;
use crate::spectral::factor::{SpectralFactor, WilsonSettings, wilson};
use crate::spectral::grid::two_sided_from_one_sided;

/// Relative eigenvalue floor used to invert `S_uu` bin by bin.
pub const INVERSE_FLOOR: f64 = 1e-9;

/// Results of the factorisation stage, one-sided grid unless said otherwise.
#[derive(Clone, Debug)]
pub struct Factorisation {
    /// `S_xu S_uu^-1` per bin (the unconstrained, non-causal estimate).
    pub h1: Vec<Matrix3<Complex64>>,
    /// `W0 = [S_xu D_u^-H]_+ D_u^-1` per bin (causal Wiener-Kolmogorov, Lambda = 0).
    pub causal_wiener: Vec<Matrix3<Complex64>>,
    /// `S_uu^-1` per bin (floored).
    pub s_uu_inv: Vec<Matrix3<Complex64>>,
    /// One-sided disturbance spectral density `S_psi`, output units^2/Hz.
    pub noise_psd: Vec<Matrix3<Complex64>>,
    /// Minimum-phase shaping filter `W_psi` (unit two-sided white input) per one-sided bin.
    pub shaping_filter: Vec<Matrix3<Complex64>>,
    /// Reconstruction error of `D_u D_u^H = S_uu` (relative, worst bin).
    pub input_factor_error: f64,
    /// Reconstruction error of `W_psi W_psi^H = S_psi` (relative, worst bin).
    pub noise_factor_error: f64,
    /// Bins whose `S_uu` needed the eigenvalue floor.
    pub floored_input_bins: usize,
    /// Whether both factorisations converged.
    pub converged: bool,
}

/// Runs the factorisation stage on a block's spectra.
///
/// # Errors
/// [`IdentError::Factor`] when a spectral factorisation is refused (empty or non-finite spectra,
/// a bin that is entirely zero) or its factor cannot be inverted.
pub fn factorise(spectra: &BlockSpectra, settings: &WilsonSettings) -> Result<Factorisation, IdentError> {
    let max_trace = spectra.s_uu.iter().map(|s| s.trace().re).fold(0.0, f64::max);
    let floor = INVERSE_FLOOR * max_trace.max(f64::MIN_POSITIVE);
    let mut floored_input_bins = 0;
    let s_uu_inv: Vec<Matrix3<Complex64>> = spectra
        .s_uu
        .iter()
        .map(|s| {
            let (inv, floored) = floored_inverse(s, floor);
            floored_input_bins += usize::from(floored);
            inv
        })
        .collect();
    let h1: Vec<Matrix3<Complex64>> = spectra
        .s_xu
        .iter()
        .zip(&s_uu_inv)
        .map(|(sxu, inv)| sxu * inv)
        .collect();
    let noise_psd: Vec<Matrix3<Complex64>> = (0..h1.len())
        .map(|k| {
            let r = spectra.s_xx[k] - h1[k] * spectra.s_xu[k].adjoint();
            (r + r.adjoint()) * Complex64::from(0.5)
        })
        .collect();

    let factor = |s: &[Matrix3<Complex64>]| -> Result<SpectralFactor<3>, IdentError> {
        let mut s = s.to_vec();
        // Mean removal empties the DC bin; a spectral zero on the unit circle has no stable
        // minimum-phase inverse. DC carries no information after detrending: repeat bin 1.
        if s.len() > 1 {
            s[0] = s[1].map(|z| Complex64::from(z.re));
        }
        let two = two_sided_from_one_sided(&s).map_err(|e| IdentError::Factor(e.to_string()))?;
        wilson(&two, settings).map_err(|e| IdentError::Factor(e.to_string()))
    };
    let d_u = factor(&spectra.s_uu)?;
    let w_psi = factor(&noise_psd)?;
    let d_u_inv = d_u.inverse().map_err(|e| IdentError::Factor(e.to_string()))?;

    let mut s_xu_dc = spectra.s_xu.clone();
    if s_xu_dc.len() > 1 {
        s_xu_dc[0] = s_xu_dc[1].map(|z| Complex64::from(z.re));
    }
    let s_xu_two = two_sided_from_one_sided(&s_xu_dc).map_err(|e| IdentError::Factor(e.to_string()))?;
    let mut g: Vec<Matrix3<Complex64>> = s_xu_two
        .iter()
        .zip(&d_u_inv)
        .map(|(s, di)| s * di.adjoint())
        .collect();
    let mut projector = CausalProjector::new(g.len()).map_err(|e| IdentError::Factor(e.to_string()))?;
    projector
        .causal_part(&mut g)
        .map_err(|e| IdentError::Factor(e.to_string()))?;
    let w0_two: Vec<Matrix3<Complex64>> = g.iter().zip(&d_u_inv).map(|(gp, di)| gp * di).collect();
    let bins = spectra.frequency_hz.len();
    let causal_wiener = w0_two[..bins].to_vec();
    let shaping_filter = w_psi.factor[..bins].to_vec();
    Ok(Factorisation {
        h1,
        causal_wiener,
        s_uu_inv,
        noise_psd,
        shaping_filter,
        input_factor_error: d_u.reconstruction_error,
        noise_factor_error: w_psi.reconstruction_error,
        floored_input_bins,
        converged: d_u.converged && w_psi.converged,
    })
}

/// Inverse of a Hermitian PSD matrix with eigenvalues floored at `floor`; says whether the floor
/// was needed.
fn floored_inverse(s: &Matrix3<Complex64>, floor: f64) -> (Matrix3<Complex64>, bool) {
    let h = (s + s.adjoint()) * Complex64::from(0.5);
    let eig = SymmetricEigen::new(h);
    let mut floored = false;
    let inv_diag = eig.eigenvalues.map(|l| {
        if l < floor {
            floored = true;
        }
        Complex64::from(1.0 / l.max(floor))
    });
    (
        eig.eigenvectors * Matrix3::from_diagonal(&inv_diag) * eig.eigenvectors.adjoint(),
        floored,
    )
}
