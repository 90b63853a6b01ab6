//! Refitting from a previous fit: what makes a retune (a change of A, Lambda or the order) fast.
//!
//! A [`StructuralFit`] keeps every order's model ([`FittedOrders`]). [`refit_structure`] uses
//! them in one of two ways:
//! - **Same data** (the input's fingerprint and the settings match, i.e. only the order choice
//!   changed): the models are reused as they are and only orders above them are fitted, each from
//!   the one below. Orders are fitted in sequence and order `n` never depends on a higher one, so
//!   the result is exactly what [`fit_structure`](super::fit_structure) gives on the same input
//!   when the previous fit was one.
//! - **Nearby data** (a retune): each order is refined by Levenberg–Marquardt from the previous
//!   model of the same order (rescaled to the new band's `omega_ref`), instead of from the
//!   Sanathanan–Koerner and far-pole starts; where that ends worse than the order below (which a
//!   nested model cannot), it is fitted from scratch. The refinement stops once the predicted gain
//!   is below 0.01 in chi2: on a well-determined order it lands within about 0.1 standard
//!   deviation of the optimum a cold fit finds; an over-parameterised order, whose optimum lies
//!   in a flat valley, can stop elsewhere in the valley, or in another valley. Callers who need
//!   the cold answer refit cold afterwards (the app does).
//!
//! An estimate with offsets is moved to its bins first, as [`fit_structure`](super::fit_structure)
//! moves it ([`super::align`]: by the order-0 fit, whatever the order asked; on nearby data that
//! fit starts from the last settled delay instead of the scan), with the weights
//! that fit's residual narrows (`super::scatter`), so "same data" is the same moved estimate and
//! weights, and an order change on it reuses the models exactly. What the previous fit made of
//! its input before fitting is kept with it (`super::placed`): the same input is not moved or
//! prepared again, and on the same weights (a change of Lambda) their eigen decompositions are
//! reused and the move starts from the last settled delay.
//!
//! Units and contracts are those of the module: the same errors as `fit_structure`, for the same
//! inputs, and no NaN in any output.

use std::sync::Arc;

use super::model::Model;
use super::order::Starts;
use super::placed::Placed;
use super::{
    OrderChoice, ResponseEstimate, StructuralError, StructuralFit, StructuralSettings, UnstableSetAside,
};

/// Every order's model as fitted, with what identifies the data they were fitted to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FittedOrders {
    /// Orders `0..`, normalised with the placed data's `omega_ref` (the band's top, rad/s).
    models: Vec<Model>,
    /// Per order, its unstable fit set aside for the model kept (`rational::Fitted::preferred`).
    set_aside: Vec<Option<UnstableSetAside>>,
    /// The settings of the fit.
    settings: Option<StructuralSettings>,
    /// Whether these models are what a fit from scratch gives on these data.
    from_scratch: bool,
    /// What the fit made of its input before fitting (`super::placed`): the data the models were
    /// fitted to (their normalisation and fingerprint); `None` for a fit built some other way,
    /// which a refit cannot start from.
    placed: Option<Arc<Placed>>,
}

impl FittedOrders {
    /// Keeps `models`, fitted to `data` with `settings`.
    pub(super) fn new(
        placed: Arc<Placed>,
        models: Vec<Model>,
        set_aside: Vec<Option<UnstableSetAside>>,
        settings: &StructuralSettings,
        from_scratch: bool,
    ) -> Self {
        Self {
            models,
            set_aside,
            settings: Some(*settings),
            from_scratch,
            placed: Some(placed),
        }
    }

    /// Whether the fit is the one [`fit_structure`](super::fit_structure) gives on its data: true
    /// for a fit from scratch and for an order change reusing one; false once an order has been
    /// refined from a fit to other data (see the module docs).
    #[must_use]
    pub fn from_scratch(&self) -> bool {
        self.from_scratch
    }

    /// Marks these models as not what a fit from scratch gives (e.g. fitted exactly, but over
    /// a band chosen from a refined fit).
    pub fn mark_refined(&mut self) {
        self.from_scratch = false;
    }

    /// Number of orders kept (orders `0..len`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.models.len()
    }

    /// Whether no order is kept (a fit built some other way).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.models.is_empty()
    }

    /// The models, normalised with `from`, rescaled to `omega_ref`: `den[m]` multiplies
    /// `sigma^(m + 1)` and `num[m]` multiplies `sigma^m`, `sigma = s / omega_ref`.
    fn rescaled(&self, from: f64, omega_ref: f64) -> Vec<Model> {
        let ratio = omega_ref / from;
        self.models.iter().map(|m| m.rescaled(ratio)).collect()
    }
}

/// [`fit_structure`](super::fit_structure), starting from `previous` (see the module docs):
/// instant for a change of the order choice alone, a few refinement steps per order for nearby
/// data. A `previous` without kept models or without their placing (or with a different band
/// size in the rational orders' parameters) is no help and the fit runs cold.
///
/// # Errors
/// Those of [`fit_structure`](super::fit_structure), for the same reasons.
pub fn refit_structure(
    input: &ResponseEstimate,
    order: OrderChoice,
    settings: &StructuralSettings,
    previous: &StructuralFit,
) -> Result<StructuralFit, StructuralError> {
    super::validate(input)?;
    let kept = &previous.fitted;
    let Some(before) = kept
        .placed
        .as_ref()
        .filter(|p| !kept.is_empty() && p.data.omega_ref.is_finite() && p.data.omega_ref > 0.0)
    else {
        let placed = Placed::new(input, settings)?;
        let highest = super::highest_order(order, placed.data.bins())?;
        return super::finish(placed, highest, order, settings, Starts::Cold, true);
    };
    let placed = Placed::again(before, input, settings)?;
    let highest = super::highest_order(order, placed.data.bins())?;
    let same = kept.settings == Some(*settings)
        && (Arc::ptr_eq(before, &placed)
            || before.data.omega_ref.to_bits() == placed.data.omega_ref.to_bits()
                && before.data.fingerprint() == placed.data.fingerprint());
    if same {
        let starts = Starts::Same(&kept.models, &kept.set_aside);
        return super::finish(placed, highest, order, settings, starts, kept.from_scratch);
    }
    let near = kept.rescaled(before.data.omega_ref, placed.data.omega_ref);
    super::finish(placed, highest, order, settings, Starts::Near(&near), false)
}

#[cfg(test)]
mod tests {
    use num_complex::Complex64;

    use super::{FittedOrders, Model};

    /// `N(sigma) / d(sigma)` at `s = j omega`, `sigma = s / omega_ref`.
    fn response(m: &Model, omega: f64, omega_ref: f64) -> [Complex64; 9] {
        let x = omega / omega_ref;
        let d = m.den_at(x);
        std::array::from_fn(|e| Model::poly(m.num.iter().map(|c| c[e]), x, 0) / d)
    }

    #[test]
    fn rescaled_models_keep_their_physical_response() {
        let model = Model {
            num: vec![
                [1.0, 0.1, -0.2, 0.0, 1.1, 0.3, 0.05, 0.0, 0.9],
                [0.2; 9],
                [-0.03; 9],
            ],
            den: vec![0.4, 0.07, 0.01],
            tau: 0.002,
        };
        let kept = FittedOrders {
            models: vec![model],
            set_aside: vec![None],
            settings: None,
            from_scratch: true,
            placed: None,
        };
        let rescaled = &kept.rescaled(250.0, 180.0)[0];
        assert_eq!(
            rescaled.tau.to_bits(),
            0.002_f64.to_bits(),
            "the delay is not rescaled"
        );
        for omega in [3.0, 60.0, 170.0, 250.0] {
            let (a, b) = (
                response(&kept.models[0], omega, 250.0),
                response(rescaled, omega, 180.0),
            );
            for (za, zb) in a.iter().zip(&b) {
                assert!(
                    (za - zb).norm() < 1e-13 * za.norm().max(1.0),
                    "{za} vs {zb} at {omega}"
                );
            }
        }
    }
}
