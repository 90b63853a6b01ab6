//! Whether a block's gain depends on the motion's amplitude: the self-check's test for a part of
//! each output odd-quadratic in its own input, `k2_i u_i |u_i|` (the catalogue's
//! `scale_nonlinearity`), which a linear model takes into `K` at the run's motion amplitude.
//!
//! Why `K` moves: by Bussgang's theorem the part of `q = u |u|` a linear filter of the inputs
//! explains is `a(f)^T u` with `a^T = S_qu S_uu^-1` (for a Gaussian input of deviation `sigma`,
//! `a_i = 2 sqrt(2 / pi) sigma`, flat over frequency), so the linear fit's row `i` reads
//! `K_i + k2_i a^T`: the gain at this run's amplitude, not the scale factor, and another run with
//! larger motion gets a larger one. What is left, `q - a^T u`, spreads over frequency (harmonics,
//! intermodulation) and is what reveals `k2`.
//!
//! The test, per output `i` and native Welch bin of the band, from the Welch matrix of
//! `[u; x; q]` (9 channels, the block's own segment and overlap, the span's signals; `S_ab =
//! E[a b^H]`): the partial cross-spectrum of `x_i` and `q_i` given the three inputs,
//! `S_xq.u = S_xq - S_xu S_uu^-1 S_uq` (likewise `S_qq.u`, `S_xx.u`), gives the regression
//! coefficient `beta = S_xq.u / S_qq.u`, which is `k2_i e^(-i w tau)` for an output delayed by
//! `tau`. Every linear dynamics of the block (its `K`, cross-coupling, poles, delay) is taken out
//! by the free per-bin regression on `u`, so no linear model error can read as `k2`; the noise of
//! the observer's input estimate does not either (the Wiener estimate's error is uncorrelated
//! with every function of the estimate for Gaussian motion). Each bin's `Re(beta e^(i w tau))`
//! has variance `S_xx.uq / (2 (n_eq - 4) S_qq.u)` (`S_xx.uq` what neither explains, `n_eq` the
//! equivalent independent averages, four regressors fitted), so the band's inverse-variance mean
//! is `k2_i`, its deviation widened by the neighbouring bins' correlation and by `nu / (nu - 2)`
//! (`nu = 2 (n_eq - 4)`: each bin's variance is itself an estimate, and weighting by its inverse
//! overstates the information). The outputs are first moved earlier by the block's own alignment
//! ([`super::alignment`]), the delay turned back being what is left of the model's.
//! Self-normalising: a misfit of the linear model elsewhere does not narrow it.
//!
//! Said (`gain_depends_on_amplitude`) per output when `k2_i` is [`SAID_SIGMAS`] of its deviations
//! from 0 **and** the gain it adds to `K_ii` (`k2_i` times `a`'s diagonal pooled over the band as
//! the gain's fit pools it, [`pooled`]) exceeds `K_ii`'s own deviation: a nonlinearity too small
//! to move `K` beyond its deviation is not the model's problem.
//!
//! Units: `k2` in output units per input unit squared; the gain's shift relative to `K_ii`.
//! Empty or too short records, a band without bins, fewer than [`MIN_AVERAGES`] equivalent
//! averages, or singular bins give no warning (nothing is concluded), never NaN.

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::alignment::aligned;
use super::signals::BlockSignals;
use crate::spectral::{SpectralError, WelchPlanner, WelchSettings};

/// How many of its deviations `k2` must be from 0 before it is said: strong evidence, since the
/// test runs on every output of every block.
pub const SAID_SIGMAS: f64 = 5.0;

/// Fewest equivalent independent averages the per-bin regression on four regressors is trusted
/// with.
pub const MIN_AVERAGES: f64 = 8.0;

/// Per output and native bin, what the band's test pools.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OddSpectra {
    /// Native bin frequencies, Hz.
    pub frequency_hz: Vec<f64>,
    /// `beta = S_xq.u / S_qq.u` per output and bin.
    pub beta: [Vec<Complex64>; 3],
    /// Variance of `Re beta` per output and bin (infinite where a bin is singular).
    pub beta_var: [Vec<f64>; 3],
    /// `S_uu` per bin.
    pub s_uu: Vec<Matrix3<Complex64>>,
    /// `S_(q_i u)` per output and bin, the row `[E q_i u_j^*]_j`.
    pub s_qu: [Vec<Vector3<Complex64>>; 3],
    /// `S_xx.u` per output and bin: what the inputs leave of the output, the level the gain's fit
    /// weighs the bin by.
    pub residual: [Vec<f64>; 3],
    /// Equivalent independent averages of the estimate.
    pub equivalent_averages: f64,
    /// How far the outputs were moved earlier before the estimate, s (the block's own alignment).
    pub lag_s: f64,
}

/// One output's figures when its gain depends on the amplitude.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OddOutput {
    /// The output channel (`K`'s row).
    pub output: String,
    /// `k2`, output units per input unit squared.
    pub k2: f64,
    /// Its standard deviation.
    pub k2_std: f64,
    /// The gain `k2` adds to `K_ii` at this run's amplitude, relative to `K_ii` (positive: `K_ii`
    /// larger in magnitude than its small-motion value).
    pub gain_shift: f64,
    /// `K_ii`'s own relative deviation.
    pub k_relative_std: f64,
}

/// The spectra of the test for `signals` (the span's) under the block's Welch settings, with
/// `equivalent_averages` those of the block's own estimate (same segment and overlap) and its
/// outputs moved earlier by `lag` samples as the block's spectra were (negative: later).
///
/// # Errors
/// What Welch refuses (a segment longer than the span, a non-finite sample).
pub fn odd_spectra(
    planner: &mut WelchPlanner,
    signals: &BlockSignals,
    sample_rate_hz: f64,
    (welch, equivalent_averages, lag): (&WelchSettings, f64, i64),
) -> Result<OddSpectra, SpectralError> {
    let q = signals
        .input
        .each_ref()
        .map(|u| u.iter().map(|v| v * v.abs()).collect::<Vec<f64>>());
    // The outputs moved earlier by `lag` samples, as the block's own spectra were
    // ([`super::alignment`]): a delay long beside the segment would smear the cross-spectra.
    let whole: Vec<&[f64]> = signals
        .input
        .iter()
        .chain(&signals.output)
        .map(Vec::as_slice)
        .collect();
    let (mut channels, input_start) = aligned(&whole, lag);
    let len = channels.first().map_or(0, |c| c.len());
    channels.extend(q.iter().map(|c| &c[input_start..input_start + len]));
    let native = WelchSettings {
        fft_len: None,
        ..*welch
    };
    let m = planner.welch_matrix(&channels, sample_rate_hz, &native)?;
    let mut out = OddSpectra {
        frequency_hz: m.frequency_hz.clone(),
        equivalent_averages,
        lag_s: lag as f64 / sample_rate_hz,
        ..OddSpectra::default()
    };
    let dof = (equivalent_averages - 4.0).max(1.0);
    for f in 0..m.n_bins() {
        let s = |i: usize, j: usize| m.get(f, i, j).unwrap_or_default();
        let s_uu = Matrix3::from_fn(&s);
        let inverse = s_uu.try_inverse().filter(|inv| inv.iter().all(|v| v.is_finite()));
        for i in 0..3 {
            let (x, qi) = (3 + i, 6 + i);
            let row = |a: usize| Vector3::new(s(a, 0), s(a, 1), s(a, 2));
            let col = |b: usize| Vector3::new(s(0, b), s(1, b), s(2, b));
            let figures = inverse.map(|inv| {
                let partial = |a: usize, b: usize| s(a, b) - (row(a).transpose() * inv * col(b))[(0, 0)];
                (partial(x, qi), partial(qi, qi).re, partial(x, x).re)
            });
            let (beta, var, residual) = match figures {
                Some((xq, qq, xx)) if qq > 0.0 && xx > 0.0 => {
                    let left = (xx - xq.norm_sqr() / qq).max(0.0);
                    (xq / qq, left / (2.0 * dof * qq), xx)
                }
                _ => (Complex64::default(), f64::INFINITY, f64::INFINITY),
            };
            out.beta[i].push(beta);
            out.beta_var[i].push(if var > 0.0 { var } else { f64::INFINITY });
            out.s_qu[i].push(row(qi));
            out.residual[i].push(residual);
        }
        out.s_uu.push(s_uu);
    }
    Ok(out)
}

/// `k2` per output over `band_hz` (its deviation widened by `bin_correlation`), with `tau_s` the
/// block's delay, and the gain it adds to `K_ii` per unit of `k2`: the diagonal of the part of
/// `q_i` the gain's fit takes for linear, `Re[(sum S_qu / r)(sum S_uu / r)^-1]_i` over the band's
/// bins weighted as the fit weighs them (by `1 / S_xx.u`); `(k2, k2_std, absorbed)` per output,
/// `None` for an output without a usable bin.
#[must_use]
pub fn pooled(
    odd: &OddSpectra,
    band_hz: [f64; 2],
    tau_s: f64,
    bin_correlation: f64,
) -> [Option<(f64, f64, f64)>; 3] {
    std::array::from_fn(|i| {
        let (mut sw, mut swk) = (0.0, 0.0);
        let mut qu = Vector3::<Complex64>::zeros();
        let mut uu = Matrix3::<Complex64>::zeros();
        for (k, &f) in odd.frequency_hz.iter().enumerate() {
            let (var, r) = (odd.beta_var[i][k], odd.residual[i][k]);
            if f < band_hz[0] || f > band_hz[1] || !(var.is_finite() && var > 0.0 && r.is_finite()) {
                continue;
            }
            let omega = 2.0 * std::f64::consts::PI * f;
            let k2 = (odd.beta[i][k] * Complex64::from_polar(1.0, omega * (tau_s - odd.lag_s))).re;
            sw += 1.0 / var;
            swk += k2 / var;
            qu += odd.s_qu[i][k] / Complex64::from(r);
            uu += odd.s_uu[k] / Complex64::from(r);
        }
        let absorbed = uu.try_inverse().map(|inv| (qu.transpose() * inv)[(0, i)].re)?;
        // Each bin's variance is itself estimated, on `nu = 2 (n_eq - 4)` degrees of freedom:
        // weights `1 / var` overstate the sum's by `nu / (nu - 2)` on average.
        let nu = 2.0 * (odd.equivalent_averages - 4.0);
        let information = if nu > 2.0 { sw * (nu - 2.0) / nu } else { 0.0 };
        (information > 0.0 && absorbed.is_finite()).then(|| {
            let sd = (bin_correlation.max(1.0) / information).sqrt();
            (swk / sw, sd, absorbed)
        })
    })
}

/// The outputs whose gain depends on the amplitude enough to say (module docs), given the
/// model's `k`, `k_std` and `tau_s`; empty when none does or the estimate has too few averages.
#[must_use]
pub fn amplitude_dependent(
    odd: &OddSpectra,
    band_hz: [f64; 2],
    bin_correlation: f64,
    outputs: [&str; 3],
    (k, k_std, tau_s): (&[[f64; 3]; 3], &[[f64; 3]; 3], f64),
) -> Vec<OddOutput> {
    if odd.equivalent_averages < MIN_AVERAGES {
        return Vec::new();
    }
    pooled(odd, band_hz, tau_s, bin_correlation)
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let (k2, k2_std, absorbed) = (*p)?;
            // Relative to `K_ii` with its sign: a positive shift makes the diagonal larger in
            // magnitude, whatever its sign.
            let kii = k[i][i];
            let gain_shift = k2 * absorbed / kii;
            let k_relative_std = k_std[i][i] / kii.abs();
            let finite = [k2, k2_std, gain_shift, k_relative_std]
                .iter()
                .all(|v| v.is_finite());
            (finite && k2.abs() >= SAID_SIGMAS * k2_std && gain_shift.abs() > k_relative_std).then(|| {
                OddOutput {
                    output: outputs[i].to_owned(),
                    k2,
                    k2_std,
                    gain_shift,
                    k_relative_std,
                }
            })
        })
        .collect()
}

#[cfg(test)]
#[path = "odd_gain_tests.rs"]
mod tests;
