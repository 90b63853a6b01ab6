//! The factorisation stage (everything that does not depend on A, Lambda or the order):
//! - `H1 = S_xu S_uu^-1` and the residual (disturbance) spectrum `S_psi = S_xx - S_xu S_uu^-1 S_ux`
//!   on the one-sided grid; this `S_psi` is the model's `noise_psd`;
//! - the minimum-phase factors `D_u` of the two-sided `S_uu` and `W_psi` of the two-sided `S_psi`
//!   (Wilson), so `S_psi(f) = 2 W_psi W_psi^H` for `0 < f < fs/2` (`W_psi` is the shaping filter for
//!   white noise of unit two-sided intensity);
//! - the causal multichannel Wiener filter `W0 = [S_xu D_u^-H]_+ D_u^-1` (Lambda = 0).
//!
//! Four numerical choices make the causal stage exact on sampled, estimated spectra; each was
//! found necessary on simulated stand runs (issue 3's and issue 13's notes) and is tested:
//! 1. **Zero-padded spectra** (`spectra::ZERO_PAD`): the Welch estimate's correlation then fits the
//!    grid, so its minimum-phase factor is an exact causal FIR, free of wrap-around.
//! 2. **Uniform loading** `S_uu + eps I` with `eps = loading * max_f tr S_uu / 3`, added on the
//!    two-sided grid (lag 0 only, so the factor stays FIR), with `S_xu` loaded consistently by
//!    `eps H1`. A bin-selective eigenvalue floor would make the factor infinitely long, and an
//!    unloaded `S_xu` would leave `-eps W D^-H`, which `D^-1` amplifies in weakly excited input
//!    directions (the accelerometer's x and y specific forces are collinear at high frequency).
//! 3. **A fixed-lag allowance** of `lag_allowance` samples in the projection,
//!    `[G e^(-j w g)]_+ e^(+j w g)`: a delay that is not a whole number of samples is causal in
//!    continuous time but, sampled and band-limited, its interpolation kernel has a tail at negative
//!    lags; `g = 0` is the paper's strict `[.]_+` and cuts that tail, biasing K by up to ~0.7 % on the
//!    accelerometer. With `g = 64`, `tests/identify_accuracy.rs` finds K within
//!    0.1 % on simulated runs whose delays are not whole samples.
//! 4. **A grid fine enough for the input factor**: Wilson's iteration works through the factor's
//!    inverse, whose impulse response is long when `S_uu` has a large dynamic range (the
//!    approach regime's slow path deviations, a real stand's low-frequency manoeuvres); on a grid
//!    too short for it the factor comes out with energy at negative lags (8.7e-5 of it on a
//!    simulated approach run at 4x zero padding), `[S_xu D_u^-H]_+` then cuts part of the gain
//!    itself, and `W0` was 2-5 % off the true K at 0.1-0.5 Hz, 5-20 of its own standard
//!    deviations, on a noise-free system where `H1` is exact. So the spectra are interpolated
//!    exactly (`spectral::refine`: they are trigonometric polynomials) onto a grid 2, 4, ... up
//!    to [`FactorisationSettings::max_refinement`] times finer until the factor's negative-lag
//!    energy is below [`FactorisationSettings::causality_tolerance`] (from 2x: no run measured,
//!    simulated or real, was causal on the spectra's own grid, 1e-6 to 1e-4 of the energy at
//!    negative lags, and each level is factored from Wilson's standard start, because an iterate
//!    from a coarser grid keeps its wrapped part: after only 4 coarse steps the finer grid's
//!    result had 8e-5 at negative lags); `D_u`, the projection and
//!    `W0` are computed there and `W0` is read back at the spectra's bins. Where even the finest
//!    grid does not hold it, [`Factorisation::input_factor_negative_lags`] says so and the
//!    warnings report it.

use std::sync::Arc;

use nalgebra::{Matrix3, SymmetricEigen};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::IdentError;
use super::spectra::BlockSpectra;
use crate::spectral::causal::CausalProjector;
use crate::spectral::factor::{SpectralFactor, WilsonSettings, wilson_from};
use crate::spectral::grid::two_sided_from_one_sided;
use crate::spectral::refine::refined;

/// Relative eigenvalue floor used to invert `S_uu` bin by bin for H1 and the residual.
pub const INVERSE_FLOOR: f64 = 1e-9;

/// Settings of the factorisation stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FactorisationSettings {
    /// Wilson's iteration.
    pub wilson: WilsonSettings,
    /// Uniform loading relative to the largest trace (see the module docs).
    pub loading: f64,
    /// Fixed-lag allowance of the causal projection, samples.
    pub lag_allowance: usize,
    /// Largest fraction of the input factor's energy allowed at negative lags before the causal
    /// stage moves to a finer grid (module docs, item 4).
    pub causality_tolerance: f64,
    /// First grid of the causal stage tried, as a multiple of the spectra's grid (a power of 2):
    /// 2, as no run measured was causal on the spectra's own grid (module docs, item 4).
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
    /// Standard deviation of each element of the frequency-response estimate per bin,
    /// `sqrt(S_psi,ii (S_uu^-1)_jj / (n_eq - 3))` (complex magnitude): what A and Lambda leave
    /// alone, so every Wiener estimate of these spectra shares it.
    pub estimate_std: Arc<Vec<Matrix3<f64>>>,
    /// Multiple coherence of each output with the three inputs per bin, `1 - S_psi,ii / S_xx,ii`
    /// (0 for a silent output), shared the same way.
    pub coherence: Arc<Vec<[f64; 3]>>,
    /// Reconstruction error of `D_u D_u^H = S_uu + eps I` (relative, worst bin).
    pub input_factor_error: f64,
    /// Reconstruction error of `W_psi W_psi^H = S_psi + eps I` (relative, worst bin).
    pub noise_factor_error: f64,
    /// Bins whose `S_uu` needed the eigenvalue floor to be inverted for H1.
    pub floored_input_bins: usize,
    /// `D_u` on the whole two-sided grid of the causal stage (the spectra's, refined
    /// `input_refinement` times): the start of a refactorisation ([`factorise_from`]).
    pub input_factor: Vec<Matrix3<Complex64>>,
    /// How many times finer than the spectra's the causal stage's grid is (module docs, item 4).
    pub input_refinement: usize,
    /// The fraction of `D_u`'s energy at negative lags on that grid (0 for an exactly causal
    /// factor; above the settings' tolerance only when the finest grid was not fine enough).
    pub input_factor_negative_lags: f64,
    /// `W_psi` on the whole two-sided grid: the start of a refactorisation.
    pub noise_factor: Vec<Matrix3<Complex64>>,
    /// Whether both factors were computed from Wilson's standard start, i.e. this is what
    /// [`factorise`] gives; false when [`factorise_from`] started from a previous factorisation.
    pub from_scratch: bool,
    /// Whether the input factor `D_u`'s iteration converged.
    pub input_factor_converged: bool,
    /// Whether the disturbance factor `W_psi`'s iteration converged.
    pub noise_factor_converged: bool,
}

impl Factorisation {
    /// Whether both factorisations converged.
    #[must_use]
    pub fn converged(&self) -> bool {
        self.input_factor_converged && self.noise_factor_converged
    }
}

fn factor_error(e: impl Into<super::FactorStageError>) -> IdentError {
    IdentError::Factor(e.into())
}

/// Runs the factorisation stage on a block's spectra.
///
/// # Errors
/// [`IdentError::Factor`] when a spectral factorisation is refused (empty or non-finite spectra,
/// a bin that is entirely zero, an odd grid) or its factor cannot be inverted.
pub fn factorise(
    spectra: &BlockSpectra,
    settings: &FactorisationSettings,
) -> Result<Factorisation, IdentError> {
    factorise_from(spectra, settings, None)
}

/// [`factorise`], Wilson's iterations started from `previous` (a factorisation of the same block
/// on the same grid, e.g. before a change of the Welch overlap; see [`wilson_from`]): about a
/// third of the Newton steps. On a finite grid the minimum-phase factor is only determined up to
/// its residual non-causality, so the result can differ from [`factorise`]'s at that level: on
/// the 30-minute, 1 kHz cruise run the input factors differ by up to 7e-5 (relative), which
/// moves the identified K by up to about one standard deviation. Such a result is provisional
/// ([`Factorisation::from_scratch`] false): the app shows it while the settings move and then
/// refactorises from scratch. A `previous` on another grid is ignored.
///
/// # Errors
/// Those of [`factorise`].
pub fn factorise_from(
    spectra: &BlockSpectra,
    settings: &FactorisationSettings,
    previous: Option<&Factorisation>,
) -> Result<Factorisation, IdentError> {
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

    let eps = settings.loading * max_trace / 3.0;
    // The two factorisations are independent: one per core.
    let residual_eps = residual_loading(spectra, &noise_psd, settings);
    let starts = previous.map(|p| (p.input_factor.as_slice(), p.noise_factor.as_slice()));
    let start_refinement = previous.map_or(1, |p| p.input_refinement);
    let (d_u, w_psi) = rayon::join(
        || {
            causal_input_factor(
                &spectra.s_uu,
                eps,
                settings,
                starts.map(|s| s.0),
                start_refinement,
            )
        },
        || loaded_factor(&noise_psd, residual_eps, &settings.wilson, starts.map(|s| s.1)),
    );
    let ((d_u, input_refinement, input_factor_negative_lags), w_psi) = (d_u?, w_psi?);
    let d_u_inv = d_u.inverse().map_err(factor_error)?;

    // Consistent loading: (S_xu + eps H1) = H1 (S_uu + eps I) on every bin of the two-sided grid
    // (the refined grid's H1 from the refined spectra, so the identity holds there too).
    let s_xu_two = refined(
        &two_sided_from_one_sided(&spectra.s_xu).map_err(factor_error)?,
        input_refinement,
    )
    .map_err(factor_error)?;
    let s_uu_two = refined(
        &two_sided_from_one_sided(&spectra.s_uu).map_err(factor_error)?,
        input_refinement,
    )
    .map_err(factor_error)?;
    let n = s_xu_two.len();
    let mut g: Vec<Matrix3<Complex64>> = s_xu_two
        .iter()
        .zip(&s_uu_two)
        .zip(&d_u_inv)
        .map(|((s, suu), di)| {
            let h = s * floored_inverse(suu, floor * 0.5).0;
            (s + h * Complex64::from(eps)) * di.adjoint()
        })
        .collect();
    let mut projector = CausalProjector::new(n).map_err(factor_error)?;
    // The refined grid has the same lag spacing (one sample), only more lags: the allowance in
    // samples is unchanged.
    let lag = settings.lag_allowance as f64;
    shift_lags(&mut g, lag);
    projector.causal_part(&mut g).map_err(factor_error)?;
    shift_lags(&mut g, -lag);
    let bins = spectra.frequency_hz.len();
    let causal_wiener = (0..bins)
        .map(|k| g[k * input_refinement] * d_u_inv[k * input_refinement])
        .collect();
    let estimate_std = Arc::new(estimate_std(spectra, &noise_psd, &s_uu_inv));
    let coherence = Arc::new(coherence(spectra, &noise_psd));
    Ok(Factorisation {
        estimate_std,
        coherence,
        h1,
        causal_wiener,
        s_uu_inv,
        noise_psd,
        shaping_filter: w_psi.factor[..bins].to_vec(),
        input_factor_error: d_u.reconstruction_error,
        noise_factor_error: w_psi.reconstruction_error,
        floored_input_bins,
        input_factor_converged: d_u.converged,
        noise_factor_converged: w_psi.converged,
        from_scratch: !(d_u.from_start || w_psi.from_start),
        input_factor: d_u.factor,
        input_refinement,
        input_factor_negative_lags,
        noise_factor: w_psi.factor,
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
    let max_trace = |s: &[Matrix3<Complex64>]| s.iter().map(|m| m.trace().re).fold(0.0, f64::max);
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
fn loaded_two_sided(
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

/// Wilson factor of the two-sided `S_uu + eps I` on the spectra's grid refined `min_refinement`,
/// twice that, ... times (from `start_refinement`, a previous factorisation's, when its factor
/// fits that grid; the result is then marked as started from it) until its
/// negative-lag energy is within the settings' tolerance or the finest grid is reached (module
/// docs, item 4). Returns the factor on its grid, the refinement and the negative-lag fraction.
fn causal_input_factor(
    one_sided: &[Matrix3<Complex64>],
    eps: f64,
    settings: &FactorisationSettings,
    start: Option<&[Matrix3<Complex64>]>,
    start_refinement: usize,
) -> Result<(SpectralFactor<3>, usize, f64), IdentError> {
    let two = loaded_two_sided(one_sided, eps)?;
    let max_refinement = settings.max_refinement.max(1);
    let min_refinement = settings.min_refinement.clamp(1, max_refinement);
    // A previous factorisation's grid is reused only when its factor fits this grid refined as
    // often (a Welch change of segment length changes the grid).
    let start_r = start_refinement.clamp(min_refinement, max_refinement);
    let (mut r, mut start) = match start {
        Some(f) if f.len() == start_r * two.len() => (start_r, Some(f)),
        _ => (min_refinement, None),
    };
    // Another path than `factorise`'s (another first grid) is not its result: provisional.
    let other_path = r != min_refinement;
    loop {
        let grid = refined(&two, r).map_err(factor_error)?;
        let mut factor = wilson_from(&grid, &settings.wilson, start).map_err(factor_error)?;
        let negative = CausalProjector::new(grid.len())
            .and_then(|mut p| p.negative_lag_fraction(&factor.factor))
            .map_err(factor_error)?;
        if negative <= settings.causality_tolerance || r >= max_refinement {
            factor.from_start |= other_path;
            return Ok((factor, r, negative));
        }
        // From Wilson's standard start again: started from the coarse factor, the iteration keeps
        // its negative lags (on a finite grid the fixed point is not unique at that level), and
        // from the coarse factor's causal part it can take a hundred times longer (measured on a
        // 30-minute run).
        start = None;
        r = (r * 2).min(max_refinement);
    }
}

/// Delays a function on the two-sided grid by `lag` samples (`F[k] e^{-2 pi i k lag / N}`, `k`
/// signed), moving lags `-lag..0` to `0..lag`.
fn shift_lags(f: &mut [Matrix3<Complex64>], lag: f64) {
    let n = f.len();
    for (k, m) in f.iter_mut().enumerate() {
        let signed = if k <= n / 2 { k as f64 } else { k as f64 - n as f64 };
        *m *= Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * signed * lag / n as f64);
    }
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
