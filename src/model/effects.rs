//! Effects of the catalogue accepted into a block's model (issue 15): the paper's model
//! `K e^(-tau s)` extended by them, as the diagnosis fits it on the whole record
//! (`diagnose::extend`). A block model that carries them has `K`, `tau_s` and their standard
//! deviations from that joint fit, `order` 0, and its response ([`super::BlockModel::response`])
//! includes the effects that are filters:
//! `H_ij(s) = e^(-(tau + skew_i) s) L(s) K_ij M_j(s) / H(s)`, `L` the lag (`1 / (T s + 1)`, or
//! `1 / ((T s)^2 + 2 zeta T s + 1)` with `lag_damping`), `M_j` a mount resonance on
//! input axis `j`, `H` the stand's angle-measurement low-pass where `reference_band_limit` was
//! accepted (the response is then the one against this stand's angles). The others
//! (g-sensitivity, quadratic scale factor, lever-arm offset, tones, clock drift) are terms beside
//! the response, sized in `accepted`. Where none of the accepted
//! effects could be added ([`ModelEffects::extends`] false), the block's model is the identified
//! one and these only list them under `not_added`: `identified` repeats the model, the response's
//! terms are empty and `chi2_per_dof` and `gap_db` hold the whole-record fit without effects
//! twice.
//!
//! Units: SI (s, Hz); sizes as in the discrepancy report's `parameters`, with `parameter_std`
//! under the same keys (`null` where not determined).

use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::band_limit::FittedBandLimit;
use crate::effect::Effect;

/// One accepted effect with its size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcceptedEffect {
    /// The catalogue entry (its id in JSON).
    pub effect: Effect,
    /// Readable name, e.g. "gyro first-order lag" ("gyro second-order low-pass" for the lag's
    /// second shape).
    pub name: String,
    /// Its size, as the discrepancy report's `parameters`.
    pub parameters: Value,
    /// Their standard deviations, under the same keys.
    pub parameter_std: Value,
}

/// A mount resonance in the response. Read from a model file only with an axis 0 to 2, and a
/// natural frequency and damping that are finite and positive.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawResonance")]
pub struct Resonance {
    /// Input axis (0, 1, 2).
    pub axis: usize,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping: f64,
}

/// [`Resonance`] as read, before its check.
#[derive(Deserialize)]
struct RawResonance {
    axis: usize,
    frequency_hz: f64,
    damping: f64,
}

impl TryFrom<RawResonance> for Resonance {
    type Error = String;

    fn try_from(raw: RawResonance) -> Result<Self, String> {
        if raw.axis > 2 {
            return Err(format!("a resonance's axis must be 0, 1 or 2: {}", raw.axis));
        }
        if !(raw.frequency_hz.is_finite() && raw.frequency_hz > 0.0) {
            return Err(format!(
                "a resonance's frequency_hz must be finite and positive: {}",
                raw.frequency_hz
            ));
        }
        if !(raw.damping.is_finite() && raw.damping > 0.0) {
            return Err(format!(
                "a resonance's damping must be finite and positive: {}",
                raw.damping
            ));
        }
        Ok(Self {
            axis: raw.axis,
            frequency_hz: raw.frequency_hz,
            damping: raw.damping,
        })
    }
}

/// A lag's time constant as read: finite and not negative.
fn lag_time<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let t = Option::<f64>::deserialize(d)?;
    match t {
        Some(t) if !(t.is_finite() && t >= 0.0) => Err(serde::de::Error::custom(format!(
            "a lag's time constant lag_s must be finite and not negative: {t}"
        ))),
        _ => Ok(t),
    }
}

/// A second-order lag's damping as read: finite and positive (zero or less is not a low-pass:
/// an undamped or growing oscillation).
fn lag_damping<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let zeta = Option::<f64>::deserialize(d)?;
    match zeta {
        Some(z) if !(z.is_finite() && z > 0.0) => Err(serde::de::Error::custom(format!(
            "a second-order lag's damping lag_damping must be finite and positive: {z}"
        ))),
        _ => Ok(zeta),
    }
}

impl Resonance {
    /// The mode's gain at `f_hz`, `|M(j 2 pi f)|` of the resonant low-pass
    /// `w_n^2 / (s^2 + 2 zeta w_n s + w_n^2)`.
    #[must_use]
    pub fn gain(&self, f_hz: f64) -> f64 {
        let r = f_hz / self.frequency_hz;
        1.0 / ((1.0 - r * r).powi(2) + (2.0 * self.damping * r).powi(2)).sqrt()
    }

    /// Whether the mode can hold an identified `gain_changes_across_band` warning `w`: it lies
    /// inside the warning's band, where its gain rises to the peak and falls beyond (the
    /// warning's one figure for the change, from a delay-only fit that misses the peak, can then
    /// have either sign: a fall of 27 % across 0.29-39.8 Hz beside a 31.8 Hz mode whose gain at
    /// the top is 1.7), or outside it its gain moves across the band the way the measured gain
    /// did (a rise towards the mode below it, a fall above). Not by column either: beside a
    /// missed mode the element the change moved most against its own deviation need not be in
    /// the mode's (a mode on `wz`, the largest change at `K[gy][wy]`, 4.5-6.8 deviations).
    /// Whether the extended model explains the data is its own poor fit's to say. False for any
    /// other warning.
    #[must_use]
    pub fn explains(&self, w: &crate::ident::warnings::IdentWarning) -> bool {
        explains_gain_change(w, Some(self.frequency_hz), |f| self.gain(f))
    }
}

/// Whether a filter of gain `gain(f)` peaking at `peak_hz` (if it peaks) can hold a
/// `gain_changes_across_band` warning `w`: it peaks inside the warning's band (its gain rises to
/// the peak and falls beyond: either sign), or its gain changes across the band the way the
/// warning says. False for any other warning.
fn explains_gain_change(
    w: &crate::ident::warnings::IdentWarning,
    peak_hz: Option<f64>,
    gain: impl Fn(f64) -> f64,
) -> bool {
    let crate::ident::warnings::IdentWarning::GainChangesAcrossBand { rise, band_hz, .. } = w else {
        return false;
    };
    let [low, high] = *band_hz;
    peak_hz.is_some_and(|p| (low..=high).contains(&p)) || (gain(high) - gain(low)) * rise > 0.0
}

impl Identified {
    /// ", band a-b Hz" where the identified band is known and not `model_band_hz` (the model
    /// fitted through the band its misfit cut), else nothing: for the words beside the model.
    #[must_use]
    pub fn band_words(&self, model_band_hz: [f64; 2]) -> String {
        match self.band_hz {
            Some(b) if (b[1] - model_band_hz[1]).abs() > 1e-9 * model_band_hz[1] => {
                format!(", band {:.2}-{:.2} Hz", b[0], b[1])
            }
            _ => String::new(),
        }
    }
}

/// The model before the effects were added: what the identifier gave.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identified {
    /// Its static gain.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// Its delay, s.
    pub tau_s: f64,
    /// Its structural order.
    pub order: usize,
    /// Its band, Hz (absent in model files written before 30 Nov; the model's own band may be
    /// wider, [`crate::model::BlockModel::take_back_the_cut_band`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
}

/// The block's accepted effects and the fit that sized them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelEffects {
    /// The effects, in the order they were added.
    pub accepted: Vec<AcceptedEffect>,
    /// Effects asked for that could not be added, each with the reason in words.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_added: Vec<NotAdded>,
    /// The lag's time constant `T`, s (absent: no lag; read only finite and not negative):
    /// `1 / (T s + 1)`, or with
    /// [`Self::lag_damping`] `1 / ((T s)^2 + 2 zeta T s + 1)`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "lag_time"
    )]
    pub lag_s: Option<f64>,
    /// A second-order lag's damping `zeta` (absent: the lag, if any, is first order; read only
    /// finite and positive).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "lag_damping"
    )]
    pub lag_damping: Option<f64>,
    /// Per-channel delays relative to `tau_s`, s (absent: no skew).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel_skew_s: Option<[f64; 3]>,
    /// Mount resonances.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub resonances: Vec<Resonance>,
    /// The stand's angle-measurement low-pass (`reference_band_limit`), whose inverse the
    /// response then carries: the response against this stand's angles, not the sensor's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_band_limit: Option<FittedBandLimit>,
    /// The identified model the effects extend.
    pub identified: Identified,
    /// The band of the whole-record fit, Hz.
    pub band_hz: [f64; 2],
    /// `chi2` per degree of freedom of the whole-record fit without and with the effects.
    pub chi2_per_dof: [f64; 2],
    /// Per-channel gap (residual over measured band power, dB) without and with the effects.
    pub gap_db: [[f64; 3]; 2],
}

/// An effect that could not be added.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NotAdded {
    /// The catalogue entry.
    pub effect: Effect,
    /// Why, in words.
    pub reason: String,
}

impl ModelEffects {
    /// Whether any effect was added: the block's model is then the extended one. Accepted
    /// effects that could none be added leave the block's model as identified (its order, poles
    /// and even gain), and these effects only list them with the reasons
    /// ([`crate::diagnose::extend`]).
    #[must_use]
    pub fn extends(&self) -> bool {
        !self.accepted.is_empty()
    }

    /// The extended response at `f_hz` of gain `k` and delay `tau_s`.
    #[must_use]
    pub fn response(&self, k: &[[f64; 3]; 3], tau_s: f64, f_hz: f64) -> nalgebra::Matrix3<Complex64> {
        let s = Complex64::new(0.0, std::f64::consts::TAU * f_hz);
        let lag = self.lag_at(f_hz);
        let skew = self.channel_skew_s.unwrap_or([0.0; 3]);
        let mut resonant = [Complex64::from(1.0); 3];
        for r in &self.resonances {
            let w = std::f64::consts::TAU * r.frequency_hz;
            if let Some(m) = resonant.get_mut(r.axis) {
                *m *= w * w / (s * s + 2.0 * r.damping * w * s + w * w);
            }
        }
        let reference = self
            .reference_band_limit
            .map_or(Complex64::from(1.0), |r| r.shape.inverse_at(r.t_s, f_hz));
        nalgebra::Matrix3::from_fn(|i, j| {
            (-s * (tau_s + skew[i])).exp() * lag * reference * k[i][j] * resonant[j]
        })
    }

    /// What a model file's effects hold that their fields alone cannot check: a damping needs a
    /// lag (`lag_damping` without `lag_s` would be silently ignored). The offending field's name
    /// in the error.
    ///
    /// # Errors
    /// The field and what is wrong, in words.
    pub fn check(&self) -> Result<(), String> {
        if self.lag_damping.is_some() && self.lag_s.is_none() {
            return Err(
                "lag_damping: a second-order lag's damping without its time constant lag_s".to_owned(),
            );
        }
        Ok(())
    }

    /// The lag's response `L(j 2 pi f)` at `f_hz` (1 without a lag): `1 / (T s + 1)`, or with
    /// [`Self::lag_damping`] `1 / ((T s)^2 + 2 zeta T s + 1)` (as the diagnosis's
    /// `LagShape::response`).
    #[must_use]
    pub fn lag_at(&self, f_hz: f64) -> Complex64 {
        let Some(t) = self.lag_s else {
            return Complex64::from(1.0);
        };
        let st = Complex64::new(0.0, std::f64::consts::TAU * f_hz * t);
        match self.lag_damping {
            Some(zeta) => 1.0 / (1.0 + 2.0 * zeta * st + st * st),
            None => 1.0 / (1.0 + st),
        }
    }

    /// The lag's gain `|L(j 2 pi f)|` at `f_hz` (1 without a lag).
    #[must_use]
    pub fn lag_gain(&self, f_hz: f64) -> f64 {
        self.lag_at(f_hz).norm()
    }

    /// Whether the accepted lag can hold an identified `gain_changes_across_band` warning `w`:
    /// its gain changes across the warning's band the way the warning says (a first-order lag's
    /// falls), or peaks inside it (a second-order lag damped below `1 / sqrt 2`, whose gain rises
    /// to its peak and falls beyond), as a mode's does ([`Resonance::explains`]).
    #[must_use]
    pub fn lag_explains(&self, w: &crate::ident::warnings::IdentWarning) -> bool {
        let Some(t) = self.lag_s.filter(|t| *t > 0.0) else {
            return false;
        };
        let peak_hz = self
            .lag_damping
            .filter(|z| 2.0 * z * z < 1.0)
            .map(|z| (1.0 - 2.0 * z * z).sqrt() / (std::f64::consts::TAU * t));
        explains_gain_change(w, peak_hz, |f| self.lag_gain(f))
    }

    /// The poles the effects give the response, `[re, im]` rad/s (the lag's, each resonance's
    /// upper one and its conjugate).
    #[must_use]
    pub fn poles(&self) -> Vec<[f64; 2]> {
        let mut poles: Vec<[f64; 2]> = Vec::new();
        match (self.lag_s.filter(|t| *t > 0.0), self.lag_damping) {
            (Some(t), None) => poles.push([-1.0 / t, 0.0]),
            // The roots of (T s)^2 + 2 zeta T s + 1: a pair, or two real ones when overdamped.
            (Some(t), Some(zeta)) if zeta < 1.0 => {
                let (re, im) = (-zeta / t, (1.0 - zeta * zeta).sqrt() / t);
                poles.extend([[re, im], [re, -im]]);
            }
            (Some(t), Some(zeta)) => {
                let root = (zeta * zeta - 1.0).sqrt();
                poles.extend([[(-zeta + root) / t, 0.0], [(-zeta - root) / t, 0.0]]);
            }
            (None, _) => {}
        }
        for r in &self.resonances {
            let w = std::f64::consts::TAU * r.frequency_hz;
            let (re, im) = (-r.damping * w, w * (1.0 - r.damping * r.damping).max(0.0).sqrt());
            poles.push([re, im]);
            poles.push([re, -im]);
        }
        poles
    }
}

#[cfg(test)]
#[path = "effects_tests.rs"]
mod tests;
