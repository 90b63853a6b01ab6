//! The block's fit over an even gain: when the measured gain changes across the band with no phase
//! of its own (a reference interpolated from a slower rate or smoothed, inputs the angle-noise
//! model shrank; [`super::gain_curvature`]), the delay-only model takes `K` as the band's mean
//! gain, and `auto` may take the change as dynamics (poles and zeros the block does not have:
//! order 3 on 2 of 12 simulated runs with a 240 Hz linearly interpolated reference, one of them
//! with a delay of -8.5 ms).
//!
//! [`over_even_gain`] reads the even gain off the delay-only model's residual (the same check
//! that says `gain_changes_across_band`), fits every order again to `W_u / g`, and keeps that
//! fit when it is delay-only and the first fit's poles do not explain the data better (the
//! information criterion of both on the same data, `g`'s two coefficients counted: a sensor's lag
//! bends the gain and the phase together, and `g` then takes the gain's bend while the delay
//! takes its phase, a worse fit; [`poles_margin`]): its `K` is then the gain at low
//! frequency, its model `g K e^(-tau s)`, and its deviations widened in quadrature by what `g`'s
//! own uncertainty moves `K` by, and never below the delay-only fit's (widened by that fit's
//! misfit: `g`'s two-term shape is an assumption, and on simulated runs with a 120 Hz linearly
//! interpolated reference the accelerometer's `K` kept a third of its bias, 2.1 of the narrower
//! deviations rms). When
//! the fit over `g` still needs poles, the dynamics are the block's (a sensor's low-pass also
//! bends the gain, with phase): the first fit is kept, as fitted. When the first fit's poles win
//! on the criterion alone, they are kept and `poles_or_even_gain` says so with the delay the fit
//! over `g` gives: the two differ by the poles' lag, and only the margin tells them apart (the
//! real run `broad07` with its gyro written 16 samples late, a 60.2 ms delay: order 3 at 46.2 ms,
//! its criterion 8.8 below the fit over `g` at 60.17 ms, said by nothing before; at the
//! recording's own 4.2 ms the order-3 fit's delay is negative and the rules reject it). A fixed order above
//! 0 is the user's structure and is left alone.
//!
//! Units as [`super::gain_curvature`]: `omega` in rad/s, `K` dimensionless. Nothing here panics
//! on any input; a check that cannot be made (no bins, no information) leaves the fit as it was.

use std::sync::Arc;

use super::IdentError;
use super::factorisation::Factorisation;
use super::gain_curvature::EvenGain;
use super::holdout::HeldOut;
use super::identify::structural_fit;
use super::selfcheck::{band_bins, gain_changes};
use super::settings::OrderSetting;
use super::spectra::BlockSpectra;
use super::structural::{InformationCriterion, StructuralFit, criterion_value};
use super::warnings::IdentWarning;
use super::wiener::WienerEstimate;
use crate::block::Block;

/// What [`over_even_gain`] gives: the fit to report and, when it was fitted over an even gain,
/// the first fit (where the next retune starts from) and the warning that says so.
#[derive(Clone, Debug)]
pub struct OverEvenGain {
    /// The fit to report.
    pub fit: Arc<StructuralFit>,
    /// The fit to the estimate as measured, when `fit` is the fit over the even gain.
    pub first: Option<Arc<StructuralFit>>,
    /// `gain_changes_across_band` where the delay-only model's residual says it: with
    /// `k_at_low_frequency` (and each row's bias as applied) when `fit` is over the gain; as
    /// fitted when the first fit was delay-only and the fit over the gain was not kept;
    /// `poles_or_even_gain` when the first fit's poles are kept on the criterion alone over a
    /// delay-only fit over the gain; `None` when the first fit has an order above 0 and the fit
    /// over the gain needs poles too (the self-check then judges that fit's own residual).
    pub warning: Option<IdentWarning>,
}

/// The block's fit, over an even gain where its delay-only model's residual shows one (module
/// docs). `fit` is the fit to the estimate as measured with its deviations widened (the
/// stretches' spread, the gyro's own noise: `widened` does that to a new fit), `held_out` the
/// halves' figures; the fit over the even gain starts from `previous` (an earlier one, in the
/// app's retunes) where given, and is then provisional as any refined fit is.
///
/// # Errors
/// None at present: a delay-only model that cannot be fitted, or a fit over the even gain that
/// fails, leaves the first fit (with the warning where it was said); the `Result` keeps the
/// stages' signature.
#[expect(
    clippy::too_many_arguments,
    reason = "the fit's stages, each its own cached input"
)]
pub fn over_even_gain(
    block: Block,
    spectra: &BlockSpectra,
    factorisation: &Factorisation,
    wiener: &WienerEstimate,
    band: &[usize],
    fit: Arc<StructuralFit>,
    order: OrderSetting,
    held_out: Option<&HeldOut>,
    previous: Option<&StructuralFit>,
    widened: &dyn Fn(&StructuralFit) -> StructuralFit,
) -> Result<OverEvenGain, IdentError> {
    let unchanged = |fit: Arc<StructuralFit>, warning| OverEvenGain {
        fit,
        first: None,
        warning,
    };
    if matches!(order, OrderSetting::Fixed(n) if n > 0) {
        return Ok(unchanged(fit, None));
    }
    // The delay-only model of the same data: the fit itself, or its order 0 fitted again from
    // the models the fit kept.
    let delay_only = if fit.order == 0 {
        fit.clone()
    } else {
        match structural_fit(
            spectra,
            factorisation,
            wiener,
            band,
            OrderSetting::Fixed(0),
            held_out,
            Some(&fit),
            None,
        ) {
            Ok(d) => Arc::new(widened(&d)),
            // No delay-only model to read the gain off: the fit as it is (never a new refusal).
            Err(_) => return Ok(unchanged(fit, None)),
        }
    };
    let bins = band_bins(spectra, &factorisation.noise_psd, wiener, band, &delay_only);
    let Some((warning, curvature)) = gain_changes(block, &bins, spectra.bin_correlation, &delay_only) else {
        return Ok(unchanged(fit, None));
    };
    let even = curvature.even_gain();
    let said = (fit.order == 0).then(|| warning.clone());
    let Ok(over) = structural_fit(
        spectra,
        factorisation,
        wiener,
        band,
        order,
        held_out,
        previous,
        Some(&even),
    ) else {
        return Ok(unchanged(fit, said));
    };
    let margin = poles_margin(&fit, &over, &even, spectra.bin_correlation);
    if over.order > 0 {
        // Poles over the even gain too: the block's own dynamics, its fit as fitted.
        return Ok(unchanged(fit, said));
    }
    if let Some(margin) = margin.filter(|m| *m > 0.0) {
        // Poles that explain the gain's change better than the even gain does (with its phase):
        // kept, and said, with the delay the even gain would give (the two are told apart by
        // the margin alone).
        let said = poles_or_even_gain(&fit, &widened(&over), &warning, margin);
        return Ok(unchanged(fit, said));
    }
    let mut over = widened(&over);
    let change: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| delay_only.k[i][j] - over.k[i][j]));
    over.carry_even_gain(EvenGain {
        k_change: change,
        ..even
    });
    // The even gain's shape is assumed (two terms; a linear interpolation's `1 / sinc^2` is
    // steeper): a fit that explains the data better through it does not know K better than the
    // delay-only fit did, whose deviations its misfit widened. Those, with g's, are the floor.
    for i in 0..3 {
        for j in 0..3 {
            let floor = delay_only.k_std[i][j].hypot(even.k_change_std[i][j]);
            if over.k_std[i][j] < floor {
                over.set_k_std(i, j, floor);
            }
        }
    }
    if !fit.fitted.from_scratch() {
        // The even gain was read off a refined fit: provisional, as that fit was.
        over.fitted.mark_refined();
    }
    // Each row's bias as applied: the change's projection on the row at low frequency.
    let applied: [f64; 3] = std::array::from_fn(|i| {
        let row = over.k[i];
        let norm: f64 = row.iter().map(|v| v * v).sum::<f64>().max(f64::MIN_POSITIVE);
        (0..3).map(|j| change[i][j] * row[j]).sum::<f64>() / norm
    });
    let warning = match warning {
        IdentWarning::GainChangesAcrossBand {
            rise,
            rise_std,
            outputs,
            k_relative_std,
            rows_moved,
            largest_change,
            band_hz,
            ..
        } => IdentWarning::GainChangesAcrossBand {
            rise,
            rise_std,
            k_bias: applied,
            outputs,
            k_relative_std,
            rows_moved,
            largest_change,
            band_hz,
            k_at_low_frequency: true,
        },
        other => other,
    };
    Ok(OverEvenGain {
        fit: Arc::new(over),
        first: Some(fit),
        warning: Some(warning),
    })
}

/// `poles_or_even_gain`: the kept fit with poles `first`, the delay-only fit over the even gain
/// `over` (deviations widened as reported), the gain's change as `gain_changes_across_band`
/// said it, and the criterion's margin of `first` over `over`.
fn poles_or_even_gain(
    first: &StructuralFit,
    over: &StructuralFit,
    change: &IdentWarning,
    margin: f64,
) -> Option<IdentWarning> {
    let IdentWarning::GainChangesAcrossBand { rise, band_hz, .. } = *change else {
        return None;
    };
    Some(IdentWarning::PolesOrEvenGain {
        order: first.order,
        tau_s: first.tau_s,
        tau_std_s: first.tau_std_s,
        even_tau_s: over.tau_s,
        even_tau_std_s: over.tau_std_s,
        rise,
        band_hz,
        margin,
    })
}

/// How much better `first`, a fit with poles, explains the block's estimate than `over`, the
/// delay-only fit over the even gain `even` (positive: `first` better): the difference of the
/// selection's information criterion
/// ([`criterion_value`], BIC; the bins' correlation and the overdispersion of the better of the
/// two discounted as in the selection) with `g`'s coefficients counted among `over`'s
/// parameters. Both chi2 are of the same estimate `W_u` with the same row weights (`over`'s is
/// `|W_u - g M|^2` weighted as `first`'s), each then narrowed where its own delay-only residual
/// scatters less than the weights say (`structural::scatter`): a fit over `g` that explains the
/// gain's bend is narrowed more, which leans the comparison towards the poles. Measured on 126
/// simulated runs with slower or band-limited references (a reviewer's campaign): the fit over
/// `g` kept wherever the first fit had admissible poles without a sensor filter (won by 90 on the
/// criterion in the one such block). `None` for a delay-only `first` or figures missing.
fn poles_margin(
    first: &StructuralFit,
    over: &StructuralFit,
    even: &EvenGain,
    bin_correlation: f64,
) -> Option<f64> {
    let chosen = |fit: &StructuralFit| fit.candidates.iter().find(|c| c.order == fit.order).cloned();
    let (a, b) = (chosen(first)?, chosen(over)?);
    if first.order == 0 || !(a.chi2.is_finite() && b.chi2.is_finite()) {
        return None;
    }
    let b_parameters = b.parameters + even.coefficients.len();
    let real_data = first.dof + a.parameters;
    let per_dof = |chi2: f64, p: usize| chi2 / real_data.saturating_sub(p).max(1) as f64;
    let correlation = bin_correlation.max(1.0);
    let scale = per_dof(a.chi2, a.parameters)
        .min(per_dof(b.chi2, b_parameters))
        .max(1.0)
        * correlation;
    let effective_data = ((real_data as f64 / correlation) as usize).max(1);
    let criterion =
        |chi2: f64, p: usize| criterion_value(InformationCriterion::Bic, chi2 / scale, p, effective_data);
    Some(criterion(b.chi2, b_parameters) - criterion(a.chi2, a.parameters))
}
