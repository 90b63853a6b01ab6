//! Fitting the orders in sequence and choosing among them.

use super::model::{Model, Prepared, parameter_count};
use super::{
    InformationCriterion, OrderCandidate, OrderChoice, StructuralError, StructuralSettings, gain_delay,
    rational,
};

/// Bins needed by order `n`: `2 n + 2`, enough distinct frequencies to separate the numerator's
/// `n` coefficients, the denominator's `n` and the delay (and more than `p / 18` for every order).
pub(super) fn required_bins(order: usize) -> usize {
    2 * order + 2
}

/// The criterion's value for `chi2` with `parameters` parameters on `real_data` real data.
pub(super) fn criterion_value(
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

/// The chosen model and every candidate.
pub(super) struct Selection {
    /// The model returned.
    pub chosen: Model,
    /// Its chi2.
    pub chi2: f64,
    /// Every order fitted, in increasing order.
    pub candidates: Vec<OrderCandidate>,
}

/// Fits orders `0..=highest` (each from the previous one's best) and picks the answer: the
/// highest for `Fixed`, the stable candidate of smallest criterion for `Auto`.
pub(super) fn fit_orders(
    data: &Prepared,
    highest: usize,
    choice: OrderChoice,
    settings: &StructuralSettings,
) -> Result<Selection, StructuralError> {
    let zero = gain_delay::fit(data, settings.tau_min_s, settings.tau_max_s);
    let mut models = vec![zero];
    for n in 1..=highest {
        // `models` holds orders 0..n here: the loop stops at the first failure.
        match rational::fit(data, n, &models[n - 1], settings.max_iterations) {
            Some(model) => models.push(model),
            // Fixed: every order below the requested one is its starting point.
            None if matches!(choice, OrderChoice::Fixed(_)) => {
                return Err(StructuralError::NumericalFailure { order: n });
            }
            None => break,
        }
    }
    let mut candidates = Vec::with_capacity(models.len());
    let mut chi2s = Vec::with_capacity(models.len());
    for model in &models {
        let chi2 = model.chi2(data);
        let p = parameter_count(model.order());
        let value = criterion_value(settings.criterion, chi2, p, data.real_data());
        if !value.is_finite() {
            return Err(StructuralError::NumericalFailure { order: model.order() });
        }
        chi2s.push(chi2);
        candidates.push(OrderCandidate {
            order: model.order(),
            parameters: p,
            chi2,
            criterion: value,
            tau_s: model.tau,
            stable: rational::is_stable(&model.den),
        });
    }
    let pick = match choice {
        OrderChoice::Fixed(_) => models.len() - 1,
        OrderChoice::Auto => candidates
            .iter()
            .enumerate()
            .filter(|(_, c)| c.stable)
            .min_by(|a, b| a.1.criterion.total_cmp(&b.1.criterion))
            .map_or(0, |(i, _)| i),
    };
    Ok(Selection {
        chosen: models.swap_remove(pick),
        chi2: chi2s[pick],
        candidates,
    })
}
