//! What a fit makes of its input before any order is fitted, kept for the next fit.
//!
//! Every fit first validates the input's weights (an eigen decomposition per bin and output row,
//! `weights::row_weights`), moves the estimate to its bins and narrows the weights to the settled
//! order-0 fit's scatter (`align`), and precomputes the data the orders read
//! (`model::Prepared`). A [`Placed`] keeps all of it with a copy of the input it came from, and
//! [`Placed::again`] starts a refit (`warm::refit_structure`) from it:
//! - **the same input** (bit for bit: frequencies, response, offsets, weights) and the same delay
//!   range, bins' correlation, alignment and narrowing: the placed data as they are (a change of
//!   the order alone; `warm`'s "same data" then reuses the models too);
//! - **the same weights** (a change of Lambda: the weights come from `S_uu` and the noise alone):
//!   the validated rows reused, the move refitted with its first order-0 fit started from the last
//!   settled delay (`gain_delay::fit_near`, which scans the whole range when the delay left its
//!   scan cell) instead of the scan;
//! - otherwise what a cold fit does.
//!
//! A refit's data are then what `fit_structure` gives on the same input, except that a move
//! started from a nearby delay settles on the maximum of the delay's cell, the scan's own when
//! the delay stayed in its lobe (a refit on other data is marked not from scratch anyway,
//! `warm`, and the app polishes it cold). Units and contracts are the module's; no NaN is kept
//! (a non-finite settled delay is not used as a start).

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::model::Prepared;
use super::weights::{RowWeight, row_weights};
use super::{ResponseEstimate, StructuralError, StructuralSettings, Weights};

/// The input as given, copied.
#[derive(Clone, Debug, PartialEq)]
struct KeptInput {
    frequency_hz: Arc<[f64]>,
    response: Arc<[Matrix3<Complex64>]>,
    offset_hz: Option<Arc<[Matrix3<Complex64>]>>,
    weights: KeptWeights,
}

/// [`Weights`], copied.
#[derive(Clone, Debug, PartialEq)]
enum KeptWeights {
    Variance(Arc<[Matrix3<f64>]>),
    RowWeight(Arc<[[Matrix3<Complex64>; 3]]>),
}

/// The settings that decide the placed data (the move's delay range and passes, the narrowing).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PlacingSettings {
    tau_min_s: f64,
    tau_max_s: f64,
    bin_correlation: f64,
    narrow_to_scatter: bool,
    aligned_s: f64,
}

impl PlacingSettings {
    fn of(s: &StructuralSettings) -> Self {
        // Every field named: a new setting must be placed here or said not to place.
        let StructuralSettings {
            tau_min_s,
            tau_max_s,
            bin_correlation,
            narrow_to_scatter,
            aligned_s,
            max_iterations: _,
            criterion: _,
            held_out_chi2: _,
        } = *s;
        Self {
            tau_min_s,
            tau_max_s,
            bin_correlation,
            narrow_to_scatter,
            aligned_s,
        }
    }

    /// Equal bit for bit (a NaN setting equals itself: the fit refuses it the same way).
    fn same(&self, other: &Self) -> bool {
        let bits = |s: &Self| [s.tau_min_s, s.tau_max_s, s.bin_correlation, s.aligned_s].map(f64::to_bits);
        bits(self) == bits(other) && self.narrow_to_scatter == other.narrow_to_scatter
    }
}

/// Whether two sequences of numbers are equal bit for bit.
fn same_bits(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> bool {
    a.map(f64::to_bits).eq(b.map(f64::to_bits))
}

/// The numbers of complex matrices, in order.
fn complex_parts<'m, const R: usize>(
    m: impl Iterator<Item = &'m nalgebra::SMatrix<Complex64, R, R>>,
) -> impl Iterator<Item = f64> {
    m.flat_map(|m| m.iter().flat_map(|z| [z.re, z.im]))
}

impl KeptInput {
    fn of(input: &ResponseEstimate) -> Self {
        Self {
            frequency_hz: Arc::from(input.frequency_hz),
            response: Arc::from(input.response),
            offset_hz: input.offset_hz.map(Arc::from),
            weights: match input.weights {
                Weights::Variance(v) => KeptWeights::Variance(Arc::from(v)),
                Weights::RowWeight(m) => KeptWeights::RowWeight(Arc::from(m)),
            },
        }
    }

    /// Whether `weights` are these, bit for bit.
    fn same_weights(&self, weights: Weights) -> bool {
        match (weights, &self.weights) {
            (Weights::Variance(v), KeptWeights::Variance(kept)) => {
                v.len() == kept.len()
                    && same_bits(
                        v.iter().flat_map(|m| m.iter().copied()),
                        kept.iter().flat_map(|m| m.iter().copied()),
                    )
            }
            (Weights::RowWeight(m), KeptWeights::RowWeight(kept)) => {
                m.len() == kept.len()
                    && same_bits(
                        complex_parts(m.iter().flatten()),
                        complex_parts(kept.iter().flatten()),
                    )
            }
            _ => false,
        }
    }

    /// Whether `input`'s frequencies, response and offsets are these, bit for bit.
    fn same_estimate(&self, input: &ResponseEstimate) -> bool {
        let offsets = match (input.offset_hz, &self.offset_hz) {
            (None, None) => true,
            (Some(g), Some(kept)) => {
                g.len() == kept.len() && same_bits(complex_parts(g.iter()), complex_parts(kept.iter()))
            }
            _ => false,
        };
        offsets
            && input.frequency_hz.len() == self.frequency_hz.len()
            && input.response.len() == self.response.len()
            && same_bits(
                input.frequency_hz.iter().copied(),
                self.frequency_hz.iter().copied(),
            )
            && same_bits(
                complex_parts(input.response.iter()),
                complex_parts(self.response.iter()),
            )
    }
}

/// An input's placed data (module docs).
pub(super) struct Placed {
    input: KeptInput,
    settings: PlacingSettings,
    /// The input's own validated row weights (before any narrowing).
    rows: Arc<[[RowWeight; 3]]>,
    /// The data the orders are fitted to.
    pub data: Prepared,
    /// The move's settled order-0 delay, s (`None`: not moved).
    moved_tau_s: Option<f64>,
}

impl std::fmt::Debug for Placed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Placed")
            .field("bins", &self.data.bins())
            .field("fingerprint", &self.data.fingerprint())
            .field("moved_tau_s", &self.moved_tau_s)
            .finish_non_exhaustive()
    }
}

/// Equal when they place the same data the same way (the data's fingerprint, the settings and
/// the move's delay).
impl PartialEq for Placed {
    fn eq(&self, other: &Self) -> bool {
        self.settings.same(&other.settings)
            && self.data.fingerprint() == other.data.fingerprint()
            && self.moved_tau_s.map(f64::to_bits) == other.moved_tau_s.map(f64::to_bits)
    }
}

impl Placed {
    /// `input` (validated by the caller) placed as a cold fit places it.
    ///
    /// # Errors
    /// Those of `weights::row_weights` and `contract::prepare`.
    pub(super) fn new(
        input: &ResponseEstimate,
        settings: &StructuralSettings,
    ) -> Result<Arc<Self>, StructuralError> {
        let rows = Arc::from(row_weights(&input.weights)?);
        Self::place(input, rows, settings, None)
    }

    /// `input` (validated by the caller) placed from `previous` (module docs).
    ///
    /// # Errors
    /// Those of [`Self::new`].
    pub(super) fn again(
        previous: &Arc<Self>,
        input: &ResponseEstimate,
        settings: &StructuralSettings,
    ) -> Result<Arc<Self>, StructuralError> {
        let same_settings = previous.settings.same(&PlacingSettings::of(settings));
        let same_weights = previous.input.same_weights(input.weights);
        if same_settings && same_weights && previous.input.same_estimate(input) {
            return Ok(Arc::clone(previous));
        }
        let rows = if same_weights {
            Arc::clone(&previous.rows)
        } else {
            Arc::from(row_weights(&input.weights)?)
        };
        let near = previous.moved_tau_s.filter(|_| same_settings && same_weights);
        Self::place(input, rows, settings, near)
    }

    fn place(
        input: &ResponseEstimate,
        rows: Arc<[[RowWeight; 3]]>,
        settings: &StructuralSettings,
        near: Option<f64>,
    ) -> Result<Arc<Self>, StructuralError> {
        let (data, moved_tau_s) = super::align::prepared(input, Arc::clone(&rows), settings, near)?;
        Ok(Arc::new(Self {
            input: KeptInput::of(input),
            settings: PlacingSettings::of(settings),
            rows,
            data,
            moved_tau_s: moved_tau_s.filter(|t| t.is_finite()),
        }))
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::Placed;
    use crate::ident::structural::weights::row_weights;
    use crate::ident::structural::{ResponseEstimate, StructuralSettings, Weights, rational_response};
    use crate::rng::Rng;

    const BINS: usize = 120;

    /// A delayed gain's estimate with noise, its columns off their bins by up to 0.1 Hz, full
    /// Hermitian row weights `A A^H + I / 2` over the noise's variance times `weight` (below about
    /// 0.1 they overstate the scatter and are narrowed), and the diagonal variances of the same
    /// size.
    struct Case {
        f: Vec<f64>,
        response: Vec<Matrix3<Complex64>>,
        offsets: Vec<Matrix3<Complex64>>,
        weights: Vec<[Matrix3<Complex64>; 3]>,
        variance: Vec<Matrix3<f64>>,
    }

    fn case(seed: u64, weight: f64) -> Case {
        let mut rng = Rng::new(seed);
        let k = [[1.01, 0.02, -0.015], [0.01, 0.99, 0.02], [-0.02, 0.005, 1.0]];
        let f: Vec<f64> = (1..=BINS).map(|b| 0.15 * b as f64).collect();
        let d: Vec<[f64; 3]> = (0..BINS)
            .map(|_| [0; 3].map(|_| rng.uniform_in(-0.1, 0.1)))
            .collect();
        let noise = 1e-3;
        let response = f
            .iter()
            .zip(&d)
            .map(|(&fc, dj)| {
                Matrix3::from_fn(|i, j| {
                    rational_response(&[k], &[], 0.0042, fc + dj[j])[(i, j)]
                        + Complex64::new(rng.normal(), rng.normal()) * noise
                })
            })
            .collect();
        let offsets = d
            .iter()
            .map(|dj| Matrix3::from_diagonal(&nalgebra::Vector3::from(dj.map(Complex64::from))))
            .collect();
        let weights = (0..BINS)
            .map(|_| {
                [0; 3].map(|_| {
                    let a = Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()));
                    (a * a.adjoint() + Matrix3::identity() * Complex64::from(0.5))
                        * Complex64::from(weight / (noise * noise))
                })
            })
            .collect();
        Case {
            f,
            response,
            offsets,
            weights,
            variance: vec![Matrix3::from_element(noise * noise); BINS],
        }
    }

    impl Case {
        fn input(&self) -> ResponseEstimate<'_> {
            ResponseEstimate {
                frequency_hz: &self.f,
                response: &self.response,
                weights: Weights::RowWeight(&self.weights),
                offset_hz: Some(&self.offsets),
            }
        }
    }

    fn largest_difference(a: &Placed, b: &Placed) -> (f64, f64) {
        let h = a
            .data
            .h
            .iter()
            .flatten()
            .zip(b.data.h.iter().flatten())
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max);
        let w = a
            .data
            .rows
            .iter()
            .flatten()
            .zip(b.data.rows.iter().flatten())
            .map(|(x, y)| (x.omega - y.omega).norm() / y.omega.norm())
            .fold(0.0, f64::max);
        (h, w)
    }

    /// The same input again is the same placing. Its weights overstate the scatter and are
    /// narrowed: the rows kept are the input's own, not the narrowed ones the data carry.
    #[test]
    fn the_same_input_is_placed_once() {
        let c = case(3, 0.02);
        let settings = StructuralSettings::default();
        let first = Placed::new(&c.input(), &settings).unwrap();
        let again = Placed::again(&first, &c.input(), &settings).unwrap();
        assert!(Arc::ptr_eq(&first, &again));
        assert!(first.moved_tau_s.is_some_and(|t| (t - 0.0042).abs() < 1e-5));
        let own = row_weights(&c.input().weights).unwrap();
        assert_eq!(&first.rows[..], &own[..]);
        assert_ne!(&first.data.rows[..], &own[..], "narrowed");
    }

    /// A changed estimate on the same weights (a change of Lambda) keeps the validated rows and
    /// moves from the last delay: the data (narrowed weights included) are the cold placing's
    /// within the move's settling, and the delay too.
    #[test]
    fn a_changed_estimate_keeps_the_rows_and_moves_from_the_last_delay() {
        let c = case(4, 0.02);
        let settings = StructuralSettings::default();
        let first = Placed::new(&c.input(), &settings).unwrap();
        let mut changed = case(4, 0.02);
        for m in &mut changed.response {
            *m *= Complex64::from(0.998);
        }
        let again = Placed::again(&first, &changed.input(), &settings).unwrap();
        let cold = Placed::new(&changed.input(), &settings).unwrap();
        assert!(!Arc::ptr_eq(&first, &again));
        assert!(Arc::ptr_eq(&first.rows, &again.rows), "the rows are reused");
        assert_ne!(&cold.data.rows[..], &cold.rows[..], "narrowed");
        let (dh, dw) = largest_difference(&again, &cold);
        assert!(dh < 1e-9, "{dh:e}");
        assert!(dw < 1e-9, "{dw:e}");
        let (tau, tau_cold) = (again.moved_tau_s.unwrap(), cold.moved_tau_s.unwrap());
        assert!(
            (tau - tau_cold).abs() * cold.data.omega_ref < 1e-5,
            "{tau} {tau_cold}"
        );
        // Not the first placing's data: the change is there.
        assert!(largest_difference(&again, &first).0 > 1e-4);
    }

    /// Anything else that places the data changed (the weights, their form, the offsets, the
    /// delay range, the bins' correlation, the alignment, the narrowing) is placed as a cold fit
    /// places it, bit for bit, and not taken from the previous placing (which a wider delay range
    /// holding the same maximum may equal).
    #[test]
    fn whatever_else_changed_is_placed_cold() {
        let c = case(5, 0.02);
        let settings = StructuralSettings::default();
        let first = Placed::new(&c.input(), &settings).unwrap();
        // Another shape, not only another size (narrowing undoes a common factor).
        let mut heavier = case(5, 0.02);
        for w in heavier.weights.iter_mut().flatten() {
            *w += Matrix3::identity() * Complex64::from(0.5 * w[(0, 0)].re);
        }
        let mut shifted = case(5, 0.02);
        for g in &mut shifted.offsets {
            *g *= Complex64::from(0.5);
        }
        let variance = ResponseEstimate {
            weights: Weights::Variance(&c.variance),
            ..c.input()
        };
        let cases: [(&str, ResponseEstimate, StructuralSettings); 7] = [
            ("weights", heavier.input(), settings),
            ("variances", variance, settings),
            ("offsets", shifted.input(), settings),
            (
                "delay range",
                c.input(),
                StructuralSettings {
                    tau_max_s: settings.tau_max_s * 2.0,
                    ..settings
                },
            ),
            (
                "correlation",
                c.input(),
                StructuralSettings {
                    bin_correlation: 2.0,
                    ..settings
                },
            ),
            (
                "alignment",
                c.input(),
                StructuralSettings {
                    aligned_s: 0.001,
                    ..settings
                },
            ),
            (
                "narrowing",
                c.input(),
                StructuralSettings {
                    narrow_to_scatter: false,
                    ..settings
                },
            ),
        ];
        for (what, input, settings) in cases {
            let again = Placed::again(&first, &input, &settings).unwrap();
            let cold = Placed::new(&input, &settings).unwrap();
            assert!(!Arc::ptr_eq(&first, &again), "{what}");
            assert_eq!(again.data.fingerprint(), cold.data.fingerprint(), "{what}");
            assert_eq!(
                again.moved_tau_s.map(f64::to_bits),
                cold.moved_tau_s.map(f64::to_bits),
                "{what}"
            );
            assert_eq!(&again.rows[..], &cold.rows[..], "{what}");
        }
    }
}
