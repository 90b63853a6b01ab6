//! The shape of a stand's angle-measurement low-pass `H(s)` as the diagnosis sizes it
//! ([`crate::effect::Effect::ReferenceBandLimit`], `crate::diagnose::band_limit`): the
//! inputs computed from the angles are `H u`, so the block's outputs read `1 / H(s)` times its
//! response against them. Kept in a block's extended model (`super::ModelEffects`), whose
//! response is then the response against this stand's angles.
//!
//! Units: time constants in s, frequencies in Hz; `T` is `1 / (2 pi f_c)`, `f_c` the corner.

use std::f64::consts::{PI, SQRT_2};

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// The shape of the angle measurement's low-pass `H` (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum BandLimitShape {
    /// `|H| = 1 / sqrt(1 + (w T)^(2 order))`, no phase.
    ZeroPhase {
        /// The Butterworth order `m`.
        order: i32,
    },
    /// `H = 1 / (1 + sqrt(2) s T + (s T)^2)`.
    Causal2,
}

impl BandLimitShape {
    /// The shapes the candidate tries.
    pub const SHAPES: [BandLimitShape; 5] = [
        BandLimitShape::ZeroPhase { order: 1 },
        BandLimitShape::ZeroPhase { order: 2 },
        BandLimitShape::ZeroPhase { order: 4 },
        BandLimitShape::ZeroPhase { order: 8 },
        BandLimitShape::Causal2,
    ];

    /// `1 / H` at `f_hz` with time constant `t_s`: what the block's response is multiplied by.
    #[must_use]
    pub fn inverse_at(self, t_s: f64, f_hz: f64) -> Complex64 {
        let x = 2.0 * PI * f_hz * t_s;
        match self {
            BandLimitShape::ZeroPhase { order } => Complex64::from((1.0 + x.powi(2 * order)).sqrt()),
            BandLimitShape::Causal2 => Complex64::new(1.0 - x * x, SQRT_2 * x),
        }
    }

    /// The Butterworth order of the shape.
    #[must_use]
    pub fn order(self) -> i32 {
        match self {
            BandLimitShape::ZeroPhase { order } => order,
            BandLimitShape::Causal2 => 2,
        }
    }

    /// Whether the shape has phase (a causal filter).
    #[must_use]
    pub fn causal(self) -> bool {
        self == BandLimitShape::Causal2
    }

    /// `|1 / H| - 1` at `f_hz`: how far the outputs rise over the inputs there.
    #[must_use]
    pub fn rise_at(self, t_s: f64, f_hz: f64) -> f64 {
        self.inverse_at(t_s, f_hz).norm() - 1.0
    }

    /// The group delay the shape adds at low frequency, s (the block's delay takes it).
    #[must_use]
    pub fn group_delay_s(self, t_s: f64) -> f64 {
        if self.causal() { SQRT_2 * t_s } else { 0.0 }
    }
}

/// A fitted angle-measurement low-pass: its shape and time constant. Read from a model file
/// only when the shape is one of [`BandLimitShape::SHAPES`] and `T` is finite and not negative.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawBandLimit")]
pub struct FittedBandLimit {
    /// The shape.
    #[serde(flatten)]
    pub shape: BandLimitShape,
    /// `T`, s (`T_s` in JSON, as in the discrepancy report's parameters).
    #[serde(rename = "T_s")]
    pub t_s: f64,
}

/// [`FittedBandLimit`] as read, before its check.
#[derive(Deserialize)]
struct RawBandLimit {
    #[serde(flatten)]
    shape: BandLimitShape,
    #[serde(rename = "T_s")]
    t_s: f64,
}

impl TryFrom<RawBandLimit> for FittedBandLimit {
    type Error = String;

    fn try_from(raw: RawBandLimit) -> Result<Self, String> {
        if !BandLimitShape::SHAPES.contains(&raw.shape) {
            return Err(format!(
                "a band limit's shape must be zero_phase of order 1, 2, 4 or 8, or causal2: {:?}",
                raw.shape
            ));
        }
        if !(raw.t_s.is_finite() && raw.t_s >= 0.0) {
            return Err(format!(
                "a band limit's T_s must be finite and not negative: {}",
                raw.t_s
            ));
        }
        Ok(Self {
            shape: raw.shape,
            t_s: raw.t_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{PI, SQRT_2};

    use num_complex::Complex64;

    use super::*;

    #[test]
    fn linear_interpolation_is_order_one_at_low_frequency() {
        // 1 / sinc^2(f / f_r) ~ 1 + (pi f / f_r)^2 / 3 = 1 + w^2 / (12 f_r^2); T = 1 / (sqrt 6 f_r).
        let f_r = 120.0;
        let t = 1.0 / (6f64.sqrt() * f_r);
        for f in [1.0, 3.0, 6.0] {
            let sinc = (PI * f / f_r).sin() / (PI * f / f_r);
            let exact = 1.0 / (sinc * sinc) - 1.0;
            let rise = BandLimitShape::ZeroPhase { order: 1 }.rise_at(t, f);
            assert!((rise - exact).abs() < 0.02 * exact, "{f}: {rise} vs {exact}");
        }
    }

    #[test]
    fn the_causal_shape_inverts_a_second_order_butterworth() {
        let (t, fc) = (2e-3, 1.0 / (2.0 * PI * 2e-3));
        for f in [1.0, 20.0, fc, 150.0] {
            let s = Complex64::new(0.0, 2.0 * PI * f);
            let w = 1.0 / t;
            let h = w * w / (s * s + SQRT_2 * w * s + w * w);
            let product = h * BandLimitShape::Causal2.inverse_at(t, f);
            assert!((product - 1.0).norm() < 1e-12, "{f}: {product}");
            // Its magnitude is the order-2 zero-phase shape's.
            let zp = BandLimitShape::ZeroPhase { order: 2 }.inverse_at(t, f);
            assert!((1.0 / h.norm() - zp.re).abs() < 1e-9 * zp.re);
        }
        assert!((BandLimitShape::Causal2.group_delay_s(t) - SQRT_2 * t).abs() < 1e-15);
        assert!(BandLimitShape::ZeroPhase { order: 4 }.group_delay_s(t).abs() < 1e-300);
    }

    #[test]
    fn a_band_limit_round_trips_through_json_and_bad_ones_are_refused() {
        for shape in BandLimitShape::SHAPES {
            let b = FittedBandLimit { shape, t_s: 2e-3 };
            let json = serde_json::to_string(&b).expect("written");
            assert_eq!(
                serde_json::from_str::<FittedBandLimit>(&json).ok(),
                Some(b),
                "{json}"
            );
        }
        let json = serde_json::to_string(&FittedBandLimit {
            shape: BandLimitShape::ZeroPhase { order: 4 },
            t_s: 1e-3,
        })
        .expect("written");
        assert_eq!(json, r#"{"shape":"zero_phase","order":4,"T_s":0.001}"#);
        for bad in [
            r#"{"shape":"zero_phase","order":0,"T_s":0.001}"#,
            r#"{"shape":"zero_phase","order":2147483647,"T_s":0.001}"#,
            r#"{"shape":"causal2","T_s":-0.001}"#,
            r#"{"shape":"lowpass","T_s":0.001}"#,
            r#"{"shape":"causal2"}"#,
        ] {
            assert!(serde_json::from_str::<FittedBandLimit>(bad).is_err(), "{bad}");
        }
    }
}
