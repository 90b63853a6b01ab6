//! The causal stage of the factorisation: the minimum-phase factor `D_u` of the two-sided `S_uu`
//! (Wilson) and the causal multichannel Wiener filter `W0 = [S_xu D_u^-H]_+ D_u^-1` (Lambda = 0).
//! Only the causal estimate ([`Estimate::CausalWiener`]) goes through it, so the session computes
//! it only when that estimate is asked for ([`Factorisation::causal_for`]); the default `H1` fit
//! needs neither its cost (most of the factorisation stage's) nor its refusals.
//!
//! Three numerical choices make it exact on sampled, estimated spectra (besides the zero-padded
//! spectra, `spectra::ZERO_PAD`, whose correlation then fits the grid, so the minimum-phase factor
//! is an exact causal FIR, free of wrap-around); each was found necessary on simulated stand runs
//! (issue 3's and issue 13's notes) and is tested:
//! 1. **Uniform loading** `S_uu + eps I` with `eps = loading * max_f tr S_uu / 3`, added on the
//!    two-sided grid (lag 0 only, so the factor stays FIR), with `S_xu` loaded consistently by
//!    `eps H1`. A bin-selective eigenvalue floor would make the factor infinitely long, and an
//!    unloaded `S_xu` would leave `-eps W D^-H`, which `D^-1` amplifies in weakly excited input
//!    directions (the accelerometer's x and y specific forces are collinear at high frequency).
//! 2. **A fixed-lag allowance** of `lag_allowance` samples in the projection,
//!    `[G e^(-j w g)]_+ e^(+j w g)`: a delay that is not a whole number of samples is causal in
//!    continuous time but, sampled and band-limited, its interpolation kernel has a tail at negative
//!    lags; `g = 0` is the paper's strict `[.]_+` and cuts that tail, biasing K by up to ~0.7 % on the
//!    accelerometer. With `g = 64`, `tests/identify_accuracy.rs` finds K within
//!    0.1 % on simulated runs whose delays are not whole samples.
//! 3. **A grid fine enough for the input factor**: Wilson's iteration works through the factor's
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
//!    result had 8e-5 at negative lags); `D_u`, the projection and `W0` are computed there and
//!    `W0` is read back at the spectra's bins. Where even the finest grid does not hold it,
//!    [`CausalStage::input_factor_negative_lags`] says so and the warnings report it.
//!
//! Units and contracts are the factorisation stage's (`super::factorisation`): one-sided spectra
//! on the spectra's grid in, `W0` per one-sided bin out (output units per input unit); empty,
//! non-finite or odd-grid spectra are refused by this stage's own Wilson factorisation
//! ([`IdentError::Factor`]), never propagated.
//!
//! [`Estimate::CausalWiener`]: super::settings::Estimate::CausalWiener

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::FactorStageError::NonFiniteInput;
use super::IdentError;
use super::explained::InputEigen;
use super::factorisation::{
    Factorisation, FactorisationSettings, factor_error, input_floor, loaded_two_sided, max_trace,
};
use super::spectra::BlockSpectra;
use crate::spectral::causal::CausalProjector;
use crate::spectral::factor::{SpectralFactor, wilson_from};
use crate::spectral::grid::two_sided_from_one_sided;
use crate::spectral::refine::refined;

/// What the causal stage computed for one block's spectra.
#[derive(Clone, Debug)]
pub struct CausalStage {
    /// `W0 = [S_xu D_u^-H]_+ D_u^-1` per one-sided bin (causal Wiener-Kolmogorov, Lambda = 0),
    /// shared with the Wiener estimates made from it.
    pub causal_wiener: std::sync::Arc<Vec<Matrix3<Complex64>>>,
    /// `D_u` on the whole two-sided grid of the causal stage (the spectra's, refined
    /// `input_refinement` times): the start of a refactorisation.
    pub input_factor: Vec<Matrix3<Complex64>>,
    /// How many times finer than the spectra's the causal stage's grid is (module docs, item 3).
    pub input_refinement: usize,
    /// The fraction of `D_u`'s energy at negative lags on that grid (0 for an exactly causal
    /// factor; above the settings' tolerance only when the finest grid was not fine enough).
    pub input_factor_negative_lags: f64,
    /// Reconstruction error of `D_u D_u^H = S_uu + eps I` (relative, worst bin).
    pub input_factor_error: f64,
    /// Whether `D_u`'s iteration converged.
    pub input_factor_converged: bool,
    /// Whether `D_u` was computed from Wilson's standard start on the first grid, i.e. this is
    /// what [`causal_stage`] gives without a previous stage.
    pub from_scratch: bool,
}

/// The causal stage of `spectra`, Wilson's iterations started from `previous` (the causal stage
/// of the same block before a change of the Welch overlap) when its factor fits the grid; the
/// result is then provisional ([`CausalStage::from_scratch`] false, see
/// [`super::factorisation::factorise_from`]).
///
/// # Errors
/// [`IdentError::Factor`] when the input's factorisation is refused (empty or non-finite spectra,
/// a bin that is entirely zero, an odd grid) or its factor cannot be inverted.
pub fn causal_stage(
    spectra: &BlockSpectra,
    settings: &FactorisationSettings,
    previous: Option<&CausalStage>,
) -> Result<CausalStage, IdentError> {
    let floor = input_floor(&spectra.s_uu);
    let eps = settings.loading * max_trace(&spectra.s_uu) / 3.0;
    let (d_u, input_refinement, input_factor_negative_lags) = causal_input_factor(
        &spectra.s_uu,
        eps,
        settings,
        previous.map(|p| p.input_factor.as_slice()),
        previous.map_or(1, |p| p.input_refinement),
    )?;
    let d_u_inv = d_u.inverse().map_err(factor_error)?;

    // Consistent loading: (S_xu + eps H1) = H1 (S_uu + eps I) on every bin of the two-sided grid
    // (the refined grid's H1 from the refined spectra, so the identity holds there too).
    let two_sided = |one: &[Matrix3<Complex64>]| {
        refined(
            &two_sided_from_one_sided(one).map_err(factor_error)?,
            input_refinement,
        )
        .map_err(factor_error)
    };
    let (s_xu_two, s_uu_two) = (two_sided(&spectra.s_xu)?, two_sided(&spectra.s_uu)?);
    let mut g: Vec<Matrix3<Complex64>> = s_xu_two
        .iter()
        .zip(&s_uu_two)
        .zip(&d_u_inv)
        .enumerate()
        .map(|(bin, ((s, suu), di))| {
            let eig =
                InputEigen::new(suu, floor * 0.5).ok_or_else(|| factor_error(NonFiniteInput { bin }))?;
            let h = s * eig.inverse();
            Ok((s + h * Complex64::from(eps)) * di.adjoint())
        })
        .collect::<Result<_, IdentError>>()?;
    let mut projector = CausalProjector::new(g.len()).map_err(factor_error)?;
    // The refined grid has the same lag spacing (one sample), only more lags: the allowance in
    // samples is unchanged.
    let lag = settings.lag_allowance as f64;
    shift_lags(&mut g, lag);
    projector.causal_part(&mut g).map_err(factor_error)?;
    shift_lags(&mut g, -lag);
    let causal_wiener = std::sync::Arc::new(
        (0..spectra.frequency_hz.len())
            .map(|k| g[k * input_refinement] * d_u_inv[k * input_refinement])
            .collect(),
    );
    Ok(CausalStage {
        causal_wiener,
        input_refinement,
        input_factor_negative_lags,
        input_factor_error: d_u.reconstruction_error,
        input_factor_converged: d_u.converged,
        from_scratch: !d_u.from_start,
        input_factor: d_u.factor,
    })
}

impl Factorisation {
    /// This factorisation with `stage` as its causal stage, which must be of the same spectra
    /// (the session adds it only to the factorisation of the spectra it computed it from).
    #[must_use]
    pub fn with_causal_stage(&self, stage: CausalStage) -> Self {
        Self {
            causal: Some(std::sync::Arc::new(stage)),
            ..self.clone()
        }
    }
}

/// Wilson factor of the two-sided `S_uu + eps I` on the spectra's grid refined `min_refinement`,
/// twice that, ... times (from `start_refinement`, a previous factorisation's, when its factor
/// fits that grid; the result is then marked as started from it) until its
/// negative-lag energy is within the settings' tolerance or the finest grid is reached (module
/// docs, item 3). Returns the factor on its grid, the refinement and the negative-lag fraction.
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
