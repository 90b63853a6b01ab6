//! The whole identification of a run: observer -> block signals -> spectra -> factorisation ->
//! regularised Wiener (A, Lambda) -> structural fit (order), one block at a time. Each stage's
//! result is an `Arc` so that callers (the app's worker) can cache a stage and redo only what a
//! changed setting touches: [`identify_block_from`] starts from cached spectra and factorisation.
//!
//! Nothing here reads a sidecar's simulator answer key: everything comes from the measured angles and
//! outputs.

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::IdentError;
use super::excitation::check_excitation;
use super::factorisation::{Factorisation, FactorisationSettings, factorise};
use super::settings::{OrderSetting, Settings};
use super::signals::block_signals;
use super::spectra::{BlockSpectra, block_spectra};
use super::structural::{
    OrderChoice, ResponseEstimate, StructuralFit, StructuralSettings, Weights, fit_structure,
};
use super::warnings::{IdentWarning, block_warnings};
use super::wiener::{WienerEstimate, band_bins, regularised_wiener};
use crate::block::Block;
use crate::run::Run;
use crate::spectral::WelchPlanner;
use crate::stand::observer::{ObserverEstimate, ObserverSettings, observe};

/// One block's identification, stage by stage.
#[derive(Clone, Debug)]
pub struct BlockIdentification {
    /// Which block.
    pub block: Block,
    /// Spectra of `[u; x]`.
    pub spectra: Arc<BlockSpectra>,
    /// Factorisation stage.
    pub factorisation: Arc<Factorisation>,
    /// Regularised Wiener estimate (A, Lambda).
    pub wiener: Arc<WienerEstimate>,
    /// Indices of the analysis band's native (un-padded) Welch bins.
    pub band: Vec<usize>,
    /// Structural model (order).
    pub structural: Arc<StructuralFit>,
    /// What was regularised or is inexact (empty when all is well).
    pub warnings: Vec<IdentWarning>,
}

/// A whole run's identification.
#[derive(Clone, Debug)]
pub struct RunIdentification {
    /// The observer's estimate of the platform motion.
    pub motion: Arc<ObserverEstimate>,
    /// One entry per identified block, in the order of the settings.
    pub blocks: Vec<BlockIdentification>,
}

/// Identifies every block the settings name.
///
/// # Errors
/// Invalid settings for this run ([`IdentError::Settings`]), an observer failure, an input axis
/// not excited in the band ([`IdentError::NotExcited`]), or any stage's error for any block.
pub fn identify_run(run: &Run, settings: &Settings) -> Result<RunIdentification, IdentError> {
    let settings = &Settings {
        blocks: settings.blocks_for(&run.blocks()),
        ..settings.clone()
    };
    settings
        .validate(run.len(), run.sample_rate_hz, &run.blocks())
        .map_err(|e| IdentError::Settings(e.to_string()))?;
    let observer_settings = ObserverSettings {
        angle_noise_rad: run.sidecar.angle_noise_rad,
        ..ObserverSettings::default()
    };
    let motion = observe(
        run.angles.each_ref().map(Vec::as_slice),
        run.sample_rate_hz,
        &observer_settings,
    )
    .map_err(|e| IdentError::Observer(e.to_string()))?;
    let mut planner = WelchPlanner::new();
    let mut blocks = Vec::new();
    for &block in &settings.blocks {
        let signals =
            block_signals(run, &motion.euler, block).ok_or(IdentError::MissingBlock(block.name()))?;
        let spectra = Arc::new(
            block_spectra(&mut planner, &signals, run.sample_rate_hz, &settings.welch)
                .map_err(|e| IdentError::Spectra(e.to_string()))?,
        );
        check_excitation(&spectra, block, settings.band_hz)?;
        let factorisation = Arc::new(factorise(&spectra, &FactorisationSettings::default())?);
        blocks.push(identify_block_from(block, spectra, factorisation, settings)?);
    }
    Ok(RunIdentification {
        motion: Arc::new(motion),
        blocks,
    })
}

/// The cheap stages (Wiener with A and Lambda, structural fit) from cached spectra and
/// factorisation.
///
/// # Errors
/// An empty band, a singular A or auto-Lambda system, or a structural fit failure.
pub fn identify_block_from(
    block: Block,
    spectra: Arc<BlockSpectra>,
    factorisation: Arc<Factorisation>,
    settings: &Settings,
) -> Result<BlockIdentification, IdentError> {
    let wiener = Arc::new(regularised_wiener(
        &spectra,
        &factorisation,
        &settings.weight(),
        settings.lambda,
        settings.band_hz,
    )?);
    // The structural fit and the model use the native Welch bins: the zero-padded grid (needed
    // for the causal projection) interpolates between them, and its neighbours are not
    // independent, which would overstate the evidence by the padding factor.
    let step = (spectra.fft_len / spectra.segment_len.max(1)).max(1);
    let band: Vec<usize> = band_bins(&spectra.frequency_hz, settings.band_hz)
        .into_iter()
        .filter(|k| k % step == 0)
        .collect();
    let warnings = block_warnings(&spectra, &factorisation, &FactorisationSettings::default(), &band);
    let structural = Arc::new(structural_fit(
        &spectra,
        &factorisation,
        &wiener,
        &band,
        settings.order,
    )?);
    Ok(BlockIdentification {
        block,
        spectra,
        factorisation,
        wiener,
        band,
        structural,
        warnings,
    })
}

/// Fits the structural model to `W_u` over the band by generalised least squares: the estimate of
/// output row `i` has covariance `S_psi,ii S_uu^-1 / (n_eq - 3)`, so its weight is
/// `Omega_i = (n_eq - 3) S_uu / S_psi,ii`, which weighs collinear inputs correctly (the
/// accelerometer's x and y specific forces are nearly collinear at high frequency).
///
/// # Errors
/// [`IdentError::Structural`] when the fit refuses its input or fails numerically.
pub fn structural_fit(
    spectra: &BlockSpectra,
    factorisation: &Factorisation,
    wiener: &WienerEstimate,
    band: &[usize],
    order: OrderSetting,
) -> Result<StructuralFit, IdentError> {
    let frequency_hz: Vec<f64> = band.iter().map(|&k| spectra.frequency_hz[k]).collect();
    let response: Vec<Matrix3<Complex64>> = band.iter().map(|&k| wiener.w_u[k]).collect();
    let dof = (spectra.equivalent_averages - 3.0).max(1.0);
    let row_weight: Vec<[Matrix3<Complex64>; 3]> = band
        .iter()
        .map(|&k| {
            let s_uu = (spectra.s_uu[k] + spectra.s_uu[k].adjoint()) * Complex64::from(0.5);
            std::array::from_fn(|i| {
                let noise = factorisation.noise_psd[k][(i, i)].re.max(f64::MIN_POSITIVE);
                s_uu * Complex64::from(dof / noise)
            })
        })
        .collect();
    let choice = match order {
        OrderSetting::Fixed(n) => OrderChoice::Fixed(n),
        OrderSetting::Auto => OrderChoice::Auto,
    };
    let input = ResponseEstimate {
        frequency_hz: &frequency_hz,
        response: &response,
        weights: Weights::RowWeight(&row_weight),
    };
    fit_structure(&input, choice, &StructuralSettings::default())
        .map_err(|e| IdentError::Structural(e.to_string()))
}
