//! Structural identification: fitting `K e^(-tau s)` and richer rational models to a frequency
//! response estimate.
//!
//! # Models
//! Order 0 is the paper's result, `W(s) = K e^(-tau s)`: `K` a real 3x3 matrix (scale factors on
//! the diagonal, cross-axis couplings off it), `tau` one delay for the block. Orders `n = 1..=4`
//! are the alternatives, a common-denominator rational matrix with delay,
//! `W(s) = N(s) / d(s) e^(-tau s)`, `d(s) = 1 + d_1 s + ... + d_n s^n`, each `N_ij(s)` a real
//! polynomial of degree `n - 1` (strictly proper: a sensor is low-pass; order 1 is exactly
//! `K / (1 + T s)`). `N(0) = K` is the static gain whatever the order.
//!
//! # Units and conventions
//! Frequencies in Hz in the input, `s = j 2 pi f` in rad/s in every output coefficient and pole,
//! delays in seconds. `response[k][(i, j)]` is output channel `i` over input axis `j` at bin `k`.
//!
//! # Weights: generalised least squares
//! The estimate of output row `i`, `W_i(f)` (a complex 1x3 row), has the covariance
//! `C_i = E[dW_i^H dW_i]` (circular complex noise; proportional to `S_psi,ii S_uu^-1 / n_eq` for
//! an `H1` estimate). The fit minimises the generalised least-squares objective
//! `chi2 = sum_k sum_i 2 r_i Omega_i r_i^H`, `r_i = W_i - model_i` (`W` moved to its bins first
//! when its columns lie elsewhere, [`ResponseEstimate::offset_hz`], `align`), with the row weight
//! `Omega_i = C_i^-1 = n_eq S_uu / S_psi,ii` ([`Weights::RowWeight`]): Hermitian positive
//! semi-definite, possibly singular where the inputs are collinear (a direction the data say
//! nothing about gets no weight). Per-element variances ([`Weights::Variance`],
//! `E|dW_ij|^2`) are the special case `Omega_i = diag(1 / variance_i1, .., 1 / variance_i3)`,
//! mapped onto the same code path. The factor 2 counts the real and imaginary parts: with
//! `Omega_i = L_i L_i^H` the whitened real residuals are `sqrt(2) (Re, Im)(r_i L_i)`, of unit
//! variance, and chi2 is chi-square with `dof = 18 n_bins - p` degrees of freedom when the model
//! is right and the weights are the true inverse covariances. Row weights of an estimate with
//! offsets are raised where the moved estimate's order-0 residual scatters less than they say
//! (`scatter`: by at most 100 times; never lowered), as the fit then uses them.
//!
//! # Uncertainty
//! The standard deviations are the square roots of the diagonal of the Gauss–Newton covariance
//! `(J^T J)^-1` at the optimum (J the Jacobian of the whitened real residuals), multiplied by `max(1, chi2 / dof)`: a fit worse than the stated noise
//! allows widens its error bars, a fit better than it does not narrow them here (the weights'
//! own narrowing to the local scatter, `scatter`, comes before). Per parameter, the
//! sandwich `(J^T J)^-1 M (J^T J)^-1` of the bins' own scores replaces it where it is wider
//! ([`sandwich`]): a misfit that piles up in some bins (on `--stand real` runs, the
//! accelerometer's frequency-dependent errors in variables) is seen there, not in the one
//! `chi2 / dof` number. A parameter the data
//! cannot determine (a singular direction of `J`) gets an infinite standard deviation.
//!
//! # Order selection
//! [`OrderChoice::Auto`] fits every order 0..=4 that the band can support and picks the stable
//! candidate with the smallest information criterion (an unstable candidate is reported but never
//! chosen). The default is BIC, `chi2 + p ln(18 n_bins)`: the models are nested, the true
//! structure is of finite order, and BIC is consistent for that question, while AIC
//! (`chi2 + 2 p`) is not. On a true `K e^(-tau s)` block the extra pole of order 1 enters only at
//! second order (`e^(-tau s) / (1 + T s) ~ e^(-(tau + T) s + T^2 s^2 / 2)`: the delay absorbs
//! `T`, and `T^2 >= 0` is a boundary problem), so its chi2 gain is `0` half the time and
//! `chi2_1` otherwise: AIC's penalty of 2 per parameter is beaten with probability
//! `~ 0.5 P(chi2_1 > 2) ~ 8 %`, BIC's `ln(5886) ~ 8.7` on a 327-bin band with `~ 0.2 %`.
//! A real sensor pole (`T = 2..4 ms` on a 40 Hz band) lowers chi2 by thousands and is chosen by
//! either. The tests (`tests_noise.rs`) measure both criteria over seeded records.
//!
//! # Contracts
//! Empty input, mismatched lengths (offsets included), non-finite or non-positive values (offsets
//! included), row weights that are not
//! Hermitian or not positive semi-definite are refused with a [`StructuralError`] naming the bin
//! (and row); nothing reachable from the input panics, and no output
//! holds NaN (an undetermined standard deviation is `+inf`).

pub mod admissible;
mod align;
mod contract;
pub mod gain_delay;
mod holdout;
mod model;
mod order;
mod phasor;
mod placed;
mod project;
mod rational;
mod report;
pub(crate) mod sandwich;
mod scatter;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_gls;
#[cfg(test)]
mod tests_holdout;
#[cfg(test)]
mod tests_noise;
#[cfg(test)]
mod tests_scatter;
#[cfg(test)]
mod tests_warm;
mod warm;
mod weights;

pub use align::rational_slope;
pub use contract::StructuralError;
pub use holdout::held_out_chi2;
pub use order::criterion_value;
pub use warm::{FittedOrders, refit_structure};

use contract::{highest_order, prepare, validate};
use nalgebra::Matrix3;
use num_complex::Complex64;
use serde::Serialize;

use crate::ident::gain_curvature::EvenGain;

/// The highest rational order fitted.
pub const MAX_ORDER: usize = 4;

/// A frequency-response estimate over an analysis band, with its weights.
#[derive(Clone, Copy, Debug)]
pub struct ResponseEstimate<'a> {
    /// The band's bins, Hz: finite, `> 0`, in the bins' order (not necessarily ascending: each at its
    /// inputs' power centroid, `spectral::centroid`).
    pub frequency_hz: &'a [f64],
    /// `W(f)` at each bin: row `i` output channel, column `j` input axis.
    pub response: &'a [Matrix3<Complex64>],
    /// The inverse covariance of the estimate, one entry per bin (see the module docs).
    pub weights: Weights<'a>,
    /// Where the estimate's columns lie about `frequency_hz`, one offset matrix `G` per bin, Hz:
    /// the estimate is `W(f) + W'(f) G` (`align`). `None`: at `frequency_hz`.
    pub offset_hz: Option<&'a [Matrix3<Complex64>]>,
}

/// The weights of a [`ResponseEstimate`], one entry per bin.
#[derive(Clone, Copy, Debug)]
pub enum Weights<'a> {
    /// `E|dW_ij|^2` of each element's estimate: finite, `> 0`; independent elements, i.e. the
    /// diagonal row weights `Omega_i = diag(1 / variance_ij)`.
    Variance(&'a [Matrix3<f64>]),
    /// `Omega_i`, the inverse covariance `E[dW_i^H dW_i]^-1` of each output row's estimate
    /// (`[i]` for output row `i`): finite, Hermitian (to `1e-9` of its largest element),
    /// positive semi-definite (no eigenvalue below `-1e-9` of its trace); singular is allowed.
    RowWeight(&'a [[Matrix3<Complex64>; 3]]),
}

impl Weights<'_> {
    /// Number of bins given.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Variance(v) => v.len(),
            Self::RowWeight(w) => w.len(),
        }
    }

    /// Whether no bin is given.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Which model order to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OrderChoice {
    /// Exactly this order, `0..=4` (orders below it are fitted too, as starting points, and
    /// reported among the candidates).
    Fixed(usize),
    /// Every supportable order `0..=4`, the information criterion chooses.
    Auto,
}

/// The information criterion of [`OrderChoice::Auto`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InformationCriterion {
    /// `chi2 + p ln(N)`, `N = 18 n_bins` real data: consistent order selection (the default).
    #[default]
    Bic,
    /// `chi2 + 2 p`: prediction-oriented, overfits a true order-0 block in a sizeable fraction
    /// of records (see the module docs).
    Aic,
}

/// Tuning of the fit. The defaults suit IMU blocks on a motion stand.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StructuralSettings {
    /// Lower end of the delay scan of order 0, s.
    pub tau_min_s: f64,
    /// Upper end of the delay scan of order 0, s (`> tau_min_s`).
    pub tau_max_s: f64,
    /// Iteration cap of each Levenberg–Marquardt refinement (orders `>= 1`).
    pub max_iterations: usize,
    /// The criterion of [`OrderChoice::Auto`].
    pub criterion: InformationCriterion,
    /// Variance inflation from the correlation of neighbouring bins
    /// ([`crate::ident::spectra::bin_correlation`]; 1 for independent bins): the parameter
    /// covariance is multiplied by it, and the criterion's chi2 and number of data divided by it.
    pub bin_correlation: f64,
    /// Each order's held-out chi2 ([`held_out_chi2`]; index = order, `None` where not fitted to
    /// both halves). With it, [`OrderChoice::Auto`] applies admissibility rule 7 (an order must
    /// predict the other half of the record better than every lower order); `None` skips it.
    pub held_out_chi2: Option<[Option<f64>; MAX_ORDER + 1]>,
    /// Whether an aligned estimate's row weights are raised where its order-0 residual scatters
    /// less than they say (`scatter`). Off for fits whose deviations serve as floors (the
    /// stationarity stretches).
    pub narrow_to_scatter: bool,
    /// The part of the delay, s, that the estimate does not smear over a bin: the outputs were
    /// moved by it before the Welch estimate ([`crate::ident::alignment`]), so an estimate
    /// compared at its inputs' centroid (`align`) holds only the remaining delay's slope. 0: none.
    pub aligned_s: f64,
}

impl Default for StructuralSettings {
    fn default() -> Self {
        Self {
            tau_min_s: -0.020,
            tau_max_s: 0.050,
            max_iterations: 100,
            criterion: InformationCriterion::Bic,
            bin_correlation: 1.0,
            held_out_chi2: None,
            narrow_to_scatter: true,
            aligned_s: 0.0,
        }
    }
}

/// One fitted order, as compared by the order selection.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct OrderCandidate {
    /// The model order (number of poles).
    pub order: usize,
    /// Number of real parameters `p` (`10` at order 0, `10 n + 1` at order `n`).
    pub parameters: usize,
    /// Weighted residual (see the module docs).
    pub chi2: f64,
    /// The information criterion's value.
    pub criterion: f64,
    /// The fitted delay, s.
    pub tau_s: f64,
    /// Whether every pole has a negative real part (order 0: always).
    pub stable: bool,
    /// Why the order may not be chosen (absent: admissible; order 0 always is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rejected: Option<admissible::Rejection>,
    /// Its held-out chi2: fitted to each half of the record, predicting the other, summed
    /// (absent when the record was not halved or the order not fitted to both halves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out_chi2: Option<f64>,
    /// The order's unstable fit of smaller chi2 that was set aside for this stable one, because
    /// the data did not prefer it significantly (absent when the order's best fit was kept, and
    /// on a retune's refined orders, which are not put through the preference).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unstable_set_aside: Option<UnstableSetAside>,
}

/// An order's best fit, unstable, set aside for its best stable one: the data's preference for
/// it (Vuong's statistic, in deviations of the summed per-bin chi2 differences) was below the
/// bar of three deviations (`rational::Fitted::preferred`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct UnstableSetAside {
    /// The unstable fit's chi2 (below the candidate's).
    pub chi2: f64,
    /// Vuong's statistic of the unstable fit over the stable one (positive: it fits better).
    pub vuong_z: f64,
}

impl std::fmt::Display for UnstableSetAside {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "an unstable fit of chi2 {:.1} was set aside for this stable one: the data prefer it \
             by {:.1} deviations, below the {} that would outweigh a sensor's being stable",
            self.chi2,
            self.vuong_z,
            rational::PREFERENCE_Z
        )
    }
}

/// `N(s) / d(s) e^(-tau s)` at `s = j 2 pi f_hz`, with `N(s) = sum_m N_m s^m` and
/// `d(s) = 1 + d_1 s + ...` (s in rad/s). Non-finite only at a pole on the imaginary axis or for
/// a non-finite `f_hz`.
#[must_use]
pub fn rational_response(
    numerator: &[[[f64; 3]; 3]],
    denominator: &[f64],
    tau_s: f64,
    f_hz: f64,
) -> Matrix3<Complex64> {
    let s = Complex64::new(0.0, 2.0 * std::f64::consts::PI * f_hz);
    let mut d = Complex64::new(1.0, 0.0);
    let mut p = s;
    for dm in denominator {
        d += p * dm;
        p *= s;
    }
    let delay = (-s * tau_s).exp() / d;
    Matrix3::from_fn(|i, j| {
        let mut n = Complex64::new(0.0, 0.0);
        let mut p = Complex64::new(1.0, 0.0);
        for nm in numerator {
            n += p * nm[i][j];
            p *= s;
        }
        n * delay
    })
}

/// The result of a structural fit. All coefficients use `s` in rad/s.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StructuralFit {
    /// The model order (number of poles).
    pub order: usize,
    /// Static gain `K = N(0)`, `k[i][j]` output `i` over input `j`.
    pub k: [[f64; 3]; 3],
    /// Standard deviation of each element of `k`.
    pub k_std: [[f64; 3]; 3],
    /// The delay, s.
    pub tau_s: f64,
    /// Standard deviation of the delay, s.
    pub tau_std_s: f64,
    /// `d_1..d_n` of `d(s) = 1 + d_1 s + ... + d_n s^n` (empty at order 0), units `s^m`.
    pub denominator: Vec<f64>,
    /// Standard deviation of each denominator coefficient.
    pub denominator_std: Vec<f64>,
    /// `N_0 = K, N_1, ...` of `N(s) = sum_m N_m s^m`.
    pub numerator: Vec<[[f64; 3]; 3]>,
    /// Roots of `d(s)`, `[re, im]` in rad/s.
    pub poles: Vec<[f64; 2]>,
    /// Weighted residual (see the module docs).
    pub chi2: f64,
    /// Degrees of freedom, `18 n_bins - p`.
    pub dof: usize,
    /// Whether every pole has a negative real part. An unstable best fit is returned with
    /// `false` here, never silently.
    pub stable: bool,
    /// The criterion used to compare candidates.
    pub criterion: InformationCriterion,
    /// Every order fitted, with its figures.
    pub candidates: Vec<OrderCandidate>,
    /// `(K_ii - 1) 1e6`, ppm.
    pub scale_factor_error_ppm: [f64; 3],
    /// Standard deviation of `scale_factor_error_ppm`, ppm.
    pub scale_factor_error_std_ppm: [f64; 3],
    /// `K_ij 1e3` for `i != j` (small-angle cross-axis coupling), mrad; 0 on the diagonal.
    pub misalignment_mrad: [[f64; 3]; 3],
    /// Standard deviation of `misalignment_mrad`, mrad; 0 on the diagonal.
    pub misalignment_std_mrad: [[f64; 3]; 3],
    /// The even gain of a delay-only model whose block's gain changes across the band with no
    /// phase (`gain_changes_across_band`): the response is `g(omega) K e^(-tau s)` and `K` the gain
    /// at low frequency ([`Self::carry_even_gain`], `ident::even_gain`). Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub even_gain: Option<EvenGain>,
    /// The lag the numerator's zeros add at low frequency and a bound on its standard deviation,
    /// s (`[lag, std]`; negative: the zeros lead): minus a third of the trace of `N_0^-1 N_1`.
    /// Absent below order 2 (no `N_1`) or when `N_0` is singular.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zeros_lag_s: Option<[f64; 2]>,
    /// Every order's model as fitted, kept for [`refit_structure`] (not serialised).
    #[serde(skip)]
    pub fitted: FittedOrders,
}

impl StructuralFit {
    /// Sets the standard deviation of `K[i][j]` to `std`, and its static figure's with it (the
    /// scale factor's, ppm, on the diagonal; the misalignment's, mrad, off it): the widenings'
    /// one way to change them.
    pub fn set_k_std(&mut self, i: usize, j: usize, std: f64) {
        self.k_std[i][j] = std;
        if i == j {
            self.scale_factor_error_std_ppm[i] = std * 1e6;
        } else {
            self.misalignment_std_mrad[i][j] = std * 1e3;
        }
    }

    /// The fitted model's response at `f_hz` (Hz): `N(s) / d(s) e^(-tau s)`, `s = j 2 pi f`,
    /// times the even gain where there is one. Non-finite only at a pole on the imaginary axis or
    /// for a non-finite `f_hz`.
    #[must_use]
    pub fn response(&self, f_hz: f64) -> Matrix3<Complex64> {
        let r = rational_response(&self.numerator, &self.denominator, self.tau_s, f_hz);
        match &self.even_gain {
            Some(g) => r * Complex64::from(g.at(f_hz)),
            None => r,
        }
    }

    /// Gives a delay-only model fitted to the estimate over the even gain `even`
    /// ([`EvenGain`], `K` already the gain at low frequency) the even gain in its response, and
    /// each element of `K` the deviation `g`'s own uncertainty adds (`even.k_change_std`, in
    /// quadrature; the static figures with it). `false`, and nothing changed, at an order above 0
    /// or when the fit carries one already.
    pub fn carry_even_gain(&mut self, even: EvenGain) -> bool {
        if self.order != 0 || self.even_gain.is_some() {
            return false;
        }
        for i in 0..3 {
            for j in 0..3 {
                let std = self.k_std[i][j].hypot(even.k_change_std[i][j]);
                self.set_k_std(i, j, std);
            }
        }
        self.even_gain = Some(even);
        true
    }
}

/// Fits the structural model of `order` to `input` (moved to its bins first when it has offsets,
/// `align`).
///
/// # Errors
/// [`StructuralError::EmptyBand`], [`StructuralError::LengthMismatch`],
/// [`StructuralError::BadFrequency`], [`StructuralError::NonFiniteResponse`],
/// [`StructuralError::NonFiniteVariance`], [`StructuralError::NonPositiveVariance`],
/// [`StructuralError::NonFiniteWeight`], [`StructuralError::NonHermitianWeight`],
/// [`StructuralError::IndefiniteWeight`] for bad input; [`StructuralError::OrderTooHigh`] for `Fixed(n)`, `n > 4`;
/// [`StructuralError::TooFewBins`] when the band has fewer than `2 n + 2` bins for
/// `Fixed(n)` (or fewer than 2 bins for `Auto`, which otherwise skips the orders the band cannot
/// support); [`StructuralError::BadTauRange`] for an empty or non-finite delay scan;
/// [`StructuralError::NumericalFailure`] when the requested order (or order 0 under `Auto`)
/// produces no finite model.
pub fn fit_structure(
    input: &ResponseEstimate,
    order: OrderChoice,
    settings: &StructuralSettings,
) -> Result<StructuralFit, StructuralError> {
    validate(input)?;
    let placed = placed::Placed::new(input, settings)?;
    let highest = highest_order(order, placed.data.bins())?;
    finish(placed, highest, order, settings, order::Starts::Cold, true)
}

/// Fits the orders from `starts`, selects, and assembles the result.
fn finish(
    placed: std::sync::Arc<placed::Placed>,
    highest: usize,
    order: OrderChoice,
    settings: &StructuralSettings,
    starts: order::Starts,
    from_scratch: bool,
) -> Result<StructuralFit, StructuralError> {
    let data = &placed.data;
    let selection = order::fit_orders(data, highest, order, settings, starts)?;
    let mut fit = report::assemble(data, &selection, settings.criterion, settings.bin_correlation);
    if report::has_nan(&fit) {
        return Err(StructuralError::NumericalFailure { order: fit.order });
    }
    fit.fitted = FittedOrders::new(
        placed,
        selection.models,
        selection.set_aside,
        settings,
        from_scratch,
    );
    Ok(fit)
}
