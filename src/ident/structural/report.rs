//! From the chosen normalised model to the [`StructuralFit`]: physical coefficients, poles,
//! standard deviations and the IEEE inertial-sensor units.
//!
//! IEEE practice for a sensor triad: the scale-factor error of axis `i` is
//! `(K_ii - 1) 1e6` ppm, the misalignment (cross-axis coupling, small angle) of output `i` to
//! input `j != i` is `K_ij 1e3` mrad. Their standard deviations scale the same way.

use super::model::{ELEMENTS, Prepared, parameter_count};
use super::order::Selection;
use super::{InformationCriterion, StructuralFit, rational};

/// Scale-factor errors and misalignments of a gain, with their standard deviations.
pub(super) struct IeeeUnits {
    /// `(K_ii - 1) 1e6`, ppm.
    pub ppm: [f64; 3],
    /// Its standard deviation, ppm.
    pub ppm_std: [f64; 3],
    /// `K_ij 1e3`, mrad, 0 on the diagonal.
    pub mrad: [[f64; 3]; 3],
    /// Its standard deviation, mrad, 0 on the diagonal.
    pub mrad_std: [[f64; 3]; 3],
}

/// The IEEE units of `k` and its standard deviations `k_std`.
pub(super) fn ieee_units(k: &[[f64; 3]; 3], k_std: &[[f64; 3]; 3]) -> IeeeUnits {
    let off = |m: &[[f64; 3]; 3]| {
        std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 0.0 } else { m[i][j] * 1e3 }))
    };
    IeeeUnits {
        ppm: std::array::from_fn(|i| (k[i][i] - 1.0) * 1e6),
        ppm_std: std::array::from_fn(|i| k_std[i][i] * 1e6),
        mrad: off(k),
        mrad_std: off(k_std),
    }
}

/// Builds the output. The covariance is that of the Gauss–Newton approximation, scaled by
/// `max(1, chi2 / dof)` and by the bins' correlation (`bin_correlation`, at least 1), and per
/// parameter the sandwich's where that is wider.
pub(super) fn assemble(
    data: &Prepared,
    selection: &Selection,
    criterion: InformationCriterion,
    bin_correlation: f64,
) -> StructuralFit {
    let model = selection.chosen();
    let order = model.order();
    let n_num = model.num.len();
    let w_ref = data.omega_ref;
    let dof = data.real_data().saturating_sub(parameter_count(order)).max(1);
    let inflation = ((selection.chi2() / dof as f64).max(1.0) * bin_correlation.max(1.0)).sqrt();
    // Widened by the sandwich where the bins' own scores spread more than the weights say
    // (`sandwich.rs`); never narrowed.
    let (plain, sandwich) = model.parameter_std_and_sandwich(data);
    let std: Vec<f64> = plain
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let widened = s * inflation;
            let robust = sandwich.as_ref().and_then(|v| v.get(i)).map_or(0.0, |v| v.sqrt());
            if widened.is_finite() {
                widened.max(robust)
            } else {
                widened
            }
        })
        .collect();
    let to_matrix = |c: &[f64; ELEMENTS]| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| c[3 * i + j]))
    };
    let k = to_matrix(&model.num[0]);
    let k_std = to_matrix(&std::array::from_fn(|e| std[e]));
    let numerator = (0..n_num)
        .map(|m| to_matrix(&model.num[m].map(|c| c / w_ref.powi(m as i32))))
        .collect();
    let power = |m: usize| w_ref.powi(m as i32 + 1);
    let denominator = (0..order).map(|m| model.den[m] / power(m)).collect();
    let denominator_std = (0..order).map(|m| std[ELEMENTS * n_num + m] / power(m)).collect();
    let tau_std_s = std[std.len() - 1] / w_ref;
    let poles = rational::roots(&model.den)
        .iter()
        .map(|r| [r.re * w_ref, r.im * w_ref])
        .collect();
    let ieee = ieee_units(&k, &k_std);
    let zeros_lag_s = super::admissible::numerator_lag(model, &std, w_ref).map(|(lag, std)| [lag, std]);
    StructuralFit {
        order,
        k,
        k_std,
        tau_s: model.tau,
        tau_std_s,
        denominator,
        denominator_std,
        numerator,
        poles,
        chi2: selection.chi2(),
        dof,
        stable: rational::is_stable(&model.den),
        criterion,
        candidates: selection.candidates.clone(),
        scale_factor_error_ppm: ieee.ppm,
        scale_factor_error_std_ppm: ieee.ppm_std,
        misalignment_mrad: ieee.mrad,
        misalignment_std_mrad: ieee.mrad_std,
        even_gain: None,
        zeros_lag_s,
        fitted: super::FittedOrders::default(),
    }
}

/// Whether any number of the fit is NaN (never expected; the last guard of the no-NaN contract).
pub(super) fn has_nan(fit: &StructuralFit) -> bool {
    let flat = |m: &[[f64; 3]; 3]| m.iter().flatten().any(|v| v.is_nan());
    flat(&fit.k)
        || flat(&fit.k_std)
        || fit.numerator.iter().any(flat)
        || fit.tau_s.is_nan()
        || fit.tau_std_s.is_nan()
        || fit.chi2.is_nan()
        || fit
            .denominator
            .iter()
            .chain(&fit.denominator_std)
            .any(|v| v.is_nan())
        || fit.poles.iter().flatten().any(|v| v.is_nan())
        || fit
            .candidates
            .iter()
            .any(|c| c.criterion.is_nan() || c.tau_s.is_nan())
        || flat(&fit.misalignment_mrad)
        || flat(&fit.misalignment_std_mrad)
        || fit
            .scale_factor_error_ppm
            .iter()
            .chain(&fit.scale_factor_error_std_ppm)
            .any(|v| v.is_nan())
}
