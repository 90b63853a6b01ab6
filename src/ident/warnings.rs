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
//! error), so a reader can judge it; `Display` is one plain sentence. The factorisation's are found
//! by [`super::factorisation_warnings`] (re-exported here).

use std::fmt;

use serde::{Deserialize, Serialize};

pub use super::factorisation_warnings::{block_warnings, cached_block_warnings, near_singular_bins};
use super::odd_gain::OddOutput;
use super::warning_words::{
    angle_noise_colour_unknown_words, angle_noise_overstated_words, delay_absorbed_words,
    delay_outside_words, delay_step_words, gain_change_words, gain_depends_on_amplitude_words,
    poles_or_even_gain_words, witness_noise_bias_words, witness_noise_shared_words,
    write_stretches_without_delay, zeros_lag_words, zeros_lead_words,
};

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

/// The gain loss through the Welch windows' overlap (`delay_outside_usual_range`) above which
/// the warning names it: a tenth of a percent, a certification's usual scale-factor tolerance.
pub const OVERLAP_LOSS_SAID: f64 = 1e-3;

/// How many times the bound the gyro puts on the angles' noise a declared `angle_noise_rad` may
/// be before `angle_noise_overstated` is said: twice (four times in power), since the bound is an
/// upper one (it holds the gyro's own noise too) and a median over the band.
pub const ANGLE_NOISE_OVERSTATED: f64 = 2.0;

/// The element of `K` a change moves furthest against its own deviation
/// (`gain_changes_across_band`): its output and input channels and the change in its deviations.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ElementChange {
    /// The output channel (`K`'s row).
    pub output: String,
    /// The input channel (`K`'s column).
    pub input: String,
    /// The change over the element's standard deviation, unsigned.
    pub sigmas: f64,
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
        /// Relative reconstruction error of its spectral factor (`None` for the input when the
        /// fit does not go through the input's factor, which is then not computed: absent from
        /// the file).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        factor_error: Option<f64>,
    },
    /// Stretches of a user's band where the input estimate cannot be trusted (multiple coherence
    /// below [`super::band::MIN_COHERENCE`]).
    UntrustedBand {
        /// `[low, high]` stretches, Hz.
        ranges_hz: Vec<[f64; 2]>,
    },
    /// The auto band was ended below the usable band's top: over the stretch left out the chosen
    /// model's chi2 per bin is far above the band's below it, while the outputs stay coherent with
    /// the inputs ([`super::band_top`]).
    BandTopMisfit {
        /// The stretch left out, Hz.
        band_hz: [f64; 2],
        /// Its mean chi2 per bin over the band's below it.
        level_ratio: f64,
        /// Its mean chi2 per bin over the expectation (18).
        chi2_per_bin_above: f64,
    },
    /// The measured gain changes across the band with no phase of its own, beyond its deviation,
    /// and enough to move `K` (the band's mean gain) by more than `K`'s own deviation from the
    /// gain at low frequency ([`super::gain_curvature`]: a reference interpolated from a slower
    /// rate, or smoothed). The block is then fitted again over the even gain and, where that fit is
    /// delay-only, `K` is given at low frequency and the model carries the even gain
    /// (`k_at_low_frequency`, `super::even_gain`); otherwise `K` is left as fitted.
    GainChangesAcrossBand {
        /// The gain's change from the band's bottom to its top, relative.
        rise: f64,
        /// Its standard deviation (widened), relative.
        rise_std: f64,
        /// How far each row of `K` (per output, in `outputs`' order) reads above the gain at low
        /// frequency, relative (its scale; negative: below).
        k_bias: [f64; 3],
        /// The block's outputs (`K`'s rows).
        outputs: [String; 3],
        /// `K`'s own relative deviation, `||K_std||_F / ||K||_F`.
        k_relative_std: f64,
        /// Whether a row of `K` moved by more than `k_relative_std` as the change was read (the
        /// curvature's first-order row bias, before a fit over the even gain applied its own,
        /// `k_bias`); `false` where only one element moved beyond its own deviation, and in
        /// model files written before it was carried (read from fresh identifications only:
        /// `crate::diagnose::input_limit::falling_gain`).
        #[serde(default)]
        rows_moved: bool,
        /// The element of `K` the change moves furthest against its own deviation (absent in
        /// model files written before it was said).
        #[serde(default)]
        largest_change: ElementChange,
        /// The band, Hz.
        band_hz: [f64; 2],
        /// Whether the model's `K` is the gain at low frequency (the block fitted again over the
        /// even gain, which the model's response carries); `false`: `K` as fitted.
        #[serde(default)]
        k_at_low_frequency: bool,
    },
    /// The model does not explain the data to the stated noise: uncertainties widened.
    PoorFit {
        /// chi2 per degree of freedom of the chosen model.
        chi2_per_dof: f64,
        /// The octave band of the largest misfit, Hz.
        worst_band_hz: [f64; 2],
        /// chi2 per degree of freedom there.
        worst_chi2_per_dof: f64,
    },
    /// The model extended with accepted effects (`identify --effects`, Accept in the app) still
    /// does not explain the data to the stated noise (the rule of [`Self::PoorFit`] on the joint
    /// fit's own chi2/dof, which replaces the identified model's poor fit): uncertainties widened.
    PoorFitWithEffects {
        /// chi2 per degree of freedom of the joint fit with the effects.
        chi2_per_dof: f64,
        /// The same fit's without them, over the same band and record.
        without_effects: f64,
    },
    /// A gain element far from a calibrated block's (diagonal near 1, cross-couplings small).
    ImplausibleGain {
        /// Output channel name.
        output: String,
        /// Input axis name.
        input: String,
        /// `K[output][input]`.
        value: f64,
    },
    /// A gain element whose standard deviation exceeds [`super::selfcheck::IMPRECISE_GAIN`]: the
    /// run does not determine the block's gain to a percent (too weak a motion for the noise).
    ImpreciseGain {
        /// Output channel name.
        output: String,
        /// Input axis name.
        input: String,
        /// `K[output][input]`.
        value: f64,
        /// Its standard deviation.
        std: f64,
    },
    /// The gyro's residual noise is not small beside the motion, and the observer's coloured
    /// angle-noise model cannot tell the gyro's own noise from the stand's: as far as it is the
    /// gyro's, the gains read high, by about `estimate` at first order, which their standard
    /// deviations now include ([`super::witness_noise`]).
    WitnessNoiseBias {
        /// The largest estimate of the bias, relative (0.01 is 1 %).
        estimate: f64,
        /// The input axis it is for (0, 1, 2: `wx`, `wy`, `wz`).
        axis: usize,
        /// Every input axis's estimate, relative.
        estimates: [f64; 3],
    },
    /// Said on every other block beside a gyro that says [`Self::WitnessNoiseBias`]: their
    /// inputs come from the same observer, whose angle-noise model took part of the gyro's own
    /// noise for the stand's, so they were shrunk too and the gains are biased by an amount not in
    /// their deviations ([`super::witness_noise`]).
    WitnessNoiseShared {
        /// The gyro's largest estimate of its own gains' bias, relative.
        gyro_estimate: f64,
    },
    /// A delay that is negative beyond its uncertainty: the block answers before the stand moves.
    NegativeDelay {
        /// The delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
    },
    /// The delay (the model's, or else the delay-only candidate's) lies outside the range a
    /// sensor's own delay is searched in first, and was found by the wider search
    /// (`structural::gain_delay`): most likely the angles and the outputs are stamped by clocks
    /// offset from each other, which the model holds as the block's delay. At the wider search's
    /// end the true delay may lie beyond it.
    DelayOutsideUsualRange {
        /// The delay, s.
        tau_s: f64,
        /// The range searched first, s.
        usual_s: [f64; 2],
        /// How far from zero the wider search reaches, s.
        reach_s: f64,
        /// How much the delay lowers the measured gain through the Welch windows' smaller
        /// overlap (`1 - r(tau)`, `r` the window's normalised autocorrelation at the delay),
        /// relative.
        overlap_loss: f64,
        /// Whether the delay-only candidate's delay is outside the range too (found by the wider
        /// search); `false`: the chosen model's poles moved its delay out by themselves.
        #[serde(default)]
        wider_search: bool,
        /// How far the outputs were moved before the Welch estimate (`super::alignment`), s: the
        /// estimate smears only the rest of the delay. 0: not moved.
        #[serde(default)]
        aligned_s: f64,
        /// The chosen model's own delay where it lies inside the range and `tau_s` is the
        /// delay-only candidate's (its poles brought it back inside), s; `None`: `tau_s` is the
        /// model's.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        model_tau_s: Option<f64>,
    },
    /// The chosen model has poles and a negative delay where the delay-only model (order 0) has a
    /// positive one: its poles' lag stands in for the delay, the delay is the remainder. Such a
    /// model is the block's only when the stand's angles lag it; otherwise it describes the
    /// reference with the block (a band-limited reference's gain rise is fitted this way).
    DelayAbsorbedByPoles {
        /// The chosen order.
        order: usize,
        /// Its delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
        /// The delay of the order-0 candidate, s.
        delay_only_tau_s: f64,
    },
    /// The block's gain changes across the band with no phase of its own
    /// (`gain_changes_across_band` on the delay-only model's residual) and the chosen model takes
    /// the change as dynamics: its poles explain the estimate better, on the information
    /// criterion, than the delay-only model over an even gain (`super::even_gain`), so they are
    /// kept, and their lag at low frequency trades with the delay. A band-limited reference
    /// bends the gain the same way; where the block has no filter of its own the delay-only
    /// model's delay is the block's, and the chosen model's is not.
    PolesOrEvenGain {
        /// The chosen order.
        order: usize,
        /// Its delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
        /// The delay of the delay-only model over the even gain, s.
        even_tau_s: f64,
        /// Its standard deviation, s.
        even_tau_std_s: f64,
        /// The gain's change from the band's bottom to its top, relative.
        rise: f64,
        /// The band, Hz.
        band_hz: [f64; 2],
        /// How much lower the chosen model's information criterion is than the delay-only model's
        /// over the even gain (the even gain's coefficients counted), in the criterion's units.
        margin: f64,
    },
    /// The chosen model's zeros lead at low frequency, beyond three of their deviations' bound: a
    /// sensor's filters do not lead, an angle measurement that lags the motion (filtered or
    /// band-limited angle sensors) makes the block seem to. The model is then the block relative
    /// to those angles; its delay and poles alone are the block's only if the zeros are the
    /// angles' lag inverted.
    ZerosLead {
        /// The chosen order.
        order: usize,
        /// The zeros' lead at low frequency (a third of the trace of `N_0^-1 N_1`), s.
        lead_s: f64,
        /// The bound on its standard deviation, s.
        lead_std_s: f64,
        /// The model's delay, s.
        tau_s: f64,
        /// The poles' lag at low frequency (`d_1`), s.
        pole_lag_s: f64,
    },
    /// The chosen model's zeros lag at low frequency, beyond three of their deviations' bound:
    /// over the band a lagging first-order numerator acts as a delay, so the delay and the zeros
    /// share the block's low-frequency delay, and the delay's own deviation does not cover how
    /// they split it (most sensors' filters have no zeros: simulated 15-25 Hz filters gave
    /// delays 0.4-0.9 ms short, 5-20 of their deviations, the zeros lagging by as much).
    ZerosLag {
        /// The chosen order.
        order: usize,
        /// The zeros' lag at low frequency (minus a third of the trace of `N_0^-1 N_1`), s.
        lag_s: f64,
        /// The bound on its standard deviation, s.
        lag_std_s: f64,
        /// The model's delay, s.
        tau_s: f64,
        /// Its standard deviation, s.
        tau_std_s: f64,
        /// The poles' lag at low frequency (`d_1`), s.
        pole_lag_s: f64,
    },
    /// The delay drifts through the record (the stretches' delays have a significant trend): the
    /// block and the stand may log on separate clocks.
    DelayDrift {
        /// Slope of the delay against time, s per s (1e-6 = 1 ppm).
        trend: f64,
        /// Its standard deviation.
        trend_std: f64,
        /// Change of the delay over the record, s.
        change_s: f64,
    },
    /// The delay steps between two stretches of the record, each steady ([`super::delay_step`]):
    /// the two streams slipped against each other (samples lost or repeated in one), and one
    /// delay describes neither side.
    DelayStep {
        /// The delay before the step, s.
        before_s: f64,
        /// The delay after it, s.
        after_s: f64,
        /// Where it lies, s from the first sample analysed.
        between_s: [f64; 2],
        /// The step in sample periods.
        samples: f64,
        /// Its standard deviation, sample periods.
        #[serde(default)]
        samples_std: f64,
        /// Whether a drift beside the step was fitted (enough stretches); without, a drift
        /// would show as a step of a fraction of a sample.
        #[serde(default)]
        drift_fitted: bool,
        /// Where the delay comes back to `before_s`, when it does (a slip and its reverse), s
        /// from the first sample analysed.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        back_between_s: Option<[f64; 2]>,
    },
    /// The stretches' delays disagree beyond their own deviations in a way neither a drift nor
    /// a step describes ([`super::delay_scatter`]): the delay's deviation is their spread.
    DelayScatter {
        /// The stretches tested.
        stretches: usize,
        /// The smallest stretch delay, s.
        min_s: f64,
        /// The largest, s.
        max_s: f64,
        /// The median of the stretches' own deviations, s.
        own_std_s: f64,
        /// Their scatter about the weighted mean, chi2 per degree of freedom.
        chi2_per_dof: f64,
        /// The record's delay deviation their spread implies, s.
        spread_std_s: f64,
    },
    /// Stretches of the record for which no delay was found inside the stationarity check's scan
    /// nor inside the record's own range (`super::stretches`): there the block's response is not
    /// the record's. They are left out of the check, which rests on the others.
    StretchesWithoutDelay {
        /// Their spans, s from the first sample.
        spans_s: Vec<[f64; 2]>,
        /// The stretches the check rests on.
        fitted: usize,
    },
    /// The fixed order asked for breaks an admissibility rule.
    InadmissibleOrder {
        /// The order.
        order: usize,
        /// Why.
        reason: crate::ident::structural::admissible::Rejection,
    },
    /// A spectral factor is inexact or did not converge.
    FactorInexact {
        /// Which spectrum.
        spectrum: Spectrum,
        /// Relative reconstruction error (worst bin).
        factor_error: f64,
        /// Whether this factor's iteration converged.
        converged: bool,
    },
    /// The run has no sound gyro (no gyro block, or one with a channel that never moves, holds
    /// samples or clips: `ident::session`), so nothing in it measures the motion a second way
    /// and the angle noise's colour cannot be estimated (`stand::colour`): the observer takes it as white
    /// at the level below. A stand whose angle noise is coloured inside the motion's band (an
    /// optical reference, an encoder's interpolation error) then passes it into this block's
    /// inputs as motion: gains biased low where the motion is weak, and a gain falling with
    /// frequency that an order above 0 "explains" with poles standing in for the delay.
    AngleNoiseColourUnknown {
        /// The white level assumed per angle (roll, yaw, pitch): its standard deviation, rad.
        angle_noise_rad: [f64; 3],
        /// Whether the level is the sidecar's (`true`) or estimated from the angles.
        declared: bool,
    },
    /// The sidecar's `angle_noise_rad` is more than [`ANGLE_NOISE_OVERSTATED`] times what the gyro
    /// leaves unexplained in the angles (`stand::colour`: that part holds the angles' noise and
    /// more, so it bounds it from above) on some axis. The declared value is the floor of the
    /// angle-noise model: overstated, the observer smooths away motion it takes for noise, and
    /// the gains are biased where the motion is weak.
    AngleNoiseOverstated {
        /// The declared standard deviation, rad.
        declared_rad: f64,
        /// The bound per angle (roll, yaw, pitch), white-equivalent standard deviation, rad.
        bound_rad: [f64; 3],
    },
    /// The record holds fewer Welch segments or equivalent averages than a segment left to the
    /// program must leave it ([`super::settings::AUTO_MIN_SEGMENTS`],
    /// [`super::settings::AUTO_MIN_EQUIVALENT_AVERAGES`]): the fit's weights rest on few averages,
    /// and the order choice may not be checkable on held-out data.
    FewSegments {
        /// Segments of the record (or span).
        segments: usize,
        /// Their equivalent number of averages.
        equivalent_averages: f64,
        /// The segment length, samples.
        segment_len: usize,
        /// Whether the segment was the program's (then already its shortest).
        segment_auto: bool,
    },
    /// The input's spectral factor keeps energy at negative lags even on the causal stage's
    /// finest grid: the causal projection then cuts part of the gain (mostly at the lowest
    /// frequencies), so `W_u` and everything fitted to it may be off there.
    FactorNotCausal {
        /// Fraction of the factor's energy at negative lags.
        negative_lags: f64,
        /// How many times finer than the spectra's the grid was.
        refinement: usize,
    },
    /// Outputs holding a part odd-quadratic in their own input (`k2 u |u|`) that moves `K`'s
    /// diagonal beyond its deviation: `K` is the gain at this run's motion amplitude
    /// ([`super::odd_gain`]).
    GainDependsOnAmplitude {
        /// The outputs concerned, with `k2` and the gain it adds.
        outputs: Vec<OddOutput>,
        /// The band tested (the model's), Hz.
        band_hz: [f64; 2],
    },
    /// The outputs hold a catalogue effect that the paper's model takes into `K` and the delay
    /// without a misfit the self-check sees (`crate::diagnose::suspect`: a gyro's g-sensitivity,
    /// an accelerometer's lever-arm error, channel delays, a quadratic scale factor): fitted
    /// beside `K e^(-tau s)` over the model's band it removes more `chi2` than BIC's cost of its
    /// parameters plus the diagnosis's look-elsewhere cost, closes part of the gap between model
    /// and outputs and opens it nowhere, and the delay or `K` moves beyond its deviation.
    EffectSuspected(super::suspicion::Suspicion),
    /// An implausible `K` that reads as a unit slip or axes swapped or reversed: a scale times
    /// a signed permutation of the identity ([`super::gain_pattern`]), said beside
    /// [`Self::ImplausibleGain`].
    GainPattern(super::gain_pattern::GainPattern),
}

impl fmt::Display for IdentWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IdentWarning::Regularised {
                spectrum,
                bins,
                band_bins,
                factor_error,
            } => {
                write!(
                    f,
                    "{} near-singular in {bins} of {band_bins} band bins: regularised",
                    spectrum.name()
                )?;
                match factor_error {
                    Some(e) => write!(f, " (factor reconstruction error {e:.1e})"),
                    None => Ok(()),
                }
            }
            IdentWarning::UntrustedBand { ranges_hz } => {
                write!(f, "the input estimate cannot be trusted in ")?;
                for (i, [lo, hi]) in ranges_hz.iter().enumerate() {
                    let sep = if i == 0 { "" } else { ", " };
                    write!(f, "{sep}{lo:.2}-{hi:.2} Hz")?;
                }
                write!(
                    f,
                    " of the given band (outputs not coherent with the inputs from the angles): \
                     results there are biased; use band_hz \"auto\" or narrow the band"
                )
            }
            IdentWarning::PoorFit {
                chi2_per_dof,
                worst_band_hz,
                worst_chi2_per_dof,
            } => write!(
                f,
                "the model does not explain the data: chi2/dof {chi2_per_dof:.2} (worst \
                 {worst_chi2_per_dof:.1} at {:.2}-{:.2} Hz); uncertainties widened by {:.2}x, \
                 and the model may miss an effect (run the diagnosis)",
                worst_band_hz[0],
                worst_band_hz[1],
                chi2_per_dof.max(1.0).sqrt()
            ),
            IdentWarning::BandTopMisfit {
                band_hz,
                level_ratio,
                chi2_per_bin_above,
            } => write!(
                f,
                "the band ends below {:.1} Hz: from there to {:.1} Hz the model misses the data by \
                 {level_ratio:.0} times the misfit below (chi2 per bin {chi2_per_bin_above:.1} times \
                 its expectation) while the outputs stay coherent with the inputs: the reference's \
                 band limit or smoothing (inputs filtered, not noisy), or dynamics no admissible \
                 order takes; the diagnosis searches above the band",
                band_hz[0], band_hz[1]
            ),
            w @ IdentWarning::GainChangesAcrossBand { .. } => f.write_str(&gain_change_words(w)),
            IdentWarning::PoorFitWithEffects {
                chi2_per_dof,
                without_effects,
            } => write!(
                f,
                "with the accepted effects the model still does not explain the data: chi2/dof \
                 {chi2_per_dof:.2} ({without_effects:.2} without them); uncertainties widened by \
                 {:.2}x, and most of the disagreement is none of the accepted effects (the \
                 diagnosis says what is left)",
                chi2_per_dof.max(1.0).sqrt()
            ),
            IdentWarning::ImplausibleGain { output, input, value } => write!(
                f,
                "K[{output}][{input}] = {value:.4} is implausible for a calibrated block (diagonal \
                 near 1, cross-couplings below 0.1): check units, axis order and signs, or the band"
            ),
            IdentWarning::ImpreciseGain {
                output,
                input,
                value,
                std,
            } => write!(
                f,
                "K[{output}][{input}] = {value:.4} +- {std:.4} (one sigma): this run does not \
                 determine the block's gain to a percent, too little motion for the noise; move \
                 the stand more, or record longer, before certifying from it"
            ),
            IdentWarning::WitnessNoiseBias { estimate, axis, .. } => {
                witness_noise_bias_words(f, *estimate, *axis)
            }
            IdentWarning::WitnessNoiseShared { gyro_estimate } => {
                witness_noise_shared_words(f, *gyro_estimate)
            }
            IdentWarning::NegativeDelay { tau_s, tau_std_s } => write!(
                f,
                "negative delay {:.3} ms (+- {:.3} ms): the block cannot answer before the stand \
                 moves; check the time columns, the angles' own latency, or the band",
                tau_s * 1e3,
                tau_std_s * 1e3
            ),
            w @ IdentWarning::DelayOutsideUsualRange { .. } => delay_outside_words(f, w),
            w @ IdentWarning::PolesOrEvenGain { .. } => poles_or_even_gain_words(f, w),
            IdentWarning::DelayAbsorbedByPoles {
                order,
                tau_s,
                tau_std_s,
                delay_only_tau_s,
            } => delay_absorbed_words(f, *order, *tau_s, *tau_std_s, *delay_only_tau_s),
            IdentWarning::ZerosLead {
                order,
                lead_s,
                lead_std_s,
                tau_s,
                pole_lag_s,
            } => zeros_lead_words(f, *order, *lead_s, *lead_std_s, *tau_s, *pole_lag_s),
            IdentWarning::DelayDrift {
                trend,
                trend_std,
                change_s,
            } => write!(
                f,
                "the delay drifts through the record: {:.3} ms over the run ({:.1} +- {:.1} ppm); \
                 the block and the stand may log on separate clocks, and one delay does not \
                 describe the run (see the stretches in the model file)",
                change_s * 1e3,
                trend * 1e6,
                trend_std * 1e6
            ),
            w @ IdentWarning::DelayStep { .. } => delay_step_words(f, w),
            w @ IdentWarning::ZerosLag { .. } => zeros_lag_words(f, w),
            w @ IdentWarning::DelayScatter { .. } => super::delay_scatter::delay_scatter_words(f, w),
            IdentWarning::StretchesWithoutDelay { spans_s, fitted } => {
                write_stretches_without_delay(f, spans_s, *fitted)
            }
            IdentWarning::InadmissibleOrder { order, reason } => {
                write!(f, "order {order} as asked is not supported by the data: {reason}")
            }
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
            IdentWarning::AngleNoiseOverstated {
                declared_rad,
                bound_rad,
            } => angle_noise_overstated_words(f, *declared_rad, *bound_rad),
            IdentWarning::AngleNoiseColourUnknown {
                angle_noise_rad,
                declared,
            } => angle_noise_colour_unknown_words(f, *angle_noise_rad, *declared),
            IdentWarning::FewSegments {
                segments,
                equivalent_averages,
                segment_len,
                segment_auto,
            } => write!(
                f,
                "only {segments} Welch segments of {segment_len} samples ({equivalent_averages:.1} \
                 equivalent averages): the noise weights rest on few averages, so the deviations \
                 may be too small, and the order may not be checked on half of the record \
                 predicting the other; {}",
                if *segment_auto {
                    "the record is short even for the program's shortest segment: a longer record \
                     is the mend"
                } else {
                    "leave segment_len out to let the program fit it to the record, or lower the \
                     overlap"
                }
            ),
            IdentWarning::GainDependsOnAmplitude { outputs, band_hz } => {
                gain_depends_on_amplitude_words(f, outputs, *band_hz)
            }
            IdentWarning::EffectSuspected(s) => s.fmt(f),
            IdentWarning::GainPattern(p) => p.fmt(f),
            IdentWarning::FactorNotCausal {
                negative_lags,
                refinement,
            } => write!(
                f,
                "the input spectrum's factor is not causal even on a grid {refinement} times finer \
                 ({negative_lags:.1e} of its energy at negative lags): the gain estimate may be off \
                 at the lowest frequencies (a shorter Welch segment or a higher band start avoids it)"
            ),
        }
    }
}
