//! The self-check of every identified block: problems a reader must know before using the model,
//! in plain words ([`IdentWarning`]), printed by the command line, kept in the model file's
//! `fit.warnings` and shown in red in the app.
//!
//! - **Poor fit**: chi2/dof of the chosen model above [`POOR_FIT`] (the weights understate the
//!   misfit: the standard deviations are widened by `sqrt(chi2/dof)`, and an effect may be
//!   missing); the octave of the largest misfit is named, from the per-bin chi2 (residual
//!   structure across frequency rather than one number).
//! - **Implausible gain**: with `calibrated` (the default), a diagonal element of `K` more than
//!   [`GAIN_TOLERANCE`] from 1 or a cross-coupling above it: wrong units, axis order or signs, or a
//!   band where the inputs are noise. Where `K` reads as a unit slip or axes swapped or reversed
//!   (a scale times a signed permutation of the identity), that is said too
//!   ([`super::gain_pattern`]).
//! - **Imprecise gain**: with `calibrated`, the largest standard deviation of an element of `K`
//!   above [`IMPRECISE_GAIN`]: the run does not determine the gain to a percent.
//! - **Gain changes across the band**: the measured gain rises (or falls) evenly in frequency,
//!   with no phase, beyond 3 of its deviations, and moves a row of `K` from the gain at low
//!   frequency by more than `K`'s relative deviation `||K_std||_F / ||K||_F` (for a `K` near the
//!   identity about `sqrt(3)` times one row's scale deviation, so stricter than a row's own test)
//!   ([`super::gain_curvature`]: a reference interpolated or smoothed). Here for a rational
//!   order's own residual; a delay-only model's is checked before the self-check, where it decides
//!   the fit over an even gain ([`super::even_gain`]).
//! - **Negative delay**: `tau + 3 sigma < 0`.
//! - **Delay outside the usual range**: the model's delay, or else the delay-only candidate's,
//!   outside the -20 to 50 ms searched first (found by the wider search of
//!   `structural::gain_delay`): clocks offset between the angles and the outputs, said with the
//!   gain the Welch segments' smaller overlap costs at that delay.
//! - **Delay absorbed by poles**: a chosen order above 0 whose delay is negative while the
//!   order-0 candidate's is positive, the two more than 2 sigma apart (the poles' lag replaces part of the delay; a band-limited
//!   reference's gain rise is fitted that way: measured on a real run's 64 s stretch, order 2 with
//!   -4.8 ms for the delay-only model's +4.2 ms, before a short record got a segment fitted to it).
//! - **Zeros lead**: a chosen order of 2 or more, admissible, whose numerator's zeros lead at low
//!   frequency beyond three of their deviations' bound (a fixed order the rules reject says
//!   `inadmissible_order` instead: a clean run forced to order 3 has zeros that lead or lag at
//!   random). A sensor's filters do not lead; angles that lag the motion do (an independent
//!   simulator's gyro behind angles low-passed at 20 Hz: order 3, zeros leading by 11.28 ms
//!   where the filter's group delay is 11.25 ms, the delay and poles giving the sensor's 3 ms).
//! - **Inadmissible order**: a fixed order that breaks a rule of [`super::structural::admissible`].
//! - **Gain depends on the amplitude** (added by the session, which holds the signals the test
//!   needs): an output odd-quadratic in its input beyond `K`'s deviation ([`super::odd_gain`]).
//! - **Few segments**: fewer Welch segments or equivalent averages than [`leaves_enough`] asks (a
//!   segment or overlap given by the user on a short record): weights on few averages, maybe no
//!   held-out check of the order.
//!
//! Units: `K` dimensionless (block units over input units), delays in s, frequencies in Hz.

use std::sync::Arc;

use num_complex::Complex64;

use super::gain_curvature::{self, Curvature};
use super::identify::row_weights;
use super::settings::{OrderSetting, Settings, leaves_enough};
use super::signals::channel_names;
use super::spectra::BlockSpectra;
use super::structural::gain_delay::DELAY_REACH_S;
use super::structural::{StructuralFit, StructuralSettings};
use super::warnings::{ElementChange, IdentWarning};
use super::wiener::WienerEstimate;
use crate::block::Block;

/// How many of its standard deviations the gain's curvature must reach to be said (with its bias
/// on `K` above `K`'s deviation): the convention of the other checks (`negative_delay`).
pub const CURVATURE_SIGMAS: f64 = 3.0;

/// chi2/dof above which the fit is reported as not explaining the data.
pub const POOR_FIT: f64 = 2.0;

/// Largest `|K_ii - 1|` and `|K_ij|` (i != j) of a calibrated block.
pub const GAIN_TOLERANCE: f64 = 0.1;

/// Largest standard deviation of an element of a calibrated block's `K` before it is reported
/// as imprecise: a percent of the identity's diagonal, ten times a certification's usual
/// scale-factor requirement. Measured: the three real recordings' largest is 0.0045; weak
/// motions of another simulator (0.02 degrees) gave 0.012-0.17 on the accelerometer.
pub const IMPRECISE_GAIN: f64 = 0.01;

/// The band's native bins as the self-check compares them: the chosen model as the estimate sees
/// it (at the bin's frequency, with its offsets), the Wiener estimate, and the weights
/// `Omega_i = (n_eq - 3) S_uu / S_psi,ii` as given to the structural fit (before its narrowing to
/// the local scatter, `structural::scatter`, which only raises them where they overstate the
/// noise: a misfit here is one there); `noise` is `S_psi` per bin. [`chi2_per_bin`] and the
/// gain-curvature check read the same bins.
#[must_use]
pub fn band_bins(
    spectra: &BlockSpectra,
    noise: &[nalgebra::Matrix3<Complex64>],
    wiener: &WienerEstimate,
    band: &[usize],
    fit: &StructuralFit,
) -> Vec<gain_curvature::Bin> {
    let dof = (spectra.equivalent_averages - 3.0).max(1.0);
    band.iter()
        .map(|&k| {
            let f_hz = spectra.model_frequency_hz(k, wiener.estimate);
            gain_curvature::Bin {
                omega: 2.0 * std::f64::consts::PI * f_hz,
                model: fit.response_seen(
                    f_hz,
                    spectra.fit_offset_hz(k, wiener.estimate).as_ref(),
                    spectra.aligned_s(),
                ),
                estimate: wiener.w_u(k),
                weights: row_weights(&spectra.s_uu[k], &noise[k], dof),
            }
        })
        .collect()
}

/// Per-bin chi2 of `fit` against the Wiener estimate over the native `band` bins ([`band_bins`]).
#[must_use]
pub fn chi2_per_bin(
    spectra: &BlockSpectra,
    noise: &[nalgebra::Matrix3<Complex64>],
    wiener: &WienerEstimate,
    band: &[usize],
    fit: &StructuralFit,
) -> Vec<f64> {
    band_bins(spectra, noise, wiener, band, fit)
        .iter()
        .map(gain_curvature::Bin::chi2)
        .collect()
}

/// The gain-curvature check (module docs, [`gain_curvature`]) on the band's `bins`
/// ([`band_bins`]): the common even gain of the chosen model's residual; said when its rise
/// across the band is beyond [`CURVATURE_SIGMAS`] of its deviation and the bias it gives a row of
/// `K` exceeds `K`'s relative deviation, or the change it gives an element of `K` exceeds that
/// element's own deviation.
#[must_use]
pub fn gain_changes(
    block: Block,
    bins: &[gain_curvature::Bin],
    bin_correlation: f64,
    fit: &StructuralFit,
) -> Option<(IdentWarning, Curvature)> {
    let c = gain_curvature::curvature(bins, &fit.k, bin_correlation)?;
    let norm = |m: &[[f64; 3]; 3]| m.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    let k_relative_std = norm(&fit.k_std) / norm(&fit.k);
    let k_bias = c.row_bias;
    let largest = k_bias.iter().fold(0.0, |m: f64, b| m.max(b.abs()));
    // The element the change moves furthest against its own deviation: a row's scale measured
    // against the whole `K`'s relative deviation is blind to a well-determined row beside
    // poorly determined off-diagonals (an accelerometer's z row behind a 500 Hz reference: its
    // rise 9 deviations, `K_zz` 3.7 of its own off, the row's scale below `K`'s 0.15 %).
    let (inputs, output_names) = channel_names(block);
    let (sigmas, (i, j)) = (0..9)
        .map(|e| (e / 3, e % 3))
        .filter(|&(i, j)| fit.k_std[i][j] > 0.0 && c.row_change[i][j].is_finite())
        .map(|(i, j)| (c.row_change[i][j].abs() / fit.k_std[i][j], (i, j)))
        .fold((0.0, (0, 0)), |best, x| if x.0 > best.0 { x } else { best });
    let rows_moved = largest > k_relative_std;
    let said = c.rise().abs() > CURVATURE_SIGMAS * c.rise_std() && (rows_moved || sigmas > 1.0);
    let to_hz = |w: f64| w / (2.0 * std::f64::consts::PI);
    said.then(|| {
        let warning = IdentWarning::GainChangesAcrossBand {
            rise: c.rise(),
            rise_std: c.rise_std(),
            k_bias,
            outputs: output_names.map(str::to_owned),
            k_relative_std,
            rows_moved,
            // None where no element has a deviation to move against.
            largest_change: if sigmas > 0.0 {
                ElementChange {
                    output: output_names[i].to_owned(),
                    input: inputs[j].to_owned(),
                    sigmas,
                }
            } else {
                ElementChange::default()
            },
            band_hz: [to_hz(c.omega_range[0]), to_hz(c.omega_range[1])],
            k_at_low_frequency: false,
        };
        (warning, c)
    })
}

/// The least determined element of `K` (the largest deviation in `k_std`; an unknown one, NaN of
/// either sign, counts as the least determined), and whether the imprecise-gain check says it:
/// its deviation unknown or beyond [`IMPRECISE_GAIN`]. The rule of [`imprecise_gain`] and of an
/// extended model's own figures (`crate::model::BlockModel`).
#[must_use]
pub fn least_determined_gain(k_std: &[[f64; 3]; 3]) -> ((usize, usize), bool) {
    let key = |v: f64| if v.is_nan() { f64::INFINITY } else { v };
    let (i, j) = (0..9)
        .map(|e| (e / 3, e % 3))
        .max_by(|&(a, b), &(c, d)| key(k_std[a][b]).total_cmp(&key(k_std[c][d])))
        .unwrap_or((0, 0));
    let std = k_std[i][j];
    ((i, j), std.is_nan() || std > IMPRECISE_GAIN)
}

/// The gain-plausibility check of a calibrated block (module docs): every element of `k` off a
/// calibrated block's by more than [`GAIN_TOLERANCE`] (a diagonal element from 1, a
/// cross-coupling from 0), or NaN; `inputs` and `outputs` name `k`'s columns and rows. Of any
/// model (an extended one's on its own `K`, `crate::model::BlockModel`).
pub fn implausible_gains<'a>(
    k: &'a [[f64; 3]; 3],
    inputs: [&'a str; 3],
    outputs: [&'a str; 3],
) -> impl Iterator<Item = IdentWarning> + 'a {
    (0..9).filter_map(move |e| {
        let (i, j) = (e / 3, e % 3);
        let v = k[i][j];
        let off = if i == j { (v - 1.0).abs() } else { v.abs() };
        (off.is_nan() || off > GAIN_TOLERANCE).then(|| IdentWarning::ImplausibleGain {
            output: outputs[i].to_owned(),
            input: inputs[j].to_owned(),
            value: v,
        })
    })
}

/// The gain-plausibility check of a calibrated `block`'s `k` ([`implausible_gains`] on its
/// channels), with what an implausible `K` reads as ([`super::gain_pattern`]) said first, the
/// cause before its symptoms; empty where every element is plausible. Of any model (an extended
/// one's on its own `K`, `crate::model::BlockModel`).
#[must_use]
pub fn gain_plausibility(block: Block, k: &[[f64; 3]; 3]) -> Vec<IdentWarning> {
    let (inputs, outputs) = channel_names(block);
    let elements: Vec<IdentWarning> = implausible_gains(k, inputs, outputs).collect();
    if elements.is_empty() {
        return elements;
    }
    super::gain_pattern::gain_pattern(block, k)
        .map(IdentWarning::GainPattern)
        .into_iter()
        .chain(elements)
        .collect()
}

/// The delay-sign check (module docs): a delay `tau_s` more than three of its deviations
/// `tau_std_s` below zero, of any model (an extended one's on its own figures,
/// `crate::model::BlockModel`).
#[must_use]
pub fn negative_delay(tau_s: f64, tau_std_s: f64) -> Option<IdentWarning> {
    (tau_s + 3.0 * tau_std_s < 0.0).then_some(IdentWarning::NegativeDelay { tau_s, tau_std_s })
}

/// The imprecise-gain check of a calibrated block (module docs): the least determined element of
/// `K`, once (the others say the same), by [`least_determined_gain`].
#[must_use]
pub fn imprecise_gain(block: Block, fit: &StructuralFit) -> Option<IdentWarning> {
    let (inputs, outputs) = channel_names(block);
    let ((i, j), imprecise) = least_determined_gain(&fit.k_std);
    imprecise.then(|| IdentWarning::ImpreciseGain {
        output: outputs[i].to_owned(),
        input: inputs[j].to_owned(),
        value: fit.k[i][j],
        std: fit.k_std[i][j],
    })
}

/// The self-check's warnings of one block (see the module docs). A delay-only model's gain
/// change is checked before, on the fit as measured (`super::even_gain`), where it decides the fit
/// over an even gain; here only a rational order's.
#[must_use]
pub fn self_check(
    block: Block,
    spectra: &BlockSpectra,
    noise: &[nalgebra::Matrix3<Complex64>],
    wiener: &Arc<WienerEstimate>,
    band: &[usize],
    fit: &StructuralFit,
    settings: &Settings,
) -> Vec<IdentWarning> {
    let mut out = Vec::new();
    if !leaves_enough(spectra.n_averages, spectra.equivalent_averages) {
        out.push(IdentWarning::FewSegments {
            segments: spectra.n_averages,
            equivalent_averages: spectra.equivalent_averages,
            segment_len: spectra.segment_len,
            segment_auto: settings.welch.segment_auto,
        });
    }
    // The band's bins, built only for the checks that read them: a poor fit's worst octave and a
    // rational order's gain change (a delay-only model's was read before, `super::even_gain`).
    let per_dof = fit.chi2 / fit.dof.max(1) as f64;
    let bins = (per_dof > POOR_FIT || fit.order > 0).then(|| band_bins(spectra, noise, wiener, band, fit));
    let bins = bins.as_deref().unwrap_or_default();
    if per_dof > POOR_FIT {
        let chi2: Vec<f64> = bins.iter().map(gain_curvature::Bin::chi2).collect();
        let mut worst = ([0.0, 0.0], 0.0);
        let mut start = 0;
        while start < band.len() {
            let f0 = spectra.frequency_hz[band[start]];
            let end = band[start..]
                .iter()
                .position(|&k| spectra.frequency_hz[k] >= 2.0 * f0)
                .map_or(band.len(), |p| start + p.max(1));
            let n = (end - start) as f64;
            let value = chi2[start..end].iter().sum::<f64>() / (18.0 * n);
            if value > worst.1 {
                worst = ([f0, spectra.frequency_hz[band[end - 1]]], value);
            }
            start = end;
        }
        out.push(IdentWarning::PoorFit {
            chi2_per_dof: per_dof,
            worst_band_hz: worst.0,
            worst_chi2_per_dof: worst.1,
        });
    }
    if fit.order > 0 {
        out.extend(gain_changes(block, bins, spectra.bin_correlation, fit).map(|(w, _)| w));
    }
    if settings.calibrated {
        out.extend(gain_plausibility(block, &fit.k));
        out.extend(imprecise_gain(block, fit));
    }
    out.extend(negative_delay(fit.tau_s, fit.tau_std_s));
    out.extend(delay_outside_usual_range(spectra, fit, settings));
    let delay_only = fit.candidates.iter().find(|c| c.order == 0).map(|c| c.tau_s);
    if let Some(delay_only_tau_s) = delay_only
        && fit.order > 0
        && fit.tau_s < 0.0
        && delay_only_tau_s > 0.0
        && delay_only_tau_s - fit.tau_s > 2.0 * fit.tau_std_s
    {
        out.push(IdentWarning::DelayAbsorbedByPoles {
            order: fit.order,
            tau_s: fit.tau_s,
            tau_std_s: fit.tau_std_s,
            delay_only_tau_s,
        });
    }
    out.extend(zeros_lead(fit));
    out.extend(zeros_lag(fit));
    if let OrderSetting::Fixed(n) = settings.order.of(block)
        && let Some(reason) = fit
            .candidates
            .iter()
            .find(|c| c.order == n)
            .and_then(|c| c.rejected.clone())
    {
        out.push(IdentWarning::InadmissibleOrder { order: n, reason });
    }
    out
}

/// `delay_outside_usual_range` when the model's delay, or else the delay-only candidate's, lies
/// outside the structural fit's first range (found by its wider search: a model with poles can
/// bring its delay back inside by fitting the misfit such a delay leaves, as our simulator's runs
/// with the outputs 47 ms late did at order 4), with the gain the Welch windows' smaller overlap
/// costs at that delay: `1 - sum w_n w_(n+k) / sum w_n^2`, `k` the delay in samples.
fn delay_outside_usual_range(
    spectra: &BlockSpectra,
    fit: &StructuralFit,
    settings: &Settings,
) -> Option<IdentWarning> {
    let usual = StructuralSettings::default();
    let usual_s = [usual.tau_min_s, usual.tau_max_s];
    let outside = |tau: &f64| *tau < usual_s[0] || *tau > usual_s[1];
    let delay_only = fit.candidates.iter().find(|c| c.order == 0).map(|c| c.tau_s);
    let tau_s = Some(fit.tau_s).filter(outside).or(delay_only.filter(outside))?;
    // What the alignment before the estimate left of the delay (`super::alignment`).
    let lag = (tau_s * spectra.sample_rate_hz - spectra.aligned_samples as f64)
        .abs()
        .round();
    let overlap_loss = overlap_loss(&settings.welch.window.coefficients(spectra.segment_len), lag);
    Some(IdentWarning::DelayOutsideUsualRange {
        tau_s,
        usual_s,
        reach_s: DELAY_REACH_S,
        overlap_loss,
        wider_search: delay_only.is_some_and(|t| outside(&t)),
        aligned_s: spectra.aligned_s(),
        model_tau_s: (!outside(&fit.tau_s)).then_some(fit.tau_s),
    })
}

/// `1 -` the window's overlap correlation ([`super::spectra::overlap_correlation`]) at a lag of
/// `lag` samples (whole, non-negative): the relative gain a delay of that many samples costs a
/// Welch estimate through `window`; 1 for a lag beyond the window or a non-finite one.
#[must_use]
pub fn overlap_loss(window: &[f64], lag: f64) -> f64 {
    if !(lag.is_finite() && lag >= 0.0) {
        return 1.0;
    }
    1.0 - super::spectra::overlap_correlation(window, lag as usize)
}

/// How many of their deviations' bound the zeros' lead must exceed for `zeros_lead`. Three, as
/// for a negative delay: at order 2 the delay trades with the numerator's first coefficient and
/// their deviations run short (an all-pole filter on synthetic data, one seed of eight: the delay
/// 2.8 of its deviations long and the zeros leading by 2.06 of theirs); angles behind a 20 Hz
/// filter gave leads of over 100.
pub const ZEROS_LEAD_DEVIATIONS: f64 = 3.0;

/// `zeros_lead` when the chosen model, admissible, has zeros that lead at low frequency beyond
/// [`ZEROS_LEAD_DEVIATIONS`] of their deviations' bound ([`StructuralFit::zeros_lag_s`]: as if
/// every parameter were fully correlated; the parameters' own deviations run short at order 2).
fn zeros_lead(fit: &StructuralFit) -> Option<IdentWarning> {
    let [lag, std] = admissible_zeros_lag(fit)?;
    (-lag > ZEROS_LEAD_DEVIATIONS * std).then(|| IdentWarning::ZerosLead {
        order: fit.order,
        lead_s: -lag,
        lead_std_s: std,
        tau_s: fit.tau_s,
        pole_lag_s: fit.denominator.first().copied().unwrap_or(0.0),
    })
}

/// `zeros_lag` when the chosen model, admissible, has zeros that lag at low frequency beyond
/// [`ZEROS_LEAD_DEVIATIONS`] of their deviations' bound, as [`zeros_lead`] for a lead.
fn zeros_lag(fit: &StructuralFit) -> Option<IdentWarning> {
    let [lag, std] = admissible_zeros_lag(fit)?;
    (lag > ZEROS_LEAD_DEVIATIONS * std).then_some(IdentWarning::ZerosLag {
        order: fit.order,
        lag_s: lag,
        lag_std_s: std,
        tau_s: fit.tau_s,
        tau_std_s: fit.tau_std_s,
        pole_lag_s: fit.denominator.first().copied().unwrap_or(0.0),
    })
}

/// The chosen model's zeros' lag and its deviations' bound, if the model is admissible.
fn admissible_zeros_lag(fit: &StructuralFit) -> Option<[f64; 2]> {
    // A fixed order the rules reject says so (`inadmissible_order`); its zeros are not evidence.
    let admissible = fit
        .candidates
        .iter()
        .any(|c| c.order == fit.order && c.rejected.is_none());
    fit.zeros_lag_s.filter(|_| admissible)
}

#[cfg(test)]
mod tests {
    use super::{IMPRECISE_GAIN, least_determined_gain};

    #[test]
    fn the_least_determined_element_is_the_one_judged() {
        let mut k_std = [[1e-4; 3]; 3];
        k_std[1][2] = 0.5 * IMPRECISE_GAIN;
        assert_eq!(least_determined_gain(&k_std), ((1, 2), false));
        k_std[2][0] = 2.0 * IMPRECISE_GAIN;
        assert_eq!(least_determined_gain(&k_std), ((2, 0), true));
        // An unknown deviation counts as the least determined, whichever sign its NaN has
        // (`total_cmp` alone would put a negative NaN below every figure).
        for nan in [f64::NAN, -f64::NAN] {
            let mut k = k_std;
            k[0][1] = nan;
            assert_eq!(least_determined_gain(&k), ((0, 1), true), "{nan}");
        }
        // Exactly at the limit: not beyond it.
        assert!(!least_determined_gain(&[[IMPRECISE_GAIN; 3]; 3]).1);
    }
}
