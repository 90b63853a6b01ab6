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
//! [`realigned`] removes it: the estimate is moved to `f` with the model fitted so far,
//! `H - W'(f) G`, and fitted again from that model, until the delay settles (within
//! [`SETTLED`] of its standard deviation, at most [`PASSES`] times). The move is the fitted
//! model's slope times the offset, so an error `dW` in the model leaves `dW' G`: second order.
//! Without offsets (`ResponseEstimate::offset_hz` `None`) nothing changes.
//!
//! Units: Hz for `f` and `G`, `W'` per Hz.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::{OrderChoice, ResponseEstimate, StructuralError, StructuralFit, StructuralSettings};

/// The most refits on a moved estimate.
const PASSES: usize = 3;

/// A pass that moves the delay by less than this share of its standard deviation ends the passes.
const SETTLED: f64 = 0.01;

/// `dW/df` of `N(s) / d(s) e^(-tau s)` at `f_hz`, per Hz (`s = j 2 pi f`).
#[must_use]
pub fn rational_slope(
    numerator: &[[[f64; 3]; 3]],
    denominator: &[f64],
    tau_s: f64,
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
        (n1 / d - n * d1 / (d * d) - ratio * tau_s) * delay * ds
    })
}

impl StructuralFit {
    /// The model as an estimate whose columns lie at offsets `offset_hz` about `f_hz` sees it,
    /// `W(f) + W'(f) G` (module docs); `W(f)` without an offset.
    #[must_use]
    pub fn response_seen(&self, f_hz: f64, offset_hz: Option<&Matrix3<Complex64>>) -> Matrix3<Complex64> {
        let at = self.response(f_hz);
        match offset_hz {
            Some(g) => at + rational_slope(&self.numerator, &self.denominator, self.tau_s, f_hz) * g,
            None => at,
        }
    }
}

/// `input`'s estimate moved to its bins' frequencies by `fit`: `H - W'(f) G` per bin.
pub(super) fn moved(
    input: &ResponseEstimate,
    offsets: &[Matrix3<Complex64>],
    fit: &StructuralFit,
) -> Vec<Matrix3<Complex64>> {
    input
        .response
        .iter()
        .zip(input.frequency_hz)
        .zip(offsets)
        .map(|((h, &f), g)| h - rational_slope(&fit.numerator, &fit.denominator, fit.tau_s, f) * g)
        .collect()
}

/// `fit` (made on `input` as given) refitted on `input` moved to its bins' frequencies (module
/// docs); `fit` itself when `input` has no offsets.
///
/// # Errors
/// Those of [`super::refit_structure`] on the moved estimate.
pub(super) fn realigned(
    input: &ResponseEstimate,
    order: OrderChoice,
    settings: &StructuralSettings,
    mut fit: StructuralFit,
) -> Result<StructuralFit, StructuralError> {
    let Some(offsets) = input.offset_hz else {
        return Ok(fit);
    };
    // The passes are part of the fit: a cold fit with them is what `fit_structure` gives.
    let from_scratch = fit.fitted.from_scratch();
    for _ in 0..PASSES {
        let response = moved(input, offsets, &fit);
        let at_bins = ResponseEstimate {
            response: &response,
            offset_hz: None,
            ..*input
        };
        let next = super::refit_structure(&at_bins, order, settings, &fit)?;
        let settled = (next.tau_s - fit.tau_s).abs() <= SETTLED * next.tau_std_s;
        fit = next;
        if settled {
            break;
        }
    }
    fit.fitted.set_from_scratch(from_scratch);
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::rational_slope;
    use crate::ident::structural::{
        OrderChoice, ResponseEstimate, StructuralSettings, Weights, fit_structure, rational_response,
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
                let slope = rational_slope(numerator, denominator, 0.0042, f);
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
        assert!(
            aligned.fitted.from_scratch(),
            "a cold fit with its passes is a fit from scratch"
        );
        // `Auto` on the same data chooses order 0: the offsets leave no misfit for poles to take.
        let auto = fit_structure(&input(Some(&offsets)), OrderChoice::Auto, &settings).unwrap();
        assert_eq!(auto.order, 0);
    }
}
