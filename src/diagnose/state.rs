//! The model of one block as the diagnosis grows it: the fitted structure, the tones found, and
//! the residual spectrum (measured minus simulated) they leave.

use std::sync::Arc;

use nalgebra::DMatrix;
use num_complex::Complex64;

use super::candidates::{Candidate, Extension};
use super::design::Design;
use super::fit::{Fitted, fit};
use super::profile::predict;
use super::structure::{Structure, Theta};
use super::tone::Tone;

/// One block's current model and residual.
#[derive(Clone, Debug)]
pub struct State {
    /// The block's data.
    pub design: Design,
    /// Group Gram matrices of the outputs (tones removed) and regressors.
    pub grams: Vec<DMatrix<Complex64>>,
    /// The fitted structure.
    pub fitted: Fitted,
    /// Tones in the model.
    pub tones: Vec<Tone>,
    /// Measured outputs minus the tones, band bins.
    pub outputs: [Vec<Complex64>; 3],
    /// Measured minus simulated outputs, band bins.
    pub residual: [Vec<Complex64>; 3],
    /// The block clock's rate error the outputs are corrected for (`None`: not in the model).
    pub clock_drift: Option<f64>,
    /// Its standard deviation (`None`: not in the model, or not determined).
    pub clock_drift_std: Option<f64>,
    /// The identification stretches' delay trend and its standard deviation, s per s: where the
    /// search for a clock drift starts (`None`: the record was too short to cut).
    pub drift_hint: Option<[f64; 2]>,
    /// The spectra above the fit's band, where tones are searched too ([`Design::line_search`];
    /// `None`: the band reaches the top already).
    pub upper: Option<Arc<Design>>,
    /// The upper outputs minus the paper's model and the tones found there.
    pub upper_residual: [Vec<Complex64>; 3],
}

impl State {
    /// The paper's model `K e^(-tau s)` fitted from a starting delay. `None` when the fit fails
    /// (degenerate inputs).
    #[must_use]
    pub fn base(design: Design, tau_s: f64, band_hz: [f64; 2]) -> Option<Self> {
        Self::refit(design, &Structure::default(), &Theta::delay_only(tau_s), band_hz)
    }

    /// `structure` fitted on `design` from `start` (no tones, no clock correction). `None` when
    /// the fit fails (degenerate inputs).
    #[must_use]
    pub fn refit(design: Design, structure: &Structure, start: &Theta, band_hz: [f64; 2]) -> Option<Self> {
        let outputs = design.outputs();
        let grams = design.grams(&outputs);
        let fitted = fit(&design, &grams, structure, start, band_hz)?;
        let residual = fitted_residual(&design, &outputs, &fitted);
        Some(Self {
            design,
            grams,
            fitted,
            tones: Vec::new(),
            outputs,
            residual,
            clock_drift: None,
            clock_drift_std: None,
            drift_hint: None,
            upper: None,
            upper_residual: [Vec::new(), Vec::new(), Vec::new()],
        })
    }

    /// The model with `candidate` added and every parameter refitted.
    #[must_use]
    pub fn with(&self, candidate: &Candidate, band_hz: [f64; 2]) -> Option<Self> {
        let mut next = self.clone();
        match &candidate.extension {
            Extension::Structural(fitted) => next.fitted = (**fitted).clone(),
            Extension::ClockCorrected {
                drift,
                drift_std,
                design,
                fitted,
            } => {
                next.design = (**design).clone();
                next.outputs = without_tones(&next.design, &self.tones);
                next.grams = next.design.grams(&next.outputs);
                next.fitted = (**fitted).clone();
                next.clock_drift = Some(*drift);
                next.clock_drift_std = *drift_std;
            }
            Extension::Tone(tone) if tone.upper => {
                let upper = self.upper.as_deref()?;
                for (r, t) in next.upper_residual.iter_mut().zip(&tone.spectrum(upper)) {
                    r.iter_mut().zip(t).for_each(|(r, t)| *r -= t);
                }
                next.tones.push(tone.clone());
            }
            Extension::Tone(tone) => {
                let spectrum = tone.spectrum(&self.design);
                for (out, tone) in next.outputs.iter_mut().zip(&spectrum) {
                    out.iter_mut().zip(tone).for_each(|(o, t)| *o -= t);
                }
                next.grams = self.design.grams(&next.outputs);
                next.fitted = fit(
                    &self.design,
                    &next.grams,
                    &self.fitted.structure,
                    &self.fitted.theta,
                    band_hz,
                )?;
                next.tones.push(tone.clone());
            }
        }
        next.residual = fitted_residual(&next.design, &next.outputs, &next.fitted);
        Some(next)
    }

    /// Sets the spectra above the fit's band where tones are searched too
    /// ([`Design::line_search`]): their residual is that of the current gain and delay.
    pub fn set_upper(&mut self, mut upper: Design) {
        let k = super::report::gain(self);
        self.upper_residual = upper.set_line_level(k, self.fitted.theta.tau_s);
        self.upper = Some(Arc::new(upper));
    }

    /// Band power of the residual relative to the measured output's, per channel, dB.
    #[must_use]
    pub fn gap_db(&self) -> [f64; 3] {
        gap_db(&self.design, &self.residual)
    }

    /// Per-channel gap, dB, of the paper's model with gain `k` and delay `tau_s` as given.
    #[must_use]
    pub fn gap_of(&self, k: [[f64; 3]; 3], tau_s: f64) -> [f64; 3] {
        let structure = Structure::default();
        let layout = structure.layout();
        let theta = Theta::delay_only(tau_s);
        let beta: Vec<f64> = k.iter().flatten().copied().collect();
        let residual = residual(
            &self.design,
            &self.design.outputs(),
            &structure,
            &layout,
            &theta,
            &beta,
        );
        gap_db(&self.design, &residual)
    }

    /// Band power of the residual of all three channels relative to the measured outputs', dB.
    #[must_use]
    pub fn total_gap_db(&self) -> f64 {
        let r: f64 = self.residual.iter().flatten().map(Complex64::norm_sqr).sum();
        let x: f64 = (0..3)
            .map(|i| self.design.z[i].iter().map(Complex64::norm_sqr).sum::<f64>())
            .sum();
        10.0 * (r / x.max(f64::MIN_POSITIVE)).max(1e-30).log10()
    }

    /// The worst channel's gap, dB.
    #[must_use]
    pub fn worst_gap_db(&self) -> f64 {
        self.gap_db().into_iter().fold(f64::NEG_INFINITY, f64::max)
    }
}

/// The design's outputs with `tones` subtracted, band bins.
#[must_use]
pub fn without_tones(design: &Design, tones: &[Tone]) -> [Vec<Complex64>; 3] {
    let mut outputs = design.outputs();
    for tone in tones {
        for (out, t) in outputs.iter_mut().zip(&tone.spectrum(design)) {
            out.iter_mut().zip(t).for_each(|(o, t)| *o -= t);
        }
    }
    outputs
}

/// Measured (tones removed) minus simulated outputs, band bins.
fn residual(
    design: &Design,
    outputs: &[Vec<Complex64>; 3],
    structure: &Structure,
    layout: &super::structure::Layout,
    theta: &Theta,
    beta: &[f64],
) -> [Vec<Complex64>; 3] {
    let model = predict(design, structure, layout, theta, beta);
    [0, 1, 2].map(|i| outputs[i].iter().zip(&model[i]).map(|(x, m)| x - m).collect())
}

/// The residual `fitted` leaves.
fn fitted_residual(design: &Design, outputs: &[Vec<Complex64>; 3], fitted: &Fitted) -> [Vec<Complex64>; 3] {
    residual(
        design,
        outputs,
        &fitted.structure,
        &fitted.layout,
        &fitted.theta,
        &fitted.profile.beta,
    )
}

/// Band power of `residual` relative to the measured output's, per channel, dB.
fn gap_db(design: &Design, residual: &[Vec<Complex64>; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| {
        let r: f64 = residual[i].iter().map(Complex64::norm_sqr).sum();
        let x: f64 = design.z[i].iter().map(Complex64::norm_sqr).sum();
        10.0 * (r / x.max(f64::MIN_POSITIVE)).max(1e-30).log10()
    })
}
