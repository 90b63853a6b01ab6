//! The delay's phase factors `e^(-j w_k tau)` over the fit's bins, without a `sin_cos` per bin.
//!
//! The structural fit evaluates them for every trial delay (the Levenberg–Marquardt loop and the
//! gain–delay line search), and their `sin_cos` was the largest single cost of a short run's
//! identification. The fit's bins are native Welch bins, equally spaced, so `e^(-j w_(k+1) tau)`
//! is `e^(-j w_k tau) e^(-j dw tau)`: one complex product per bin. The product's rounding grows by
//! about one ulp per step, so the exact value is recomputed every [`RESYNC`] bins (error below
//! `RESYNC * 2^-52`, about 1e-14). Bins that are not equally spaced (to [`SPACING_TOLERANCE`]) get
//! the exact value every time.
//!
//! Units: rad/s and s. Empty `omega`: no factors.

use num_complex::Complex64;

/// Bins between exact evaluations.
pub(super) const RESYNC: usize = 32;

/// Largest relative departure of a spacing from the mean spacing of "equally spaced" bins.
const SPACING_TOLERANCE: f64 = 1e-9;

/// The common spacing of `omega` when its bins are equally spaced (and there are at least two).
pub(super) fn uniform_step(omega: &[f64]) -> Option<f64> {
    let (first, last) = (*omega.first()?, *omega.last()?);
    if omega.len() < 2 {
        return None;
    }
    let step = (last - first) / (omega.len() - 1) as f64;
    let uniform = step > 0.0
        && omega
            .windows(2)
            .all(|p| ((p[1] - p[0]) - step).abs() <= SPACING_TOLERANCE * step);
    uniform.then_some(step)
}

/// `e^(-j omega_k tau)` for each bin, in order.
pub(super) struct Phasors<'a> {
    omega: &'a [f64],
    tau: f64,
    /// `e^(-j dw tau)` for equally spaced bins.
    step: Option<Complex64>,
    k: usize,
    z: Complex64,
}

impl<'a> Phasors<'a> {
    /// The factors over `omega` (of common spacing `step`, from [`uniform_step`]) for delay `tau`.
    pub fn new(omega: &'a [f64], step: Option<f64>, tau: f64) -> Self {
        Self {
            omega,
            tau,
            step: step.map(|dw| Complex64::from_polar(1.0, -dw * tau)),
            k: 0,
            z: Complex64::new(1.0, 0.0),
        }
    }
}

impl Iterator for Phasors<'_> {
    type Item = Complex64;

    fn next(&mut self) -> Option<Complex64> {
        let &omega = self.omega.get(self.k)?;
        self.z = match self.step {
            Some(step) if !self.k.is_multiple_of(RESYNC) => self.z * step,
            _ => Complex64::from_polar(1.0, -omega * self.tau),
        };
        self.k += 1;
        Some(self.z)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.omega.len() - self.k;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Phasors<'_> {}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `from_polar` per bin: equally spaced bins (long enough for several resyncs, large
    /// phases) and unequally spaced ones.
    #[test]
    fn phasors_match_the_exact_factors() {
        let dw = 2.0 * std::f64::consts::PI * 0.0610;
        let uniform: Vec<f64> = (7..1500).map(|k| f64::from(k) * dw).collect();
        let mut uneven = uniform.clone();
        uneven[100] += 0.3 * dw;
        for (omega, equal) in [(&uniform, true), (&uneven, false)] {
            let step = uniform_step(omega);
            assert_eq!(step.is_some(), equal);
            for tau in [0.0, 4.2e-3, -0.37, 12.5] {
                let got: Vec<Complex64> = Phasors::new(omega, step, tau).collect();
                assert_eq!(got.len(), omega.len());
                for (z, &w) in got.iter().zip(omega.iter()) {
                    let exact = Complex64::from_polar(1.0, -w * tau);
                    // The argument `w tau` itself is only known to about `|w tau|` ulps.
                    let tolerance = 1e-14 * (1.0 + (w * tau).abs());
                    assert!((z - exact).norm() < tolerance, "tau {tau}, w {w}: {z} vs {exact}");
                }
            }
        }
        assert_eq!(uniform_step(&[]), None);
        assert_eq!(uniform_step(&[3.0]), None);
        assert_eq!(uniform_step(&[3.0, 3.0]), None);
    }
}
