//! A run's identification and its blocks' last stages: observer -> block signals -> spectra ->
//! factorisation -> regularised Wiener (A, Lambda) -> structural fit (order). The stages are
//! orchestrated and cached once, by [`Session`]; [`identify_block_from`] is the cheap end of the
//! chain (band, excitation, Wiener, structural fit, stationarity, self-check) from cached spectra
//! and factorisation.
//!
//! Nothing here reads a sidecar's simulator answer key: everything comes from the measured angles and
//! outputs.

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::IdentError;
use super::band::{
    BandSetting, MIN_BAND_BINS, MIN_COHERENCE, auto_limits, best_coherence, native_bins, untrusted_ranges,
    usable_band,
};
use super::band_top::misfit_edge;
use super::delay_scatter::delay_scatter;
use super::even_gain::over_even_gain;
use super::excitation::check_excitation;
use super::factorisation::Factorisation;
use super::gain_curvature::EvenGain;
use super::holdout::{HeldOut, cached_held_out};
use super::left_out_noise::{gain_shift, widen_for_left_out_noise};
use super::selfcheck::{chi2_per_bin, self_check};
use super::session::{Session, Start};
use super::settings::{OrderSetting, Settings};
use super::signals::channel_names;
use super::spectra::BlockSpectra;
use super::stretches::{Stationarity, cached_stationarity, widen};
use super::structural::{
    OrderChoice, ResponseEstimate, StructuralFit, StructuralSettings, Weights, fit_structure, refit_structure,
};
use super::warnings::{IdentWarning, cached_block_warnings};
use super::wiener::{WienerEstimate, regularised_wiener};
use super::witness_noise::{bias_estimate, widen_for_witness_noise};
use crate::block::Block;
use crate::run::Run;
use crate::stand::observer::ObserverEstimate;

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
    /// The analysis band used, Hz: the usable band found from the data (`band_hz: "auto"`) or
    /// the user's.
    pub band_hz: [f64; 2],
    /// Indices of the analysis band's native (un-padded) Welch bins.
    pub band: Vec<usize>,
    /// Structural model (order).
    pub structural: Arc<StructuralFit>,
    /// The fit over the usable band the coherence found, when the band was ended below it at a
    /// misfit ([`super::band_top`]): where the next retune's first fit starts from.
    pub usable_band_fit: Option<Arc<StructuralFit>>,
    /// The fit to the estimate as measured, when `structural` was fitted over an even gain
    /// ([`super::even_gain`]): where the next retune's fit over the band starts from.
    pub first_fit: Option<Arc<StructuralFit>>,
    /// The stretches' fits (the stationarity check, on a shorter segment for a record too short
    /// for stretches at the settings' segment; `None` for a record too short even then).
    pub stationarity: Option<Arc<Stationarity>>,
    /// The first-order shift of `K` were all the angle noise the colour model left out taken as
    /// noise ([`super::left_out_noise::gain_shift`]), already in `structural`'s deviations;
    /// `None` without a left-out part (the model file's `fit.k_shift_left_out_angle_noise`).
    pub k_shift_left_out_angle_noise: Option<[[f64; 3]; 3]>,
    /// What was regularised or is inexact (empty when all is well).
    pub warnings: Vec<IdentWarning>,
}

/// The structural fits a retune of a block starts from ([`identify_block_from`]'s `previous`).
#[derive(Clone, Debug)]
pub struct FitStart {
    /// The block's fit to the estimate as measured: the fit reported, or the first fit when the
    /// reported one was fitted over an even gain.
    pub fit: Arc<StructuralFit>,
    /// Its fit over the usable band, when the band was ended below it at a misfit.
    pub usable_band: Option<Arc<StructuralFit>>,
    /// Its fit over an even gain, when that was the fit reported ([`super::even_gain`]).
    pub over_even_gain: Option<Arc<StructuralFit>>,
}

impl BlockIdentification {
    /// Where a retune of this block starts from.
    #[must_use]
    pub fn fit_start(&self) -> FitStart {
        FitStart {
            fit: self.first_fit.clone().unwrap_or_else(|| self.structural.clone()),
            usable_band: self.usable_band_fit.clone(),
            over_even_gain: self.first_fit.as_ref().map(|_| self.structural.clone()),
        }
    }
}

/// A whole run's identification.
#[derive(Clone, Debug)]
pub struct RunIdentification {
    /// The observer's estimate of the platform motion.
    pub motion: Arc<ObserverEstimate>,
    /// One entry per identified block, in the order of the settings.
    pub blocks: Vec<BlockIdentification>,
    /// The blocks the settings name that this run cannot identify, in the order of the
    /// settings: each with its refusal ([`IdentError::is_refusal`]). Only beside at least one
    /// identified block: a run whose every block is refused is an error.
    pub refused: Vec<Refusal>,
}

/// A block the run cannot identify, beside others it can ([`IdentError::is_refusal`]): an
/// accelerometer with no band where its outputs are coherent with the inputs, or with an input
/// axis not excited (its own error, `IdentError::NoUsableBand` or `IdentError::NotExcited`).
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    /// Which block.
    pub block: Block,
    /// Why.
    pub error: IdentError,
    /// Whether it was decided from scratch, not on a warm start (an accelerometer's weak axis is
    /// refused when the fit cannot determine its gains): else the identification is
    /// [`RunIdentification::provisional`].
    pub from_scratch: bool,
}

/// Where [`Session::identify`] is: the stage about to start, and how many of `total`
/// stages are done.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IdentStep {
    /// Stages done.
    pub done: usize,
    /// Stages in all: the observer, then spectra, factorisation and fit per block.
    pub total: usize,
    /// The stage about to start (`observer`, `spectra`, `factorisation`, `fit`), or `done`.
    pub stage: &'static str,
    /// Its block, if it is a block's stage.
    pub block: Option<Block>,
}

impl RunIdentification {
    /// Whether a block's factorisation or structural fit was started from an earlier one
    /// ([`Start::Warm`]): close to, but not exactly, what `imu-attest identify` gives.
    #[must_use]
    pub fn provisional(&self) -> bool {
        self.blocks.iter().any(|b| {
            !b.structural.fitted.from_scratch() || !b.factorisation.from_scratch_for(b.wiener.estimate)
        }) || self.refused.iter().any(|r| !r.from_scratch)
    }
}

/// Identifies every block the settings name, from scratch: a [`Session`] of a copy of `run`
/// (hold a session instead to keep the stages for another identification).
///
/// # Errors
/// Invalid settings for this run ([`IdentError::Settings`]), an observer failure, the gyro's
/// refusal ([`IdentError::NotExcited`], [`IdentError::NoUsableBand`]), every block refused, or
/// any other stage's error for any block. A block refused beside others is in
/// [`RunIdentification::refused`].
pub fn identify_run(run: &Run, settings: &Settings) -> Result<RunIdentification, IdentError> {
    let mut session = Session::new(Arc::new(run.clone()));
    let id = session.identify(settings, Start::Cold, &mut |_| {})?;
    drop(session);
    Ok(Arc::unwrap_or_clone(id))
}

/// The cheap stages (Wiener with A and Lambda, structural fit) from cached spectra and
/// factorisation. With `previous` (an earlier structural fit of this block, e.g. before a change
/// of A, Lambda, the order or the Welch settings), the structural fit starts from it
/// ([`refit_structure`]): an order change alone reuses its fits exactly, other changes refine
/// each order from it.
///
/// The band is resolved here ([`resolve_band`]) and the block's excitation over it checked
/// ([`check_excitation`]): every caller (the command line, the app, `bench`, the diagnosis) gets
/// the same refusals.
///
/// # Errors
/// No usable band, an input axis too weakly excited for the fit to determine its gains, an empty
/// band, a singular A or auto-Lambda system, or a structural fit failure.
pub fn identify_block_from(
    block: Block,
    spectra: Arc<BlockSpectra>,
    factorisation: Arc<Factorisation>,
    settings: &Settings,
    previous: Option<&FitStart>,
) -> Result<BlockIdentification, IdentError> {
    // Excitation first, over the band asked for (or the auto search limits): a stand axis held
    // still is named as such, not as a band without coherence. A weak direction is refused only
    // when the fit cannot determine its gains ([`excitation::UNDETERMINED`]): a weaker axis
    // whose gains the data still give to a tenth is identified (its sigmas say how well).
    let weak = check_excitation(
        &spectra,
        block,
        settings.band_hz.search_limits(spectra.sample_rate_hz),
    )
    .err();
    let identified = identify_excited(block, spectra, factorisation, settings, previous);
    match (identified, weak) {
        (Ok(id), Some(refusal)) if !determined(&id.structural, block, &refusal) => Err(refusal),
        (Ok(id), _) => Ok(id),
        (Err(e), weak) => Err(weak.unwrap_or(e)),
    }
}

/// Whether `fit` determines the gains of the input axis `refusal` names: its direction holds at
/// least [`excitation::HELD_STILL`] of the strongest's power, and no element of `K` has a
/// standard deviation above [`excitation::UNDETERMINED`] times the largest gain (a NaN is
/// undetermined).
fn determined(fit: &StructuralFit, block: Block, refusal: &IdentError) -> bool {
    let IdentError::NotExcited {
        axis, relative_power, ..
    } = refusal
    else {
        return true;
    };
    if !channel_names(block).0.contains(axis) || *relative_power < super::excitation::HELD_STILL {
        return false;
    }
    let scale = fit.k.iter().flatten().fold(0.0, |m: f64, v| m.max(v.abs()));
    fit.k_std
        .iter()
        .flatten()
        .all(|s| *s <= super::excitation::UNDETERMINED * scale)
}

/// [`identify_block_from`] past the first excitation check.
fn identify_excited(
    block: Block,
    spectra: Arc<BlockSpectra>,
    factorisation: Arc<Factorisation>,
    settings: &Settings,
    previous: Option<&FitStart>,
) -> Result<BlockIdentification, IdentError> {
    let found = resolve_band(&spectra, block, settings.band_hz)?;
    let weak = check_excitation(&spectra, block, found).err();
    let fit_over = |band_hz: [f64; 2], previous: Option<&StructuralFit>| -> Result<_, IdentError> {
        let wiener = Arc::new(regularised_wiener(
            &spectra,
            &factorisation,
            settings.estimate,
            &settings.weight(),
            settings.lambda,
            band_hz,
        )?);
        let band = native_bins(&spectra, band_hz);
        let held_out = cached_held_out(&spectra, band_hz);
        let structural = structural_fit(
            &spectra,
            &factorisation,
            &wiener,
            &band,
            settings.order.of(block),
            held_out.as_deref(),
            previous,
            None,
        )?;
        Ok((band_hz, wiener, band, Arc::new(structural)))
    };
    // Each fit starts from the previous fit over the same band, where there is one: the usable
    // band's (kept when the band was ended at a misfit) for the first, the reported one for the
    // refit over the ended band.
    let previous_fit = previous.map(|p| &*p.fit);
    let first_start = previous.map(|p| p.usable_band.as_deref().unwrap_or(&p.fit));
    let mut fitted = fit_over(found, first_start)?;
    let mut trimmed = None;
    let mut usable_band_fit = None;
    if settings.band_hz == BandSetting::Auto {
        let (_, wiener, band, structural) = &fitted;
        let chi2 = chi2_per_bin(&spectra, &factorisation.noise_psd, wiener, band, structural);
        if let Some(edge) = misfit_edge(&chi2, spectra.bin_correlation) {
            let top = spectra.frequency_hz[band[edge.index - 1]];
            let first_from_scratch = structural.fitted.from_scratch();
            // From the caller's start, not refined from the fit just made: a refinement lands
            // near, not on, the cold fit's optimum, and the command line gives the cold answer.
            // A trimmed band the data cannot be fitted on (too few bins for the order asked, an
            // axis not excited there) keeps the first fit: the trim is an improvement, never a
            // new refusal.
            let refit = fit_over([found[0], top], previous_fit).and_then(|refit| {
                match check_excitation(&spectra, block, [found[0], top]) {
                    Err(refusal) if !determined(&refit.3, block, &refusal) => Err(refusal),
                    _ => Ok(refit),
                }
            });
            if let Ok(mut refit) = refit {
                // The cut was chosen from a refined, not a cold, fit: the result is provisional
                // even when the refit reused its models exactly.
                if !first_from_scratch && refit.3.fitted.from_scratch() {
                    let mut s = (*refit.3).clone();
                    s.fitted.mark_refined();
                    refit.3 = Arc::new(s);
                }
                trimmed = Some(IdentWarning::BandTopMisfit {
                    band_hz: [spectra.frequency_hz[band[edge.index]], found[1]],
                    level_ratio: edge.level_above / edge.level_below.max(f64::MIN_POSITIVE),
                    chi2_per_bin_above: edge.level_above,
                });
                usable_band_fit = Some(structural.clone());
                fitted = refit;
            }
        }
    }
    let (band_hz, wiener, band, structural) = fitted;
    let mut warnings = cached_block_warnings(&spectra, &factorisation, band_hz, settings.estimate);
    warnings.extend(trimmed);
    let stationarity = cached_stationarity(&spectra, band_hz);
    // The gyro's own noise in the angle-noise model: its gains' deviations carry the bias that
    // leaves, before the self-check judges their precision.
    let witness = spectra
        .gyro_witnessed
        .then(|| bias_estimate(&spectra, &factorisation.coherence, &band));
    let widened = |fit: &StructuralFit| -> (StructuralFit, Option<IdentWarning>) {
        let mut w = fit.clone();
        if let Some(st) = stationarity.as_deref() {
            widen(&mut w, st);
        }
        let said = witness.and_then(|e| widen_for_witness_noise(&mut w, e));
        (w, said)
    };
    let (first, said) = widened(&structural);
    warnings.extend(said);
    let held_out = cached_held_out(&spectra, band_hz);
    let over = over_even_gain(
        block,
        &spectra,
        &factorisation,
        &wiener,
        &band,
        Arc::new(first),
        settings.order.of(block),
        held_out.as_deref(),
        previous.and_then(|p| p.over_even_gain.as_deref()),
        &|f| widened(f).0,
    )?;
    // The angle noise the colour model left out (`left_out_noise`): a shift common to the gain
    // across the band, so after the even gain is judged (with it in the deviations, a gain that
    // changes across the band was no longer seen to: on 30-minute real-stand runs the
    // accelerometer's `K` then read worse), and before the self-check judges the precision.
    let k_shift_left_out_angle_noise = spectra
        .left_out_noise
        .as_deref()
        .map(|left_out| gain_shift(&spectra, &factorisation.coherence, &band, &over.fit.k, left_out));
    let structural = match &k_shift_left_out_angle_noise {
        Some(shift) => {
            let mut w = (*over.fit).clone();
            widen_for_left_out_noise(&mut w, shift);
            Arc::new(w)
        }
        None => over.fit,
    };
    if let Some(st) = stationarity.as_deref().filter(|st| st.drifts()) {
        let duration = st.stretches.last().map_or(0.0, |l| l.span_s[1]) - st.stretches[0].span_s[0];
        let (trend, trend_std) = st.drift();
        warnings.push(IdentWarning::DelayDrift {
            trend,
            trend_std,
            change_s: trend * duration,
        });
    }
    if let Some(step) = stationarity.as_deref().and_then(|st| st.delay_step) {
        warnings.push(step.warning());
    }
    warnings.extend(stationarity.as_deref().and_then(delay_scatter));
    if let Some(st) = stationarity.as_deref().filter(|st| !st.no_delay_s.is_empty()) {
        warnings.push(IdentWarning::StretchesWithoutDelay {
            spans_s: st.no_delay_s.clone(),
            fitted: st.stretches.len(),
        });
    }
    if let BandSetting::Fixed(given) = settings.band_hz {
        let ranges = untrusted_ranges(&spectra, given);
        if !ranges.is_empty() {
            warnings.push(IdentWarning::UntrustedBand { ranges_hz: ranges });
        }
    }
    warnings.extend(self_check(
        block,
        &spectra,
        &factorisation.noise_psd,
        &wiener,
        &band,
        &structural,
        settings,
    ));
    warnings.extend(over.warning);
    if let Some(refusal) = weak.filter(|r| !determined(&structural, block, r)) {
        return Err(refusal);
    }
    Ok(BlockIdentification {
        block,
        spectra,
        factorisation,
        wiener,
        band_hz,
        band,
        structural,
        usable_band_fit,
        first_fit: over.first,
        stationarity,
        k_shift_left_out_angle_noise,
        warnings,
    })
}

/// The band to fit: the usable band inside the auto limits, or the user's band as given.
///
/// # Errors
/// [`IdentError::NoUsableBand`] when `band` is auto and no stretch is usable.
pub fn resolve_band(spectra: &BlockSpectra, block: Block, band: BandSetting) -> Result<[f64; 2], IdentError> {
    match band {
        BandSetting::Fixed(given) => Ok(given),
        BandSetting::Auto => {
            let limits = auto_limits(spectra.sample_rate_hz);
            let found = spectra
                .usable_band_cache
                .get_or(limits, || usable_band(spectra, limits));
            found.map(|band| *band).ok_or_else(|| IdentError::NoUsableBand {
                block: block.name(),
                low_hz: limits[0],
                high_hz: limits[1],
                best_coherence: best_coherence(spectra, limits),
                min: MIN_COHERENCE,
                bins: MIN_BAND_BINS,
                others: true,
                coherent_s: super::coherent_spans::coherent_spans(spectra, limits).unwrap_or_default(),
            })
        }
    }
}

/// The generalised least-squares weights of the three output rows of an `H1`-type estimate at one
/// bin: `Omega_i = dof S_uu / S_psi,ii` (`S_uu` made Hermitian; `noise` is `S_psi`), the inverse
/// covariance of row `i`. The structural fit (which narrows them where the estimate scatters
/// less, `structural::scatter`), the self-check's per-bin chi2 and the stretches' fits all start
/// from this.
#[must_use]
pub fn row_weights(
    s_uu: &Matrix3<Complex64>,
    noise: &Matrix3<Complex64>,
    dof: f64,
) -> [Matrix3<Complex64>; 3] {
    let s_uu = (s_uu + s_uu.adjoint()) * Complex64::from(0.5);
    std::array::from_fn(|i| s_uu * Complex64::from(dof / noise[(i, i)].re.max(f64::MIN_POSITIVE)))
}

/// Fits the structural model to `W_u` over the band by generalised least squares: the estimate of
/// output row `i` has covariance `S_psi,ii S_uu^-1 / (n_eq - 3)`, so its weight is
/// `Omega_i = (n_eq - 3) S_uu / S_psi,ii`, which weighs collinear inputs correctly (the
/// accelerometer's x and y specific forces are nearly collinear at high frequency). The fit
/// raises these weights where the estimate scatters less than they say (`structural::scatter`:
/// part of `S_psi` is the system's slope across the bin, which does not scatter `H1`).
///
/// With `held_out` (the halves' figures, [`cached_held_out`]), `auto` admits an order above 0 only
/// when it predicts held-out data better than every lower order (admissibility rule 7). With
/// `previous`, the fit starts from it ([`refit_structure`]). With `even` (an even gain of the
/// block's gain across the band, [`super::even_gain`]), the fit is to `W_u / g` (each row's
/// weight times `g^2`, the estimate's covariance over `g^2`): every order's `N(0)` is then the
/// gain at low frequency; the fit returned carries no even gain itself.
///
/// # Errors
/// [`IdentError::Structural`] when the fit refuses its input or fails numerically.
#[expect(
    clippy::too_many_arguments,
    reason = "the fit's stages, each its own cached input"
)]
pub fn structural_fit(
    spectra: &BlockSpectra,
    factorisation: &Factorisation,
    wiener: &WienerEstimate,
    band: &[usize],
    order: OrderSetting,
    held_out: Option<&HeldOut>,
    previous: Option<&StructuralFit>,
    even: Option<&EvenGain>,
) -> Result<StructuralFit, IdentError> {
    let frequency_hz: Vec<f64> = band
        .iter()
        .map(|&k| spectra.model_frequency_hz(k, wiener.estimate))
        .collect();
    // g where the model is compared with the estimate (the input's centroid for H1).
    let g: Vec<f64> = frequency_hz
        .iter()
        .map(|&f| even.map_or(1.0, |e| e.at(f)))
        .collect();
    let response: Vec<Matrix3<Complex64>> = band
        .iter()
        .zip(&g)
        .map(|(&k, g)| wiener.w_u(k) / Complex64::from(*g))
        .collect();
    let dof = (spectra.equivalent_averages - 3.0).max(1.0);
    let row_weight: Vec<[Matrix3<Complex64>; 3]> = band
        .iter()
        .zip(&g)
        .map(|(&k, g)| {
            row_weights(&spectra.s_uu[k], &factorisation.noise_psd[k], dof)
                .map(|w| w * Complex64::from(g * g))
        })
        .collect();
    let choice = match order {
        OrderSetting::Fixed(n) => OrderChoice::Fixed(n),
        OrderSetting::Auto => OrderChoice::Auto,
    };
    let offsets = spectra.fit_offsets_hz(band, wiener.estimate);
    let input = ResponseEstimate {
        frequency_hz: &frequency_hz,
        response: &response,
        weights: Weights::RowWeight(&row_weight),
        offset_hz: offsets.as_deref(),
    };
    let settings = StructuralSettings {
        bin_correlation: spectra.bin_correlation,
        held_out_chi2: held_out.map(|h| h.chi2),
        aligned_s: spectra.aligned_s(),
        ..StructuralSettings::default()
    };
    match previous {
        Some(previous) => refit_structure(&input, choice, &settings, previous),
        None => fit_structure(&input, choice, &settings),
    }
    .map_err(IdentError::from)
}
