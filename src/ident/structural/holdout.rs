//! Held-out prediction: every order fitted to one half of the record predicts the other.
//!
//! The information criterion judges each order on the data it was fitted to, with weights that
//! may understate or misshape the noise. Poles that fit noise lower chi2 on their own data and
//! raise it on data they have not seen; a real pole lowers it on both. [`held_out_chi2`] fits
//! orders `0..` to two estimates of the same response from disjoint stretches of the record (the
//! first and second half) and evaluates each half's models on the other half's estimate with
//! that half's weights: order `n`'s held-out chi2 is `chi2(model_1[n] on half 2) +
//! chi2(model_2[n] on half 1)`. Admissibility rule 7 ([`super::admissible`]) keeps an order
//! above 0 only when that figure is below every lower order's.
//!
//! Halves with offsets are moved to their bins first, each by its own order-0 fit
//! ([`super::align`]).
//!
//! Units and contracts are those of the module: the halves are validated as any input
//! ([`super::fit_structure`]'s errors), need not share bins (each model is renormalised to the
//! other half's reference frequency), and an order not fitted to both halves has no figure.

use std::sync::Arc;

use super::align::prepared;
use super::order::{Starts, fit_orders};
use super::weights::row_weights;
use super::{MAX_ORDER, OrderChoice, ResponseEstimate, StructuralError, StructuralSettings, highest_order};

/// Each order's held-out chi2 (index = order): the models of every order `0..=4` the two
/// estimates support, fitted cold to each, each evaluated on the other; `None` where an order
/// was not fitted to both or its figure is not finite.
///
/// # Errors
/// Those of [`super::fit_structure`] for `Auto`, for either half.
pub fn held_out_chi2(
    first: &ResponseEstimate,
    second: &ResponseEstimate,
    settings: &StructuralSettings,
) -> Result<[Option<f64>; MAX_ORDER + 1], StructuralError> {
    let settings = StructuralSettings {
        held_out_chi2: None,
        ..*settings
    };
    // Halves whose columns lie off their bins are moved there, each by its own order-0 fit
    // (`super::align`).
    let place = |half: &ResponseEstimate| {
        super::validate(half)?;
        let rows = Arc::from(row_weights(&half.weights)?);
        let (data, _) = prepared(half, rows, &settings, None)?;
        let highest = highest_order(OrderChoice::Auto, data.bins())?;
        Ok::<_, StructuralError>((data, highest))
    };
    let (a, highest_a) = place(first)?;
    let (b, highest_b) = place(second)?;
    let highest = highest_a.min(highest_b);
    let fa = fit_orders(&a, highest, OrderChoice::Auto, &settings, Starts::Cold)?;
    let fb = fit_orders(&b, highest, OrderChoice::Auto, &settings, Starts::Cold)?;
    let mut out = [None; MAX_ORDER + 1];
    for (n, slot) in out.iter_mut().enumerate().take(highest + 1) {
        let (Some(ma), Some(mb)) = (fa.models.get(n), fb.models.get(n)) else {
            break;
        };
        let on_b = ma.rescaled(b.omega_ref / a.omega_ref).chi2(&b);
        let on_a = mb.rescaled(a.omega_ref / b.omega_ref).chi2(&a);
        let total = on_a + on_b;
        *slot = total.is_finite().then_some(total);
    }
    Ok(out)
}
