//! Estimates whose columns lie off their bin's frequency: the model compared where the estimate
//! was measured.
//!
//! An `H1` estimate at a bin is the response at the bin's input power centroid `f` only when the
//! three inputs' power lies there together. A stand's sines on different axes put each column at
//! its own line: to first order the estimate is `W(f) + W'(f) G`, with `G` the bin's offset matrix
//! (Hz, `spectral::centroid`, "Offset matrix") and `W' = dW/df`. A model compared at `f` alone
//! then misses by `W'(f) G`: for a delay `tau`, a phase of `2 pi (f_line - f) tau`, hundreds of
//! standard deviations at a strong line, read as a poor fit.
//!
//! [`moved_estimate`] removes it before the fit: the estimate is moved to `f` with the order-0
//! fit's slope, `H - W'(f) G`, and the order-0 model (gain and delay, `gain_delay`) is fitted
//! again on the moved estimate until its delay settles (a change that turns the phase at the
//! band's top by less than [`SETTLED_RAD`], at most [`PASSES`] times; a failed pass keeps the last
//! move). The orders are then fitted to the
//! moved estimate as to any other. The move depends on the data and the placing settings (delay
//! range, bins' correlation, alignment, narrowing; `super::placed`), not on the order asked: a
//! refit for another order finds the same moved data (`super::warm`'s "same data"), and a cold
//! fit is what [`super::fit_structure`] gives on them. What is left is the
//! chosen model's slope less the order-0 slope, times `G`: the poles' own phase slope over a
//! fraction of a bin, second order. The settled order-0 model's residual also tells where the
//! weights overstate the estimate's scatter: there they are narrowed to it (`super::scatter`,
//! the rows divided by a scale: their eigen decompositions are not made again). A refit on
//! nearby data (`super::placed`) starts the move's first order-0 fit from the last settled delay
//! instead of the scan (`gain_delay::fit_near`, which scans when the delay left its scan cell).
//! Without offsets (`ResponseEstimate::offset_hz` `None`) nothing changes.
//!
//! Units: Hz for `f` and `G`, `W'` per Hz.

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::model::Prepared;
use super::weights::RowWeight;
use super::{ResponseEstimate, StructuralError, StructuralFit, StructuralSettings, prepare};

/// The most order-0 refits on a moved estimate.
const PASSES: usize = 3;

/// A pass whose delay change turns the phase at the band's top by less than this ends the
/// passes, rad.
const SETTLED_RAD: f64 = 1e-6;

/// `dW/df` of `N(s) / d(s) e^(-tau s)` at `f_hz`, per Hz (`s = j 2 pi f`), with the delay's own
/// slope for `tau_s - aligned_s` only (the part of the delay an aligned estimate smears,
/// `StructuralSettings::aligned_s`; 0: the whole slope).
#[must_use]
pub fn rational_slope(
    numerator: &[[[f64; 3]; 3]],
    denominator: &[f64],
    tau_s: f64,
    aligned_s: f64,
    f_hz: f64,
) -> Matrix3<Complex64> {
    let ds = Complex64::new(0.0, 2.0 * std::f64::consts::PI);
    let s = ds * f_hz;
    // d(s) and d'(s).
    let (mut d, mut d1) = (Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0));
    let (mut p, mut p1) = (s, Complex64::new(1.0, 0.0));
    for (m, dm) in denominator.iter().enumerate() {
        d += p * dm;
        d1 += p1 * dm * (m + 1) as f64;
        p *= s;
        p1 *= s;
    }
    let delay = (-s * tau_s).exp();
    Matrix3::from_fn(|i, j| {
        let (mut n, mut n1) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
        let (mut p, mut p1) = (Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0));
        for (m, nm) in numerator.iter().enumerate() {
            n += p * nm[i][j];
            n1 += p1 * nm[i][j] * m as f64;
            p1 = p;
            p *= s;
        }
        let ratio = n / d;
        (n1 / d - n * d1 / (d * d) - ratio * (tau_s - aligned_s)) * delay * ds
    })
}

impl StructuralFit {
    /// The model as an estimate whose columns lie at offsets `offset_hz` about `f_hz` sees it,
    /// `W(f) + W'(f) G` (module docs; the delay's slope less `aligned_s`, [`rational_slope`]);
    /// `W(f)` without an offset.
    #[must_use]
    pub fn response_seen(
        &self,
        f_hz: f64,
        offset_hz: Option<&Matrix3<Complex64>>,
        aligned_s: f64,
    ) -> Matrix3<Complex64> {
        let at = self.response(f_hz);
        match offset_hz {
            Some(g) => {
                at + rational_slope(&self.numerator, &self.denominator, self.tau_s, aligned_s, f_hz) * g
            }
            None => at,
        }
    }
}

/// `input`'s estimate moved to its bins' frequencies by the order-0 model `K e^(-tau s)`:
/// `H - W'(f) G` per bin, `W'(f) = -j 2 pi (tau - aligned) K e^(-j 2 pi f tau)` (the slope of
/// the delay the estimate smears, `StructuralSettings::aligned_s`).
fn moved(
    input: &ResponseEstimate,
    offsets: &[Matrix3<Complex64>],
    k: &[f64; super::model::ELEMENTS],
    tau: f64,
    aligned: f64,
) -> Vec<Matrix3<Complex64>> {
    let gain = Matrix3::from_fn(|i, j| Complex64::from(k[3 * i + j]));
    input
        .response
        .iter()
        .zip(input.frequency_hz)
        .zip(offsets)
        .map(|((h, &f), g)| {
            let phase = -2.0 * std::f64::consts::PI * f * tau;
            let slope = Complex64::new(0.0, -2.0 * std::f64::consts::PI * (tau - aligned))
                * Complex64::from_polar(1.0, phase);
            h - gain * slope * g
        })
        .collect()
}

/// An estimate moved to its bins (module docs) and its weights narrowed to the settled order-0
/// model's scatter (`super::scatter`; `None`: as given).
struct Aligned {
    response: Vec<Matrix3<Complex64>>,
    rows: Option<Vec<[RowWeight; 3]>>,
    /// The settled order-0 fit's delay, s.
    tau: f64,
}

/// `input` moved to its bins (the module docs; as it is without offsets) and prepared with its
/// validated row weights `rows` (`super::weights::row_weights` of `input.weights`), narrowed where
/// the settled order-0 fit's residual scatters less than they say: what every fit starts from
/// (`super::placed`). The move's first order-0 fit starts from `near` (a delay from a fit to
/// nearby data, `gain_delay::fit_near`) or scans the delay range; the settled delay of the move
/// is returned beside the data (`None` without a move).
///
/// # Errors
/// Those of [`prepare`].
pub(super) fn prepared(
    input: &ResponseEstimate,
    rows: Arc<[[RowWeight; 3]]>,
    settings: &StructuralSettings,
    near: Option<f64>,
) -> Result<(Prepared, Option<f64>), StructuralError> {
    match moved_estimate(input, &rows, settings, near) {
        Some(aligned) => {
            let at = ResponseEstimate {
                response: &aligned.response,
                offset_hz: None,
                ..*input
            };
            let rows = aligned.rows.map_or(rows, Arc::from);
            Ok((prepare(&at, rows, settings)?, Some(aligned.tau)))
        }
        None => Ok((prepare(input, rows, settings)?, None)),
    }
}

/// `input`'s estimate moved to its bins' frequencies by the settled order-0 fit (module docs),
/// with its row weights `rows` narrowed where that fit's residual scatters less than they say
/// (`super::scatter`); `None` without offsets, or when no finite order-0 fit can be made (the
/// orders' own fits then say why).
fn moved_estimate(
    input: &ResponseEstimate,
    rows: &Arc<[[RowWeight; 3]]>,
    settings: &StructuralSettings,
    near: Option<f64>,
) -> Option<Aligned> {
    let offsets = input.offset_hz?;
    // The model alone (gain and delay, no deviations) is what the move needs; the weights are
    // the input's throughout, and each pass starts from the last delay.
    let (lo, hi) = (settings.tau_min_s, settings.tau_max_s);
    let correlation = settings.bin_correlation;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return None;
    }
    let order0 = |response: &[Matrix3<Complex64>], near: Option<f64>| {
        let at = ResponseEstimate {
            response,
            offset_hz: None,
            ..*input
        };
        let data = Prepared::new(&at, Arc::clone(rows));
        let model = match near {
            Some(near) => super::gain_delay::fit_near(&data, near, lo, hi, correlation),
            None => super::gain_delay::fit(&data, lo, hi, correlation),
        };
        let finite = model.tau.is_finite() && model.num.first()?.iter().all(|v| v.is_finite());
        finite.then_some((model, data))
    };
    let (mut model, mut data) = order0(input.response, near.filter(|t| t.is_finite()))?;
    let mut response = moved(input, offsets, &model.num[0], model.tau, settings.aligned_s);
    for _ in 0..PASSES {
        let Some((next, next_data)) = order0(&response, Some(model.tau)) else {
            break;
        };
        // Settled when the delay's change turns the band's top by less than `SETTLED_RAD`: the
        // move changes by less than that fraction of itself.
        let settled = (next.tau - model.tau).abs() * next_data.omega_ref <= SETTLED_RAD;
        (model, data) = (next, next_data);
        response = moved(input, offsets, &model.num[0], model.tau, settings.aligned_s);
        if settled {
            break;
        }
    }
    // The settled model's scatter on the response it was fitted to (the last pass's).
    let rows = match input.weights {
        super::Weights::RowWeight(_) if settings.narrow_to_scatter => super::scatter::narrowed(
            rows,
            &model.chi2_rows(&data),
            super::model::parameter_count(0),
            settings.bin_correlation,
        ),
        _ => None,
    };
    Some(Aligned {
        response,
        rows,
        tau: model.tau,
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::rational_slope;
    use crate::ident::structural::{
        OrderChoice, ResponseEstimate, StructuralError, StructuralSettings, Weights, fit_structure,
        rational_response, refit_structure,
    };
    use crate::rng::Rng;

    /// The analytic slope against a central difference of the response (orders 0 and 2).
    #[test]
    fn the_slope_is_the_response_s_derivative() {
        let num = [
            [[1.0, 0.02, -0.01], [0.0, 0.97, 0.03], [0.01, 0.0, 1.02]],
            [[1e-3, 0.0, 2e-4], [0.0, 8e-4, 0.0], [-1e-4, 0.0, 9e-4]],
        ];
        for (numerator, denominator) in [(&num[..1], &[][..]), (&num[..], &[3e-3, 4e-6][..])] {
            for f in [0.3, 4.0, 17.5, 60.0] {
                let h = 1e-5 * f;
                let diff = (rational_response(numerator, denominator, 0.0042, f + h)
                    - rational_response(numerator, denominator, 0.0042, f - h))
                    / Complex64::from(2.0 * h);
                let slope = rational_slope(numerator, denominator, 0.0042, 0.0, f);
                assert!(
                    (diff - slope).norm() < 1e-7 * slope.norm().max(1e-3),
                    "{f} Hz: {:e}",
                    (diff - slope).norm()
                );
            }
        }
    }

    /// Columns measured at their own frequencies (each at `f_c + d_j`, `|d_j|` up to 0.1 Hz, the
    /// exact response there): compared at `f_c` the fit is biased and its chi2 enormous; with the
    /// offsets `G = diag(d_j)` it recovers `K` and `tau`, and chi2 is left with the second order.
    #[test]
    fn columns_at_their_own_frequencies_are_fitted_where_they_lie() {
        let mut rng = Rng::new(17);
        let k = [[1.01, 0.02, -0.015], [0.01, 0.99, 0.02], [-0.02, 0.005, 1.0]];
        let tau = 0.0042;
        let bins = 150;
        let f: Vec<f64> = (1..=bins).map(|b| 0.12 * b as f64).collect();
        let d: Vec<[f64; 3]> = (0..bins)
            .map(|_| [0; 3].map(|_| rng.uniform_in(-0.1, 0.1)))
            .collect();
        let response: Vec<Matrix3<Complex64>> = f
            .iter()
            .zip(&d)
            .map(|(&fc, dj)| Matrix3::from_fn(|i, j| rational_response(&[k], &[], tau, fc + dj[j])[(i, j)]))
            .collect();
        let offsets: Vec<Matrix3<Complex64>> = d
            .iter()
            .map(|dj| Matrix3::from_diagonal(&nalgebra::Vector3::from(dj.map(Complex64::from))))
            .collect();
        let variance = vec![Matrix3::from_element(1e-8); bins];
        let input = |offset_hz| ResponseEstimate {
            frequency_hz: &f,
            response: &response,
            weights: Weights::Variance(&variance),
            offset_hz,
        };
        let settings = StructuralSettings::default();
        let at_centres = fit_structure(&input(None), OrderChoice::Fixed(0), &settings).unwrap();
        let aligned = fit_structure(&input(Some(&offsets)), OrderChoice::Fixed(0), &settings).unwrap();
        let per_dof = |fit: &crate::ident::structural::StructuralFit| fit.chi2 / fit.dof as f64;
        assert!(per_dof(&at_centres) > 20.0, "{}", per_dof(&at_centres));
        assert!(per_dof(&aligned) < 0.01, "{}", per_dof(&aligned));
        assert!((aligned.tau_s - tau).abs() < 1e-8, "{}", aligned.tau_s);
        let dk = (0..9)
            .map(|e| (aligned.k[e / 3][e % 3] - k[e / 3][e % 3]).abs())
            .fold(0.0, f64::max);
        assert!(dk < 1e-5, "{dk:e}");
        assert!(aligned.fitted.from_scratch(), "a cold fit on the moved estimate");
        // `Auto` on the same data chooses order 0: the offsets leave no misfit for poles to take.
        let auto = fit_structure(&input(Some(&offsets)), OrderChoice::Auto, &settings).unwrap();
        assert_eq!(auto.order, 0);
        // The move does not depend on the order asked: a refit for another order is `warm`'s
        // "same data", bit for bit the cold fit of that order, and from scratch.
        for order in [OrderChoice::Fixed(0), OrderChoice::Fixed(1)] {
            let refit = refit_structure(&input(Some(&offsets)), order, &settings, &auto).unwrap();
            let cold = fit_structure(&input(Some(&offsets)), order, &settings).unwrap();
            assert!(refit.fitted.from_scratch(), "{order:?}");
            assert_eq!(refit.tau_s.to_bits(), cold.tau_s.to_bits(), "{order:?}");
            assert_eq!(refit.k, cold.k, "{order:?}");
            assert_eq!(refit.chi2.to_bits(), cold.chi2.to_bits(), "{order:?}");
        }
    }

    /// Offsets that are not one per bin, or not finite, are refused naming the bin.
    #[test]
    fn bad_offsets_are_refused() {
        let f = [1.0, 2.0];
        let response = [Matrix3::identity(); 2];
        let variance = [Matrix3::from_element(1e-6); 2];
        let settings = StructuralSettings::default();
        let fit = |offsets: &[Matrix3<Complex64>]| {
            fit_structure(
                &ResponseEstimate {
                    frequency_hz: &f,
                    response: &response,
                    weights: Weights::Variance(&variance),
                    offset_hz: Some(offsets),
                },
                OrderChoice::Fixed(0),
                &settings,
            )
        };
        assert_eq!(
            fit(&[Matrix3::zeros()]).unwrap_err(),
            StructuralError::OffsetMismatch {
                offsets: 1,
                frequencies: 2
            }
        );
        let mut nan = [Matrix3::zeros(); 2];
        nan[1][(2, 0)] = Complex64::new(f64::NAN, 0.0);
        assert_eq!(
            fit(&nan).unwrap_err(),
            StructuralError::NonFiniteOffset { bin: 1 }
        );
    }
}
