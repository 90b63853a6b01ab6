//! Fitting the orders in sequence and choosing among them.

use rayon::prelude::*;

use super::model::{Model, Prepared, parameter_count};
use super::{
    InformationCriterion, OrderCandidate, OrderChoice, StructuralError, StructuralSettings, UnstableSetAside,
    admissible, gain_delay, rational,
};

/// Relative excess of chi2 over the order below that a refined order may keep (rounding: a
/// first-order fit whose pole has gone to infinity has order 0's chi2).
const NESTED_SLACK: f64 = 1e-6;

/// Bins needed by order `n`: `2 n + 2`, enough distinct frequencies to separate the numerator's
/// `n` coefficients, the denominator's `n` and the delay (and more than `p / 18` for every order).
pub(super) fn required_bins(order: usize) -> usize {
    2 * order + 2
}

/// The criterion's value for `chi2` with `parameters` parameters on `real_data` real data.
#[must_use]
pub fn criterion_value(
    criterion: InformationCriterion,
    chi2: f64,
    parameters: usize,
    real_data: usize,
) -> f64 {
    let penalty = match criterion {
        InformationCriterion::Bic => (real_data as f64).ln(),
        InformationCriterion::Aic => 2.0,
    };
    chi2 + penalty * parameters as f64
}

/// Where the fits of each order start.
#[derive(Clone, Copy)]
pub(super) enum Starts<'a> {
    /// From scratch: the delay scan, then each order from the one below.
    Cold,
    /// The data are those these models (orders `0..`) were fitted to: they are kept as they are
    /// (all of them, also above the highest order asked for), and only orders above them are
    /// fitted (from the one below, as [`Starts::Cold`] does). Beside them, each order's unstable
    /// fit set aside, as [`Selection::set_aside`] keeps it.
    Same(&'a [Model], &'a [Option<UnstableSetAside>]),
    /// Nearby data (a retune): each order is refined from the model of the same order here
    /// (normalised to this fit's `omega_ref`); order 0 in its delay's scan cell, scanned again
    /// only when the cell holds no maximum.
    Near(&'a [Model]),
}

/// The chosen model and every candidate.
pub(super) struct Selection {
    /// Every order fitted (or kept), in increasing order: possibly beyond the candidates.
    pub models: Vec<Model>,
    /// Per model, the unstable fit of its order set aside for it ([`rational::Fitted::preferred`]).
    pub set_aside: Vec<Option<UnstableSetAside>>,
    /// Index in `models` (and in `candidates`) of the model returned.
    pub pick: usize,
    /// Every order fitted, in increasing order.
    pub candidates: Vec<OrderCandidate>,
}

impl Selection {
    /// The model returned.
    pub fn chosen(&self) -> &Model {
        &self.models[self.pick]
    }

    /// Its chi2.
    pub fn chi2(&self) -> f64 {
        self.candidates[self.pick].chi2
    }
}

/// Fits orders `0..=highest` (each from the previous one's best, or as `starts` says) and picks
/// the answer: the highest for `Fixed`, the admissible candidate ([`admissible`]) of smallest
/// criterion for `Auto`. The criterion's chi2 is divided by the overdispersion
/// `max(1, min_n chi2_n / dof_n)` (quasi-likelihood): when no candidate explains the data to its
/// stated noise, the noise is larger than stated and so is the evidence's uncertainty.
pub(super) fn fit_orders(
    data: &Prepared,
    highest: usize,
    choice: OrderChoice,
    settings: &StructuralSettings,
    starts: Starts,
) -> Result<Selection, StructuralError> {
    let (mut models, mut set_aside) = match starts {
        Starts::Same(kept, aside) if !kept.is_empty() => {
            // Parallel to the models (`FittedOrders` keeps them so); none said where missing.
            let mut aside = aside.to_vec();
            aside.resize(kept.len(), None);
            (kept.to_vec(), aside)
        }
        // Near: order 0 refined in the previous delay's cell, scanned only when that holds no
        // maximum (a retune is provisional: the app refits from scratch once the settings rest).
        Starts::Near(near) if !near.is_empty() => (
            vec![gain_delay::fit_near(
                data,
                near[0].tau,
                settings.tau_min_s,
                settings.tau_max_s,
                settings.bin_correlation,
            )],
            vec![None],
        ),
        _ => (
            vec![gain_delay::fit(
                data,
                settings.tau_min_s,
                settings.tau_max_s,
                settings.bin_correlation,
            )],
            vec![None],
        ),
    };
    // Near: every order's refinement at once (they are independent), in parallel.
    let mut warm: Vec<Option<(Model, f64)>> = match starts {
        Starts::Near(near) => (1..=highest)
            .into_par_iter()
            .map(|n| {
                let start = near.get(n)?;
                rational::refine_warm(data, start, settings.max_iterations)
            })
            .collect(),
        _ => Vec::new(),
    };
    for n in models.len()..=highest {
        // `models` holds orders 0..n here: the loop stops at the first failure.
        let below = &models[n - 1];
        // A refined order is kept unless it ends worse than the order below (which, from order 2
        // on, nests in it): then it is fitted from scratch, which cannot, but for a stable fit
        // preferred to a better unstable one (`rational::Fitted::preferred`). A refined order
        // (a retune, provisional: the app refits from scratch once the settings rest) is not
        // put through that preference.
        let refined = warm
            .get_mut(n - 1)
            .and_then(Option::take)
            .filter(|(_, chi2)| *chi2 <= below.chi2(data) * (1.0 + NESTED_SLACK));
        let fitted = match refined {
            Some((model, _)) => Some((model, None)),
            None => rational::fit(data, n, below, settings.max_iterations)
                .map(|fitted| fitted.preferred(data, settings.bin_correlation)),
        };
        match fitted {
            Some((model, aside)) => {
                models.push(model);
                set_aside.push(aside);
            }
            // Fixed: every order below the requested one is its starting point.
            None if matches!(choice, OrderChoice::Fixed(_)) => {
                return Err(StructuralError::NumericalFailure { order: n });
            }
            None => break,
        }
    }
    // Kept models above `highest` stay in `models` (for a later change of order), out of the choice.
    let considered = &models[..models.len().min(highest + 1)];
    let chi2: Vec<f64> = considered.iter().map(|m| m.chi2(data)).collect();
    // Overdispersion: where even the richest fit leaves chi2/dof above 1 the weights understate
    // the noise, and the evidence of every candidate is discounted by it (quasi-likelihood BIC).
    let per_dof = |i: usize| {
        let dof = data
            .real_data()
            .saturating_sub(parameter_count(considered[i].order()))
            .max(1);
        chi2[i] / dof as f64
    };
    let overdispersion = (0..considered.len())
        .map(per_dof)
        .fold(f64::INFINITY, f64::min)
        .max(1.0);
    let correlation = settings.bin_correlation.max(1.0);
    let effective_data = ((data.real_data() as f64 / correlation) as usize).max(1);
    let mut candidates = Vec::with_capacity(considered.len());
    for (i, model) in considered.iter().enumerate() {
        let chi2 = chi2[i];
        let p = parameter_count(model.order());
        let value = criterion_value(
            settings.criterion,
            chi2 / (overdispersion * correlation),
            p,
            effective_data,
        );
        if !value.is_finite() {
            return Err(StructuralError::NumericalFailure { order: model.order() });
        }
        candidates.push(OrderCandidate {
            order: model.order(),
            parameters: p,
            chi2,
            criterion: value,
            tau_s: model.tau,
            stable: rational::is_stable(&model.den),
            rejected: admissible::rejection(
                data,
                model,
                (per_dof(i).max(1.0) * correlation).sqrt(),
                settings.held_out_chi2.as_ref().map(|h| &h[..]),
            ),
            held_out_chi2: settings
                .held_out_chi2
                .and_then(|h| h.get(model.order()).copied().flatten()),
            unstable_set_aside: set_aside[i],
        });
    }
    let pick = match choice {
        OrderChoice::Fixed(_) => considered.len() - 1,
        OrderChoice::Auto => candidates
            .iter()
            .enumerate()
            .filter(|(_, c)| c.rejected.is_none())
            .min_by(|a, b| a.1.criterion.total_cmp(&b.1.criterion))
            .map_or(0, |(i, _)| i),
    };
    Ok(Selection {
        models,
        set_aside,
        pick,
        candidates,
    })
}
