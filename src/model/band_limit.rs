//! The shape of a stand's angle-measurement low-pass `H(s)` as the diagnosis sizes it
//! ([`crate::effect::Effect::ReferenceBandLimit`], `crate::diagnose::band_limit`): the
//! inputs computed from the angles are `H u`, so the block's outputs read `1 / H(s)` times its
//! response against them. Kept in a block's extended model (`super::ModelEffects`), whose
//! response is then the response against this stand's angles.
//!
//! Units: time constants in s, frequencies in Hz; `T` is `1 / (2 pi f_c)`, `f_c` the corner
//! (where `|H| = 1 / sqrt 2`), except for [`BandLimitShape::Interpolated`], whose `T` is the
//! reference's sample period `1 / f_r` and whose corner is `0.3189 f_r`.

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
    /// `H = sinc^2(f T)`, no phase: a reference sampled every `T` (at `f_r = 1 / T`) and
    /// interpolated linearly onto the run's samples, on average over where the run's samples
    /// fall between the reference's (a motion-capture reference resampled onto an IMU's). The
    /// order-1 zero-phase shape is its second-order approximation (`T_1 = T / sqrt 6`), whose
    /// rise falls 1 % short at `f = 0.05 f_r`, 13 % at `0.2 f_r` and 27 % at `0.3 f_r`.
    Interpolated,
}

/// Where `sinc^2(x)` is `1 / sqrt 2`: the interpolated shape's corner is this over `T`.
pub const INTERPOLATED_CORNER: f64 = 0.318_916_698_685_223;

/// How far towards the reference's rate (`f T`) the interpolated shape's inverse is followed:
/// beyond, it is held (it grows without bound towards `f = f_r`, where `sinc^2` vanishes; a
/// search's trial `T` may reach there, a fitted one does not).
const INTERPOLATED_REACH: f64 = 0.9;

impl BandLimitShape {
    /// The shapes the candidate tries.
    pub const SHAPES: [BandLimitShape; 6] = [
        BandLimitShape::ZeroPhase { order: 1 },
        BandLimitShape::ZeroPhase { order: 2 },
        BandLimitShape::ZeroPhase { order: 4 },
        BandLimitShape::ZeroPhase { order: 8 },
        BandLimitShape::Causal2,
        BandLimitShape::Interpolated,
    ];

    /// `1 / H` at `f_hz` with time constant `t_s`: what the block's response is multiplied by.
    #[must_use]
    pub fn inverse_at(self, t_s: f64, f_hz: f64) -> Complex64 {
        let x = 2.0 * PI * f_hz * t_s;
        match self {
            BandLimitShape::ZeroPhase { order } => Complex64::from((1.0 + x.powi(2 * order)).sqrt()),
            BandLimitShape::Causal2 => Complex64::new(1.0 - x * x, SQRT_2 * x),
            BandLimitShape::Interpolated => {
                let y = PI * (f_hz * t_s).abs().min(INTERPOLATED_REACH);
                let sinc = if y < 1e-4 { 1.0 - y * y / 6.0 } else { y.sin() / y };
                Complex64::from(1.0 / (sinc * sinc))
            }
        }
    }

    /// The Butterworth order of the shape; `None` for the interpolated shape (not a
    /// Butterworth).
    #[must_use]
    pub fn order(self) -> Option<i32> {
        match self {
            BandLimitShape::ZeroPhase { order } => Some(order),
            BandLimitShape::Causal2 => Some(2),
            BandLimitShape::Interpolated => None,
        }
    }

    /// The shape's name in the model file and the discrepancy report (`shape`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BandLimitShape::ZeroPhase { .. } => "zero_phase",
            BandLimitShape::Causal2 => "causal2",
            BandLimitShape::Interpolated => "interpolated",
        }
    }

    /// The corner (where `|H| = 1 / sqrt 2`) for `T = t_s`, Hz; `None` at `T = 0` (no band
    /// limit) and where it is not finite (a `T` so small its inverse overflows).
    #[must_use]
    pub fn corner_hz(self, t_s: f64) -> Option<f64> {
        (t_s > 0.0)
            .then(|| self.corner_times_t() / t_s)
            .filter(|c| c.is_finite())
    }

    /// The interpolated shape's reference rate `1 / T`, Hz; `None` for the other shapes and
    /// where `corner_hz` is.
    #[must_use]
    pub fn reference_rate_hz(self, t_s: f64) -> Option<f64> {
        (self == BandLimitShape::Interpolated && t_s > 0.0)
            .then(|| 1.0 / t_s)
            .filter(|r| r.is_finite())
    }

    /// `corner x T`: `1 / (2 pi)`, or [`INTERPOLATED_CORNER`].
    #[must_use]
    pub fn corner_times_t(self) -> f64 {
        match self {
            BandLimitShape::Interpolated => INTERPOLATED_CORNER,
            _ => 1.0 / (2.0 * PI),
        }
    }

    /// The `T` at which `|1 / H|` rises by `rise` at `f_hz` (a search's start): exact for the
    /// Butterworth shapes, the low-frequency approximation `1 + (pi f T)^2 / 3` for the
    /// interpolated one (within its reach).
    #[must_use]
    pub fn t_for_rise(self, rise: f64, f_hz: f64) -> f64 {
        match self.order() {
            Some(m) => {
                let x = ((1.0 + rise).powi(2) - 1.0).powf(1.0 / (2.0 * f64::from(m)));
                x / (2.0 * PI * f_hz)
            }
            None => (3.0 * rise).sqrt().min(0.5) / (PI * f_hz),
        }
    }

    /// The shape a band-limit finding's parameters name (`shape`, and `order` for the zero-phase
    /// Butterworths), as the discrepancy report writes them; a report written before findings
    /// named their shape has `causal` and `order` only: `causal2`, or `zero_phase` of that order.
    /// `None` where they name none of [`Self::SHAPES`].
    #[must_use]
    pub fn from_parameters(p: &serde_json::Value) -> Option<Self> {
        let order = p
            .get("order")
            .and_then(serde_json::Value::as_i64)
            .and_then(|m| i32::try_from(m).ok());
        let causal = p.get("causal").and_then(serde_json::Value::as_bool);
        let name = match p.get("shape") {
            Some(v) => v.as_str()?,
            None if causal? => "causal2",
            None => "zero_phase",
        };
        let shape = match name {
            "zero_phase" => Self::ZeroPhase { order: order? },
            "causal2" => Self::Causal2,
            "interpolated" => Self::Interpolated,
            _ => return None,
        };
        Self::SHAPES.contains(&shape).then_some(shape)
    }

    /// The shape in a few words: its name, and a Butterworth's order (`zero_phase order 4`,
    /// `causal2 order 2`, `interpolated`).
    #[must_use]
    pub fn label(self) -> String {
        match self.order() {
            Some(m) => format!("{} order {m}", self.name()),
            None => self.name().to_owned(),
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
                "a band limit's shape must be zero_phase of order 1, 2, 4 or 8, causal2 or interpolated: {:?}",
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
    fn the_interpolated_shape_is_the_inverse_of_sinc_squared() {
        let f_r = 120.0;
        let t = 1.0 / f_r;
        let shape = BandLimitShape::Interpolated;
        for f in [0.5, 10.0, 30.0, 60.0] {
            // sinc^2 from its series, independent of the shape's closed form.
            let y = PI * f / f_r;
            let series: f64 = (0..30)
                .map(|k| (-1f64).powi(k) * y.powi(2 * k) / (2..=2 * k + 1).map(f64::from).product::<f64>())
                .sum();
            let exact = 1.0 / (series * series);
            let inverse = shape.inverse_at(t, f);
            assert!(
                (inverse.re - exact).abs() < 1e-12 * exact && inverse.im == 0.0,
                "{f}: {inverse}"
            );
        }
        // Its corner: sinc^2 = 1 / sqrt 2 there.
        let corner = shape.corner_hz(t).expect("corner");
        assert!((shape.inverse_at(t, corner).re - SQRT_2).abs() < 1e-6, "{corner}");
        assert!(shape.corner_hz(0.0).is_none() && shape.order().is_none());
        assert!(shape.corner_hz(1e-320).is_none() && shape.reference_rate_hz(1e-320).is_none());
        assert_eq!(shape.reference_rate_hz(t), Some(f_r));
        assert!(BandLimitShape::Causal2.reference_rate_hz(t).is_none());
        // Held beyond its reach, finite at the reference's rate.
        assert!(shape.inverse_at(t, f_r).re.is_finite());
        assert_eq!(shape.inverse_at(t, f_r), shape.inverse_at(t, 0.95 * f_r));
        // The start: a rise of 2 % at 30 Hz within 2 % of it.
        let t0 = shape.t_for_rise(0.02, 30.0);
        assert!((shape.rise_at(t0, 30.0) / 0.02 - 1.0).abs() < 0.02, "{t0}");
        for s in BandLimitShape::SHAPES.into_iter().filter(|s| s.order().is_some()) {
            let t0 = s.t_for_rise(0.05, 30.0);
            assert!((s.rise_at(t0, 30.0) - 0.05).abs() < 1e-12, "{s:?}");
        }
    }

    #[test]
    fn a_findings_parameters_name_its_shape() {
        // As the discrepancy report writes them (diagnose::report): each shape read back.
        for s in BandLimitShape::SHAPES {
            let mut p = serde_json::json!({ "shape": s.name(), "causal": s.causal(), "T_s": 0.002 });
            if let Some(m) = s.order() {
                p["order"] = serde_json::json!(m);
            }
            assert_eq!(BandLimitShape::from_parameters(&p), Some(s), "{p}");
        }
        // A report written before shapes were named.
        let old = |causal: bool, order: i64| serde_json::json!({ "causal": causal, "order": order });
        assert_eq!(
            BandLimitShape::from_parameters(&old(true, 2)),
            Some(BandLimitShape::Causal2)
        );
        assert_eq!(
            BandLimitShape::from_parameters(&old(false, 4)),
            Some(BandLimitShape::ZeroPhase { order: 4 })
        );
        // Names none of the shapes tried.
        for bad in [
            serde_json::json!({ "shape": "zero_phase", "order": 3 }),
            serde_json::json!({ "shape": "zero_phase" }),
            serde_json::json!({ "shape": "bessel", "order": 2 }),
            serde_json::json!({ "shape": 2 }),
            serde_json::json!({ "order": 1 }),
            serde_json::json!({ "causal": false, "order": 3 }),
        ] {
            assert_eq!(BandLimitShape::from_parameters(&bad), None, "{bad}");
        }
        assert_eq!(
            BandLimitShape::ZeroPhase { order: 8 }.label(),
            "zero_phase order 8"
        );
        assert_eq!(BandLimitShape::Interpolated.label(), "interpolated");
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
        let json = serde_json::to_string(&FittedBandLimit {
            shape: BandLimitShape::Interpolated,
            t_s: 0.01,
        })
        .expect("written");
        assert_eq!(json, r#"{"shape":"interpolated","T_s":0.01}"#);
        for bad in [
            r#"{"shape":"zero_phase","order":0,"T_s":0.001}"#,
            r#"{"shape":"zero_phase","order":2147483647,"T_s":0.001}"#,
            r#"{"shape":"causal2","T_s":-0.001}"#,
            r#"{"shape":"lowpass","T_s":0.001}"#,
            r#"{"shape":"causal2"}"#,
            r#"{"shape":"interpolated","T_s":"0.01"}"#,
        ] {
            assert!(serde_json::from_str::<FittedBandLimit>(bad).is_err(), "{bad}");
        }
    }
}
