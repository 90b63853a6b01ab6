//! The identified model file (contract section 4, schema `imu-attest/model/1`): what `identify`
//! writes and what `discrepancy` and `compare` read.
//!
//! Arrays are `[frequency][row][col]`; complex arrays are `{"re": .., "im": ..}`. The frequency
//! grid is the analysis band's bins of the (zero-padded) Welch grid. Beside the contract's fields
//! each block carries `W_u_std` (standard deviation of each element of `W_u`), `W_psi` (the
//! disturbance's minimum-phase shaping filter for unit two-sided white noise, so
//! `noise_psd = 2 W_psi W_psi^H` off DC), and `fit` (every figure of the structural fit and of the
//! regularised Wiener stage). A standard deviation the data cannot determine is `null`. No NaN or
//! infinity is ever written: [`Model::check_finite`] runs before every write.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::Path;

use nalgebra::Matrix3;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

pub mod band_limit;
pub mod effects;
mod extended;
pub mod refused;
pub mod validation;

pub use effects::ModelEffects;
pub use refused::RefusedBlock;

use crate::faults::RecordingFault;
use crate::ident::gain_curvature::EvenGain;
use crate::ident::identify::{BlockIdentification, RunIdentification};
use crate::ident::settings::{Estimate, Settings};
use crate::ident::signals::channel_names;
use crate::ident::structural::OrderCandidate;
use crate::ident::warnings::IdentWarning;
use crate::output::{OutputError, write_atomic};
use crate::run::Run;

/// The schema id of the model file.
pub const MODEL_SCHEMA: &str = "imu-attest/model/1";

/// A model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// Always [`MODEL_SCHEMA`].
    pub schema: String,
    /// The run it was identified from.
    pub source: Source,
    /// The settings as used.
    pub settings: Settings,
    /// One entry per block, keyed `"gyro"` / `"accel"`.
    pub blocks: BTreeMap<String, BlockModel>,
    /// Faults of the recording itself (`faults::detect`), absent when none was found.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub recording_faults: Vec<RecordingFault>,
    /// The run's blocks the identification refused beside the identified ones ([`refused`]),
    /// keyed `"gyro"` / `"accel"`: absent when every block was identified.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub refused_blocks: BTreeMap<String, RefusedBlock>,
}

/// Where the model came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// The run's file name.
    pub file: String,
    /// SHA-256 of the run file as stored.
    pub sha256: String,
    /// Regime (sidecar, or the file stem).
    pub regime: String,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

impl Source {
    /// The source record of a loaded run.
    #[must_use]
    pub fn of(run: &Run) -> Self {
        Self {
            file: run.source.file_name.clone(),
            sha256: run.source.sha256.clone(),
            regime: run.sidecar.regime.clone(),
            sample_rate_hz: run.sample_rate_hz,
        }
    }
}

/// Complex `[frequency][row][col]` arrays.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ComplexArray {
    /// Real parts.
    pub re: Vec<[[f64; 3]; 3]>,
    /// Imaginary parts.
    pub im: Vec<[[f64; 3]; 3]>,
}

impl ComplexArray {
    fn from_bins(bins: impl Iterator<Item = Matrix3<Complex64>>) -> Self {
        let (mut re, mut im) = (Vec::new(), Vec::new());
        for m in bins {
            re.push(std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)].re)));
            im.push(std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)].im)));
        }
        Self { re, im }
    }

    /// The matrix at bin `k`, if present.
    #[must_use]
    pub fn at(&self, k: usize) -> Option<Matrix3<Complex64>> {
        let (re, im) = (self.re.get(k)?, self.im.get(k)?);
        Some(Matrix3::from_fn(|i, j| Complex64::new(re[i][j], im[i][j])))
    }
}

/// One block's model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockModel {
    /// Input channel names.
    pub inputs: [String; 3],
    /// Output channel names.
    pub outputs: [String; 3],
    /// Static gain: `K[i][j]` from input axis j to output channel i.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Delay, s.
    pub tau_s: f64,
    /// Structural order (0 = `K e^(-tau s)`).
    pub order: usize,
    /// Denominator `d_1..d_n` of `d(s) = 1 + d_1 s + ...` (empty at order 0), s in rad/s.
    pub denominator: Vec<f64>,
    /// Numerator coefficient matrices `N_0 = K, N_1, ...`.
    pub numerator: Vec<[[f64; 3]; 3]>,
    /// Poles `[re, im]`, rad/s.
    pub poles: Vec<[f64; 2]>,
    /// Band frequencies, Hz.
    pub frequency_hz: Vec<f64>,
    /// Identified frequency response `(I - A^-1 Lambda) W`, `W` the settings' estimate (`H1` by
    /// default, or the causal Wiener-Kolmogorov `W0`).
    #[serde(rename = "W_u")]
    pub w_u: ComplexArray,
    /// Standard deviation of each element of `W_u`.
    #[serde(rename = "W_u_std")]
    pub w_u_std: Vec<[[f64; 3]; 3]>,
    /// One-sided cross-spectral density of the disturbance, output units^2/Hz.
    pub noise_psd: ComplexArray,
    /// Minimum-phase shaping filter of the disturbance.
    #[serde(rename = "W_psi")]
    pub shaping_filter: ComplexArray,
    /// `coherence[frequency][output]`: multiple coherence with the three inputs.
    pub coherence: Vec<[f64; 3]>,
    /// The analysis band used, Hz: the usable band found from the data (`band_hz: "auto"`),
    /// or the user's.
    #[serde(default)]
    pub band_hz: [f64; 2],
    /// The block identified on consecutive stretches of the record (order 0): per-stretch `K`
    /// and delay, their spread and the delay's trend (`segment_len` when on a shorter segment
    /// than the settings'). Absent for a record too short to cut.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stationarity: Option<crate::ident::stretches::Stationarity>,
    /// Noise terms of the block's disturbance (the residual of this model over the analysed
    /// span; `crate::noise`). Absent when not computed or the span is too short.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<crate::noise::BlockNoise>,
    /// Effects of the catalogue accepted into the model (`identify --effects`, the app's
    /// Accept): with them `K`, `tau_s` and their deviations are the joint fit's, `order` is 0 and
    /// `poles` are the effects' ([`effects`]). Absent when none was accepted; when some were
    /// accepted and none could be added ([`ModelEffects::extends`] false), it only lists them
    /// with the reasons and the model is as identified.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effects: Option<ModelEffects>,
    /// The even gain of a block whose gain changes across the band with no phase (the warning
    /// `gain_changes_across_band`), in a delay-only model: the response is `g(omega)` times the
    /// rest and `K` the gain at low frequency ([`crate::ident::gain_curvature::EvenGain`]).
    /// Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub even_gain: Option<EvenGain>,
    /// Quality figures.
    pub fit: Fit,
}

/// Quality figures of a block's identification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    /// Standard deviation of K (`null` where undetermined).
    pub k_std: [[Option<f64>; 3]; 3],
    /// Standard deviation of tau, s.
    pub tau_std_s: Option<f64>,
    /// Scale-factor errors `(K_ii - 1) 1e6`, ppm.
    pub scale_factor_error_ppm: [f64; 3],
    /// Their standard deviations, ppm.
    pub scale_factor_error_std_ppm: [Option<f64>; 3],
    /// Cross-axis misalignments `K_ij 1e3` (i != j; diagonal 0), mrad.
    pub misalignment_mrad: [[f64; 3]; 3],
    /// Their standard deviations, mrad.
    pub misalignment_std_mrad: [[Option<f64>; 3]; 3],
    /// Weighted residual of the structural fit.
    pub chi2: f64,
    /// Its degrees of freedom.
    pub dof: usize,
    /// Whether the chosen model is stable.
    pub stable: bool,
    /// chi2 per degree of freedom (near 1 when the model explains the data to its noise).
    #[serde(default)]
    pub chi2_per_dof: f64,
    /// Variance inflation from the correlation of neighbouring Welch bins, applied to every
    /// standard deviation (`ident::spectra::bin_correlation`).
    #[serde(default)]
    pub bin_correlation: f64,
    /// Every order tried: `{order, parameters, chi2, criterion, tau_s, stable}`.
    pub candidates: Vec<OrderCandidate>,
    /// Lagrange multipliers used.
    pub lambda: [f64; 3],
    /// Whether they were solved from the constraint.
    pub lambda_auto: bool,
    /// Band-integrated relative residual of `W_u S_uu = S_xu`.
    pub constraint_residual: f64,
    /// Overlap-corrected number of Welch averages.
    pub equivalent_averages: f64,
    /// Reconstruction error of the disturbance's spectral factor `W_psi` (relative, worst bin);
    /// absent in files written before it had its own name (`factor_errors[1]` then, not read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_factor_error: Option<f64>,
    /// Reconstruction error of the input's spectral factor `D_u`; absent when the fit did not go
    /// through the causal stage (`ident::causal_stage`), which alone factors the input.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_factor_error: Option<f64>,
    /// How many times finer than the spectra's the causal stage's grid was
    /// (`ident::causal_stage`, item 3); absent when the fit did not go through it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub causal_grid_refinement: Option<usize>,
    /// For a block of a run whose gyro coloured the angle-noise model (the gyro and an
    /// accelerometer beside it): the error of `K` (reported less true) if what the gyro left
    /// unexplained in the angles where that model kept its white floor were all the angles'
    /// noise (negative: the gains read low; it may as well be the gyro's own noise, then none),
    /// `|shift| / sqrt(3)` being in `k_std` ([`crate::ident::left_out_noise`]). Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_shift_left_out_angle_noise: Option<[[f64; 3]; 3]>,
    /// What was regularised or is inexact (absent or empty when all is well).
    #[serde(default)]
    pub warnings: Vec<IdentWarning>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A pole `[re, im]` (rad/s) in words: a real pole with its time constant, a complex pair
/// with its natural frequency and damping.
#[must_use]
pub fn describe_pole([re, im]: [f64; 2]) -> String {
    if im.abs() < 1e-12 {
        format!("{re:.4} rad/s (time constant {:.3} ms)", -1e3 / re)
    } else {
        let w = re.hypot(im);
        format!(
            "{re:.4} ± {:.4}j rad/s ({:.3} Hz, damping {:.2})",
            im.abs(),
            w / std::f64::consts::TAU,
            -re / w
        )
    }
}

impl BlockModel {
    /// The model of one identified block.
    #[must_use]
    pub fn from_identification(b: &BlockIdentification) -> Self {
        let (inputs, outputs) = channel_names(b.block);
        let s = &b.structural;
        let w = &b.wiener;
        let f = &b.factorisation;
        let causal = f.causal_for(w.estimate);
        let band = &b.band;
        Self {
            inputs: inputs.map(str::to_owned),
            outputs: outputs.map(str::to_owned),
            k: s.k,
            tau_s: s.tau_s,
            order: s.order,
            denominator: s.denominator.clone(),
            numerator: s.numerator.clone(),
            poles: s.poles.clone(),
            frequency_hz: band.iter().map(|&k| b.spectra.frequency_hz[k]).collect(),
            w_u: ComplexArray::from_bins(band.iter().map(|&k| w.w_u(k))),
            w_u_std: band
                .iter()
                .map(|&k| std::array::from_fn(|i| std::array::from_fn(|j| w.w_u_std[k][(i, j)])))
                .collect(),
            noise_psd: ComplexArray::from_bins(band.iter().map(|&k| f.noise_psd[k])),
            shaping_filter: ComplexArray::from_bins(band.iter().map(|&k| f.shaping_filter[k])),
            coherence: band.iter().map(|&k| w.coherence[k]).collect(),
            band_hz: b.band_hz,
            stationarity: b.stationarity.as_deref().cloned(),
            noise: None,
            effects: None,
            even_gain: s.even_gain,
            fit: Fit {
                k_std: s.k_std.map(|r| r.map(finite)),
                tau_std_s: finite(s.tau_std_s),
                scale_factor_error_ppm: s.scale_factor_error_ppm,
                scale_factor_error_std_ppm: s.scale_factor_error_std_ppm.map(finite),
                misalignment_mrad: s.misalignment_mrad,
                misalignment_std_mrad: s.misalignment_std_mrad.map(|r| r.map(finite)),
                chi2: s.chi2,
                dof: s.dof,
                stable: s.stable,
                chi2_per_dof: s.chi2 / s.dof.max(1) as f64,
                bin_correlation: b.spectra.bin_correlation,
                candidates: s.candidates.clone(),
                lambda: w.lambda,
                lambda_auto: w.lambda_auto,
                constraint_residual: w.constraint_residual,
                equivalent_averages: b.spectra.equivalent_averages,
                noise_factor_error: Some(f.noise_factor_error),
                input_factor_error: causal.map(|c| c.input_factor_error),
                causal_grid_refinement: causal.map(|c| c.input_refinement),
                k_shift_left_out_angle_noise: b.k_shift_left_out_angle_noise,
                warnings: b.warnings.clone(),
            },
        }
    }
}

impl BlockModel {
    /// The model's response at `f_hz` (Hz), `s = j 2 pi f`: `N(s) / d(s) e^(-tau s)`, or with
    /// effects added their extended response ([`ModelEffects::response`]); times the even gain
    /// where there is one.
    #[must_use]
    pub fn response(&self, f_hz: f64) -> Matrix3<Complex64> {
        let r = match self.extended_by() {
            Some(e) => e.response(&self.k, self.tau_s, f_hz),
            None => crate::ident::structural::rational_response(
                &self.numerator,
                &self.denominator,
                self.tau_s,
                f_hz,
            ),
        };
        match &self.even_gain {
            Some(g) => r * Complex64::from(g.at(f_hz)),
            None => r,
        }
    }

    /// The accepted effects where the model is extended by them (at least one could be added,
    /// [`ModelEffects::extends`]); `None` for a model as identified.
    #[must_use]
    pub fn extended_by(&self) -> Option<&ModelEffects> {
        self.effects.as_ref().filter(|e| e.extends())
    }
}

impl Model {
    /// The model file of an identified run.
    #[must_use]
    pub fn from_identification(run: &Run, settings: &Settings, id: &RunIdentification) -> Self {
        Self {
            schema: MODEL_SCHEMA.to_owned(),
            source: Source::of(run),
            settings: settings.clone(),
            blocks: id
                .blocks
                .iter()
                .map(|b| (b.block.name().to_owned(), BlockModel::from_identification(b)))
                .collect(),
            recording_faults: crate::faults::detect(run),
            refused_blocks: refused::refused_blocks(&id.refused),
        }
    }

    /// Reads the estimate of a model file written before the `estimate` setting existed
    /// (26 Nov): those were fitted to the causal Wiener estimate, so a file whose settings do not
    /// name an estimate gets `causal_wiener`, not today's default, and a diagnosis or report made
    /// from it (`--model`) uses what its numbers came from. `bytes` is the file `self` was read
    /// from.
    pub fn settle_estimate(&mut self, bytes: &[u8]) {
        #[derive(Deserialize)]
        struct Probe {
            settings: ProbeSettings,
        }
        #[derive(Deserialize)]
        struct ProbeSettings {
            estimate: Option<serde::de::IgnoredAny>,
        }
        if serde_json::from_slice::<Probe>(bytes).is_ok_and(|p| p.settings.estimate.is_none()) {
            self.settings.estimate = Estimate::CausalWiener;
        }
    }

    /// Checks that every number is finite (JSON cannot carry NaN or infinity).
    ///
    /// # Errors
    /// The JSON path of the first non-finite number.
    pub fn check_finite(&self) -> Result<(), String> {
        let value = serde_json::to_value(self).map_err(|e| e.to_string())?;
        first_null(&value, "", false).map_or(Ok(()), |path| Err(format!("{path} is not a finite number")))
    }

    /// Writes the model file (pretty JSON) atomically, after [`Model::check_finite`]: every writer
    /// of a model goes through here, so no NaN or infinity reaches a file.
    ///
    /// # Errors
    /// [`OutputError::NonFinite`] naming the first non-finite number (nothing is written), or the
    /// errors of [`write_atomic`].
    pub fn write_file(&self, path: &Path) -> Result<(), OutputError> {
        self.check_finite().map_err(|detail| OutputError::NonFinite {
            path: path.to_path_buf(),
            detail,
        })?;
        write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })
    }
}

/// The path of the first `null` in `value` (where `serde_json` wrote NaN or infinity), outside
/// keys containing `_std` (undetermined uncertainties).
#[must_use]
pub fn first_non_finite(value: &serde_json::Value) -> Option<String> {
    first_null(value, "", false)
}

/// `serde_json` writes NaN and infinity as `null`; in a model only the `*_std*` figures may
/// legitimately be `null` (undetermined). Returns the path of the first other `null`.
fn first_null(value: &serde_json::Value, path: &str, null_allowed: bool) -> Option<String> {
    match value {
        serde_json::Value::Null if !null_allowed => Some(path.to_owned()),
        serde_json::Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, v)| first_null(v, &format!("{path}[{i}]"), null_allowed)),
        serde_json::Value::Object(map) => map.iter().find_map(|(k, v)| {
            let child = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            first_null(v, &child, null_allowed || k.contains("_std"))
        }),
        _ => None,
    }
}

#[cfg(test)]
#[path = "model_tests.rs"]
mod tests;
