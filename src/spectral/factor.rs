//! Minimum-phase spectral factorisation of matrix spectral densities (Wilson's algorithm).
//!
//! Given a Hermitian positive-semidefinite `D x D` density `S` on the two-sided FFT grid,
//! [`wilson`] finds `F` with `S(f) = F(f) F(f)^H` on every bin, `F` causal (its lag sequence,
//! see [`super::causal`], vanishes at negative lags) and minimum phase (`F^-1` causal too).
//! Such a factor is unique up to a constant unitary on the right; we fix it by requiring the
//! **lag-0 term `F(z = inf)` (= the mean of `F` over the grid) to be lower triangular with a real
//! positive diagonal**. For `D = 1` that is the usual scalar factor with `F(inf) > 0`.
//!
//! Method: G. T. Wilson (1972), "The factorization of matricial spectral densities", SIAM J. Appl.
//! Math. 23, in the frequency-domain form of Dhamala, Rangarajan & Ding (2008). It is Newton's
//! method on `S = psi psi^H`: starting from the constant `psi_0 = chol(R(0))` (`R(0)` the lag-0
//! covariance, i.e. the mean of `S` over the grid), each step writes `psi <- psi (I + Delta)` with
//! `Delta` causal and `Delta + Delta^H = g - I`, `g = psi^-1 S psi^-H`: `Delta` is the strictly
//! causal part of `g - I`, half of its Nyquist lag, and at lag 0 the lower triangle of the lag-0
//! term with half its diagonal (so that the lag-0 term of `psi` stays lower triangular with a
//! positive diagonal). Convergence is quadratic near the solution: 6-8 steps for well-conditioned
//! 3x3 densities, 11-17 with a 60 dB dynamic range or floored bins, from `N = 64` to `4096`.
//!
//! # Accuracy on a finite grid
//! The grid is periodic, so "causal" means "lags `0..N/2`". A factor whose impulse response (or
//! whose inverse's) decays like `rho^n` (`rho` = largest pole or zero radius) is recovered only up
//! to its wrap-around, about `rho^(N/2)` relative: pick `N` so that is negligible. Measured
//! (tests): `rho = 0.5`, `N = 64`: `1.4e-10`; `rho = 0.95`, `N = 256 / 1024 / 4096`:
//! `7.8e-4 / 3.3e-12 / 1e-13`; otherwise ~`1e-15`. A density whose periodic extension is not
//! smooth (e.g. a kink at Nyquist) has a slowly decaying cepstrum and no grid method resolves its
//! factor well: for `1 / (1 + (f / 0.125 fs)^8) + 1e-6` on `N = 2048` this and the cepstral method
//! differ by `1.4e-7` (for the smooth digital-Butterworth version of the same shape: `2e-12`).
//!
//! # Convergence
//! The iteration stops when the reconstruction error (against the floored density) or the largest
//! relative step falls to [`WilsonSettings::tolerance`]; either counts as converged (a small step
//! means `psi^-1 S psi^-H ~ I`, i.e. a whitened residual at rounding level, which for an
//! ill-conditioned density can leave a relative reconstruction error somewhat above the
//! tolerance: judge by [`SpectralFactor::reconstruction_error`]). If an iterate turns singular or
//! non-finite the iteration stops unconverged. The iterate with the smallest reconstruction error
//! is returned.
//!
//! # Conventions
//! - Grid of [`super::grid`]: `N` bins (`N` even) in FFT order; use the **two-sided** density (the
//!   factor of a one-sided density is wrong by `sqrt 2` in the interior).
//! - Units: `F` has the square root of the units of `S` (for a density in `x^2/Hz`: `x/sqrt(Hz)`).
//!
//! # Contracts
//! - Empty or odd-length input, a NaN/infinite entry, an all-zero bin, or a bin that is not
//!   Hermitian within [`WilsonSettings::hermitian_tolerance`] are errors ([`FactorError`], with the
//!   first offending bin); nothing panics and no NaN is returned.
//! - Near-singular bins are regularised (eigenvalues clamped up to a floor, reported), and
//!   non-convergence is reported in [`SpectralFactor`] rather than being an error.
//! - Allocation: the work arrays are allocated once per call; only bins that need the eigenvalue
//!   floor go through a (heap) `DMatrix` eigendecomposition, once, before the iteration.

use nalgebra::{DMatrix, SMatrix};
use num_complex::Complex64;

use super::causal::{CausalError, CausalProjector};

/// Settings of [`wilson`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WilsonSettings {
    /// Stop when the reconstruction error `max_f ||F F^H - S||_F / ||S||_F` (of the floored `S`) or
    /// the largest relative step `max_f ||F_new - F||_F / ||F||_F` falls to this. Default `1e-10`.
    pub tolerance: f64,
    /// Iteration cap (Newton steps). Default 500.
    pub max_iter: usize,
    /// Relative eigenvalue floor: on every bin, eigenvalues of `S(f)` below
    /// `eigen_floor * max_f trace S(f)` are raised to that floor. Default `1e-9`. Zero disables the
    /// regularisation (only negative eigenvalues are then raised to 0, and singular bins make the
    /// iteration stop unconverged).
    pub eigen_floor: f64,
    /// A bin fails as non-Hermitian when `||S - S^H||_F > hermitian_tolerance * ||S||_F`; bins
    /// within it are replaced by their Hermitian part `(S + S^H) / 2`. Default `1e-6`.
    pub hermitian_tolerance: f64,
}

impl Default for WilsonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iter: 500,
            eigen_floor: 1e-9,
            hermitian_tolerance: 1e-6,
        }
    }
}

/// Why a factorisation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FactorError {
    /// No bins at all.
    #[error("spectral density is empty")]
    Empty,
    /// The grid length is odd.
    #[error("spectral density has an odd number of bins ({len}); the two-sided grid needs N even")]
    OddLength {
        /// The number of bins given.
        len: usize,
    },
    /// A NaN or infinite entry.
    #[error("bin {bin} of the spectral density has a non-finite entry")]
    NonFinite {
        /// The first offending bin.
        bin: usize,
    },
    /// A bin that is exactly zero (no factor can be normalised there).
    #[error("bin {bin} of the spectral density is all zero")]
    ZeroBin {
        /// The first offending bin.
        bin: usize,
    },
    /// A bin whose anti-Hermitian part is too large.
    #[error("bin {bin} is not Hermitian: ||S - S^H|| / ||S|| = {asymmetry:e}")]
    NonHermitian {
        /// The first offending bin.
        bin: usize,
        /// Its relative asymmetry `||S - S^H||_F / ||S||_F`.
        asymmetry: f64,
    },
    /// A setting is out of range (negative, NaN, or a zero iteration cap).
    #[error("setting `{name}` = {value} is out of range")]
    BadSetting {
        /// The field of [`WilsonSettings`].
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The lag-0 covariance is not positive definite (only possible with `eigen_floor = 0`).
    #[error("the lag-0 covariance is not positive definite; set a positive eigen_floor")]
    SingularCovariance,
    /// A factor bin has no inverse.
    #[error("the factor is singular at bin {bin}")]
    SingularFactor {
        /// The first singular bin.
        bin: usize,
    },
    /// The causal projection refused the grid (cannot happen after the checks above).
    #[error(transparent)]
    Causal(#[from] CausalError),
}

/// A minimum-phase factor and how it was obtained.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralFactor<const D: usize> {
    /// `F` on the input's grid: `F F^H ~ S`, causal, minimum phase, lag-0 term lower triangular
    /// with a positive real diagonal.
    pub factor: Vec<SMatrix<Complex64, D, D>>,
    /// Newton steps taken.
    pub iterations: usize,
    /// Whether the tolerance was met (on the floored density) within `max_iter`.
    pub converged: bool,
    /// `max_f ||F F^H - S||_F / ||S||_F` against the **input** `S` (so it includes the floor's
    /// loading on near-singular bins).
    pub reconstruction_error: f64,
    /// Bins on which eigenvalues were raised to the floor.
    pub floored_bins: usize,
    /// The largest eigenvalue increase, `max_f (floor - lambda_min(S(f)))` over floored bins, in
    /// the units of `S` (0 if none).
    pub max_loading: f64,
    /// Whether the iteration started from a given factor ([`wilson_from`]) rather than from the
    /// lag-0 covariance.
    pub from_start: bool,
}

impl<const D: usize> SpectralFactor<D> {
    /// The lag-0 term `F(z = inf)`: the mean of the factor over the grid.
    #[must_use]
    pub fn zero_lag(&self) -> SMatrix<Complex64, D, D> {
        mean(&self.factor)
    }

    /// `F^-1` on every bin (causal too, since `F` is minimum phase).
    ///
    /// # Errors
    /// [`FactorError::SingularFactor`] with the first bin where `F` has no inverse.
    pub fn inverse(&self) -> Result<Vec<SMatrix<Complex64, D, D>>, FactorError> {
        self.factor
            .iter()
            .enumerate()
            .map(|(bin, f)| f.try_inverse().ok_or(FactorError::SingularFactor { bin }))
            .collect()
    }
}

/// Wilson's minimum-phase factor of the two-sided density `s` (see the module docs).
///
/// # Errors
/// [`FactorError::Empty`], [`FactorError::OddLength`], [`FactorError::NonFinite`],
/// [`FactorError::ZeroBin`], [`FactorError::NonHermitian`] for bad input (first bad bin);
/// [`FactorError::BadSetting`] for a negative or NaN tolerance/floor or `max_iter = 0`;
/// [`FactorError::SingularCovariance`] if `eigen_floor = 0` and the lag-0 covariance is singular.
/// Not converging within `max_iter` is *not* an error: see [`SpectralFactor::converged`].
pub fn wilson<const D: usize>(
    s: &[SMatrix<Complex64, D, D>],
    settings: &WilsonSettings,
) -> Result<SpectralFactor<D>, FactorError> {
    wilson_from(s, settings, None)
}

/// [`wilson`] started from `start`, the factor of a nearby density on the same grid (e.g. the
/// same spectra estimated with another Welch overlap): Newton's method then needs a few steps
/// instead of a dozen. The result reconstructs `s` as well as [`wilson`]'s does, but on a finite
/// grid the factor is only determined up to its residual non-causality, so it can differ from
/// [`wilson`]'s at that level (see the identifier's factorisation docs). A `start` of another
/// length or with a non-finite bin is not used (the iteration starts from the lag-0 covariance, as
/// [`wilson`] does); nor is its result when it does not converge (e.g. a singular bin): the
/// iteration is then redone from the lag-0 covariance. [`SpectralFactor::from_start`] says which.
///
/// # Errors
/// Those of [`wilson`].
pub fn wilson_from<const D: usize>(
    s: &[SMatrix<Complex64, D, D>],
    settings: &WilsonSettings,
    start: Option<&[SMatrix<Complex64, D, D>]>,
) -> Result<SpectralFactor<D>, FactorError> {
    check_settings(settings)?;
    let input = validated(s, settings.hermitian_tolerance)?;
    let mut projector = CausalProjector::new(input.len())?;
    let (floored, floored_bins, max_loading) = apply_floor(&input, settings.eigen_floor);
    let usable = start.filter(|f| {
        f.len() == input.len()
            && f.iter()
                .all(|m| m.iter().all(|z| z.re.is_finite() && z.im.is_finite()))
    });
    if let Some(start) = usable {
        let iterated = iterate(start.to_vec(), &floored, &mut projector, settings)?;
        if iterated.converged {
            return Ok(finish(iterated, &input, floored_bins, max_loading, true));
        }
    }
    let psi0 = cholesky_lower(&mean(&floored)).ok_or(FactorError::SingularCovariance)?;
    let iterated = iterate(vec![psi0; floored.len()], &floored, &mut projector, settings)?;
    Ok(finish(iterated, &input, floored_bins, max_loading, false))
}

/// The iterate of smallest reconstruction error, with the step count and the convergence flag.
struct Iterated<const D: usize> {
    best: Vec<SMatrix<Complex64, D, D>>,
    iterations: usize,
    converged: bool,
}

/// Normalises the best iterate and reports it against the input density.
fn finish<const D: usize>(
    iterated: Iterated<D>,
    input: &[SMatrix<Complex64, D, D>],
    floored_bins: usize,
    max_loading: f64,
    from_start: bool,
) -> SpectralFactor<D> {
    let mut best = iterated.best;
    normalise_zero_lag(&mut best);
    SpectralFactor {
        reconstruction_error: reconstruction_error(&best, input),
        factor: best,
        iterations: iterated.iterations,
        converged: iterated.converged,
        floored_bins,
        max_loading,
        from_start,
    }
}

/// Wilson's Newton steps from `psi` (causal, minimum phase) on the floored density.
fn iterate<const D: usize>(
    mut psi: Vec<SMatrix<Complex64, D, D>>,
    floored: &[SMatrix<Complex64, D, D>],
    projector: &mut CausalProjector,
    settings: &WilsonSettings,
) -> Result<Iterated<D>, FactorError> {
    let identity = SMatrix::<Complex64, D, D>::identity();
    let mut g = vec![identity; floored.len()];
    let mut best = psi.clone();
    let mut best_error = reconstruction_error(&psi, floored);
    let floored_norms: Vec<f64> = floored.iter().map(SMatrix::norm).collect();
    let (mut iterations, mut converged) = (0, best_error <= settings.tolerance);
    while !converged && iterations < settings.max_iter {
        // g - I = psi^-1 S psi^-H - I on every bin.
        let mut singular = false;
        for ((gk, pk), sk) in g.iter_mut().zip(&psi).zip(floored) {
            match pk.try_inverse() {
                Some(inv) => *gk = sandwich(&inv, sk) - identity,
                None => singular = true,
            }
        }
        if singular {
            break;
        }
        let lag0 = hermitian_part(&mean(&g));
        projector.strictly_causal_part(&mut g)?;
        let delta0 = lower_rule(&lag0);
        let (mut step, mut error) = (0.0_f64, 0.0_f64);
        for (((pk, dk), sk), s_norm) in psi.iter_mut().zip(&g).zip(floored).zip(&floored_norms) {
            let next = product(pk, &(identity + dk + delta0));
            step = step.max((next - *pk).norm() / pk.norm());
            error = error.max((outer(&next) - sk).norm() / s_norm);
            *pk = next;
        }
        iterations += 1;
        if !error.is_finite() {
            break;
        }
        if error < best_error {
            best_error = error;
            best.copy_from_slice(&psi);
        }
        converged = error <= settings.tolerance || step <= settings.tolerance;
    }

    Ok(Iterated {
        best,
        iterations,
        converged,
    })
}

fn check_settings(settings: &WilsonSettings) -> Result<(), FactorError> {
    for (name, value) in [
        ("tolerance", settings.tolerance),
        ("eigen_floor", settings.eigen_floor),
        ("hermitian_tolerance", settings.hermitian_tolerance),
    ] {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(FactorError::BadSetting { name, value });
        }
    }
    if settings.max_iter == 0 {
        return Err(FactorError::BadSetting {
            name: "max_iter",
            value: 0.0,
        });
    }
    Ok(())
}

/// The Hermitian parts of the bins, after the input checks of [`wilson`].
fn validated<const D: usize>(
    s: &[SMatrix<Complex64, D, D>],
    hermitian_tolerance: f64,
) -> Result<Vec<SMatrix<Complex64, D, D>>, FactorError> {
    if s.is_empty() {
        return Err(FactorError::Empty);
    }
    if !s.len().is_multiple_of(2) {
        return Err(FactorError::OddLength { len: s.len() });
    }
    s.iter()
        .enumerate()
        .map(|(bin, m)| {
            if !m.iter().all(|z| z.re.is_finite() && z.im.is_finite()) {
                return Err(FactorError::NonFinite { bin });
            }
            let norm = m.norm();
            if norm == 0.0 {
                return Err(FactorError::ZeroBin { bin });
            }
            let asymmetry = (m - m.adjoint()).norm() / norm;
            if asymmetry > hermitian_tolerance {
                return Err(FactorError::NonHermitian { bin, asymmetry });
            }
            Ok(hermitian_part(m))
        })
        .collect()
}

/// Raises eigenvalues below `eigen_floor * max trace` to that floor, bin by bin. Returns the
/// floored density, the number of bins changed and the largest eigenvalue increase.
fn apply_floor<const D: usize>(
    s: &[SMatrix<Complex64, D, D>],
    eigen_floor: f64,
) -> (Vec<SMatrix<Complex64, D, D>>, usize, f64) {
    let max_trace = s.iter().map(|m| m.trace().re).fold(0.0, f64::max);
    let floor = eigen_floor * max_trace;
    let shift = SMatrix::<Complex64, D, D>::identity() * Complex64::from(floor);
    let (mut count, mut max_loading) = (0, 0.0_f64);
    let out = s
        .iter()
        .map(|m| {
            // Cheap test first: S - floor I positive definite means nothing to clamp.
            if floor > 0.0 && cholesky_lower(&(m - shift)).is_some() {
                return *m;
            }
            let eig = DMatrix::from_column_slice(D, D, m.as_slice()).symmetric_eigen();
            let lambda_min = eig.eigenvalues.min();
            if lambda_min >= floor {
                return *m;
            }
            count += 1;
            max_loading = max_loading.max(floor - lambda_min);
            let clamped = eig.eigenvalues.map(|l| Complex64::from(l.max(floor)));
            let v = &eig.eigenvectors;
            let rebuilt = v * DMatrix::from_diagonal(&clamped) * v.adjoint();
            hermitian_part(&SMatrix::from_column_slice(rebuilt.as_slice()))
        })
        .collect();
    (out, count, max_loading)
}

/// `max_f ||F F^H - S||_F / ||S||_F`.
fn reconstruction_error<const D: usize>(
    f: &[SMatrix<Complex64, D, D>],
    s: &[SMatrix<Complex64, D, D>],
) -> f64 {
    f.iter()
        .zip(s)
        .map(|(fk, sk)| (outer(fk) - sk).norm() / sk.norm())
        .fold(0.0, f64::max)
}

/// `a b`, written out so that the small fixed size unrolls (nalgebra's generic product is several
/// times slower for 3x3 complex matrices).
fn product<const D: usize>(
    a: &SMatrix<Complex64, D, D>,
    b: &SMatrix<Complex64, D, D>,
) -> SMatrix<Complex64, D, D> {
    SMatrix::from_fn(|i, j| (0..D).map(|k| a[(i, k)] * b[(k, j)]).sum())
}

/// `f f^H`.
fn outer<const D: usize>(f: &SMatrix<Complex64, D, D>) -> SMatrix<Complex64, D, D> {
    hermitian_product(f, f)
}

/// `a s a^H` for a Hermitian `s`.
fn sandwich<const D: usize>(
    a: &SMatrix<Complex64, D, D>,
    s: &SMatrix<Complex64, D, D>,
) -> SMatrix<Complex64, D, D> {
    hermitian_product(&product(a, s), a)
}

/// `x y^H` for factors whose product is known to be Hermitian: the lower triangle is computed,
/// the upper mirrored.
fn hermitian_product<const D: usize>(
    x: &SMatrix<Complex64, D, D>,
    y: &SMatrix<Complex64, D, D>,
) -> SMatrix<Complex64, D, D> {
    let mut out = SMatrix::<Complex64, D, D>::zeros();
    for i in 0..D {
        for j in 0..=i {
            let v: Complex64 = (0..D).map(|k| x[(i, k)] * y[(j, k)].conj()).sum();
            out[(i, j)] = v;
            out[(j, i)] = v.conj();
        }
    }
    out
}

/// The lag-0 term of `Delta` from the (Hermitian) lag-0 term `m` of `g - I`: the strict lower
/// triangle of `m` plus half its (real) diagonal, so that `Delta_0 + Delta_0^H = m`.
fn lower_rule<const D: usize>(m: &SMatrix<Complex64, D, D>) -> SMatrix<Complex64, D, D> {
    SMatrix::from_fn(|i, j| match i.cmp(&j) {
        std::cmp::Ordering::Greater => m[(i, j)],
        std::cmp::Ordering::Equal => Complex64::from(0.5 * m[(i, i)].re),
        std::cmp::Ordering::Less => Complex64::ZERO,
    })
}

/// Removes the (rounding-level) unitary freedom left in the lag-0 term: `F <- F F_0^-1 L` with
/// `L = chol(F_0 F_0^H)`, so that the lag-0 term is exactly `L` (up to rounding). Leaves `F`
/// unchanged if `F_0` is singular.
fn normalise_zero_lag<const D: usize>(f: &mut [SMatrix<Complex64, D, D>]) {
    let f0 = mean(f);
    let (Some(inv), Some(l)) = (f0.try_inverse(), cholesky_lower(&(f0 * f0.adjoint()))) else {
        return;
    };
    let u = inv * l;
    for fk in f {
        *fk *= u;
    }
}

/// The lower Cholesky factor `L` (`L L^H = m`, real positive diagonal) of a Hermitian `m`, read
/// from its lower triangle; `None` unless `m` is positive definite. (nalgebra's `Cholesky` takes
/// complex square roots of negative pivots, so it does not detect indefinite complex matrices.)
fn cholesky_lower<const D: usize>(m: &SMatrix<Complex64, D, D>) -> Option<SMatrix<Complex64, D, D>> {
    let mut l = SMatrix::<Complex64, D, D>::zeros();
    for j in 0..D {
        let pivot = m[(j, j)].re - (0..j).map(|k| l[(j, k)].norm_sqr()).sum::<f64>();
        if !(pivot > 0.0 && pivot.is_finite()) {
            return None;
        }
        let diag = pivot.sqrt();
        l[(j, j)] = Complex64::from(diag);
        for i in j + 1..D {
            let dot: Complex64 = (0..j).map(|k| l[(i, k)] * l[(j, k)].conj()).sum();
            l[(i, j)] = (m[(i, j)] - dot) / diag;
        }
    }
    Some(l)
}

fn hermitian_part<const D: usize>(m: &SMatrix<Complex64, D, D>) -> SMatrix<Complex64, D, D> {
    (m + m.adjoint()) * Complex64::from(0.5)
}

fn mean<const D: usize>(f: &[SMatrix<Complex64, D, D>]) -> SMatrix<Complex64, D, D> {
    f.iter().sum::<SMatrix<Complex64, D, D>>() / Complex64::from(f.len().max(1) as f64)
}

#[cfg(test)]
#[path = "factor_tests.rs"]
mod tests;
