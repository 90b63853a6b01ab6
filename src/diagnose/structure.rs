//! The parametric model the diagnosis fits: the paper's `x = K e^(-tau s) u` extended by any set
//! of catalogue effects, split into the parameters it is linear in (`K`, `k2`, `G`, the lever-arm
//! offset: solved by weighted least squares) and those it is not (`tau`, channel skews, the lag's
//! time constant, resonances: searched). Tones are fitted apart, on the whole-record bins
//! (`tone.rs`), since they are incoherent with every regressor.
//!
//! Per output channel `i`, with `s = 2 pi i f`:
//! `x_i = c_i(s) [sum_j K_ij M_j(s) u_j + k2_i q_i + sum_l dr_l df_i/dr_l] + d(s) sum_j G_ij f_j`,
//! `d(s) = e^(-tau s) g(s)`,
//! `c_i(s) = g(s) e^(-(tau + skew_i) s) L(s)`, `M_j(s) = w^2 / (s^2 + 2 zeta w s + w^2)` on
//! resonant axes (1 elsewhere), `q_i = u_i |u_i|`. The lever-arm term uses `K ~ I` (its gain
//! errors, of order 1e-3, change the offset's estimate by as little). `g(s) = 1 / H(s)` undoes the
//! stand's band limit (the angle measurement through a low-pass `H`, so the inputs computed from
//! the angles fall short of the motion), 1 unless [`Structure::band_limit`] gives its shape
//! (`super::band_limit`); its time constant `T >= 0` ([`Theta::band_limit_t_s`]) is searched.
//! `L(s)` is the lag ([`LagShape`]): 1 without one, `1 / (T s + 1)` first order, or
//! `1 / ((T s)^2 + 2 zeta T s + 1)` second order (a sensor's low-pass of its own: a read-out's
//! anti-alias or a configurable digital low-pass, commonly a second-order section), its damping
//! `zeta` searched between [`LAG_DAMPING`]'s bounds (below, a mode: `platform_resonance`; above,
//! a first-order lag and a little delay; a fit held at either is set aside).

use std::f64::consts::PI;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::band_limit::BandLimitShape;
use super::design::{AUX, Q, U};

/// The range of a second-order lag's damping the search keeps: from 0.5, a low-pass's section
/// with a peak of 1.15 (1.25 dB; a Butterworth's is 0.71, a Bessel's 0.87), to 4, where it is a
/// first-order lag and a little delay. A fit held at either bound is not a low-pass of this form
/// (below: a mode, `platform_resonance`; above: the first order), and is not offered
/// ([`lag_damping_held`]).
pub const LAG_DAMPING: [f64; 2] = [0.5, 4.0];

/// Whether a second-order lag's fitted damping sits at a bound of [`LAG_DAMPING`] (within 2 %).
#[must_use]
pub fn lag_damping_held(zeta: f64) -> bool {
    !(zeta > LAG_DAMPING[0] * 1.02 && zeta < LAG_DAMPING[1] / 1.02)
}

/// The form of a lag (a sensor's own bandwidth, or the stand's reference lag fitted as one), each
/// with one time constant `T` ([`Theta::lag_s`]), the second order with its damping too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LagShape {
    /// `1 / (T s + 1)`.
    FirstOrder,
    /// `1 / ((T s)^2 + 2 zeta T s + 1)`, corner `1 / (2 pi T)`.
    SecondOrder,
}

impl LagShape {
    /// Every shape, in the order the candidates are offered.
    pub const SHAPES: [Self; 2] = [Self::FirstOrder, Self::SecondOrder];

    /// The lag's response at `s` with time constant `t_s` and (second order) damping `zeta`.
    #[must_use]
    pub fn response(self, t_s: f64, zeta: f64, s: Complex64) -> Complex64 {
        let st = s * t_s;
        match self {
            Self::FirstOrder => 1.0 / (1.0 + st),
            Self::SecondOrder => 1.0 / (1.0 + 2.0 * zeta * st + st * st),
        }
    }

    /// Nonlinear parameters it adds: `T`, and the damping for the second order.
    #[must_use]
    pub fn parameters(self) -> usize {
        match self {
            Self::FirstOrder => 1,
            Self::SecondOrder => 2,
        }
    }

    /// A second-order section's -3 dB frequency over its natural frequency `1 / (2 pi T)`:
    /// `sqrt(1 - 2 zeta^2 + sqrt((1 - 2 zeta^2)^2 + 1))` (1 for a Butterworth's `1 / sqrt 2`).
    #[must_use]
    pub fn corner_ratio(zeta: f64) -> f64 {
        let a = 1.0 - 2.0 * zeta * zeta;
        (a + (a * a + 1.0).sqrt()).sqrt()
    }

    /// What a lag of this shape is, in the lab's words: the first order's is
    /// [`Effect::SensorLag`](crate::effect::Effect::SensorLag)'s.
    #[must_use]
    pub fn what(self) -> &'static str {
        match self {
            Self::FirstOrder => crate::effect::Effect::SensorLag.what(),
            Self::SecondOrder => "second-order low-pass",
        }
    }

    /// The readable name of a lag of this shape on `block`, as an effect's (`Effect::name_on`):
    /// "gyro first-order lag", "gyro second-order low-pass".
    #[must_use]
    pub fn name_on(self, block: crate::block::Block) -> String {
        format!("{} {}", block.word(), self.what())
    }

    /// The shape of a lag finding's `parameters` (a report's): second order where its `shape`
    /// says so, else first order (a first-order lag's parameters hold `T_s` alone).
    #[must_use]
    pub fn of_parameters(parameters: &serde_json::Value) -> Self {
        if parameters.get("shape").and_then(serde_json::Value::as_str) == Some(Self::SecondOrder.name()) {
            Self::SecondOrder
        } else {
            Self::FirstOrder
        }
    }

    /// The name used in reports (`"first_order"`, `"second_order"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::FirstOrder => "first_order",
            Self::SecondOrder => "second_order",
        }
    }
}

/// Which effects the model holds (besides tones).
#[derive(Clone, Debug, Default, PartialEq)]
#[expect(
    clippy::struct_excessive_bools,
    reason = "each flag is one catalogue effect present or not; a set type would only hide that"
)]
pub struct Structure {
    /// The lag's shape; `None`: no lag.
    pub lag: Option<LagShape>,
    /// Per-channel delays.
    pub skew: bool,
    /// Quadratic scale factor per channel.
    pub k2: bool,
    /// Gyro g-sensitivity matrix.
    pub g_sensitivity: bool,
    /// Accelerometer lever-arm offset.
    pub lever_arm: bool,
    /// The shape of the angle measurement's low-pass (the stand's band limit); `None`: none.
    pub band_limit: Option<BandLimitShape>,
    /// Input axes carrying a mount resonance, in the order of [`Theta::resonances`].
    pub resonance_axes: Vec<usize>,
}

/// The nonlinear parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Theta {
    /// Common delay, s.
    pub tau_s: f64,
    /// Channel skews `[a, b]`: channel delays are `tau + [a, b, -a-b]` (zero-mean gauge).
    pub skew_s: [f64; 2],
    /// Lag time constant, s.
    pub lag_s: f64,
    /// A second-order lag's damping (unused otherwise).
    pub lag_damping: f64,
    /// The stand's band limit's time constant `T`, s (module docs).
    pub band_limit_t_s: f64,
    /// `(frequency_hz, damping)` per resonant axis.
    pub resonances: Vec<(f64, f64)>,
}

impl Theta {
    /// The paper's model: a delay and nothing else.
    #[must_use]
    pub fn delay_only(tau_s: f64) -> Self {
        Self {
            tau_s,
            skew_s: [0.0; 2],
            lag_s: 0.0,
            lag_damping: 0.0,
            band_limit_t_s: 0.0,
            resonances: Vec::new(),
        }
    }

    /// Channel skews relative to the common delay, s.
    #[must_use]
    pub fn channel_skew_s(&self) -> [f64; 3] {
        let [a, b] = self.skew_s;
        [a, b, -a - b]
    }
}

/// How a linear parameter's regressor is filtered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// `c_i(s)`.
    Channel,
    /// `c_i(s) M_j(s)`.
    ChannelResonant(usize),
    /// `e^(-tau s) / H(s)` (the stand's band limit, where held, as the channels').
    Delay,
}

/// One linear parameter's appearance in one output channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// Output channel.
    pub channel: usize,
    /// Index into the linear parameter vector.
    pub param: usize,
    /// Index into the design's `z`.
    pub regressor: usize,
    /// Its filter.
    pub filter: Filter,
}

/// Where each group of linear parameters sits in the parameter vector.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// Every term.
    pub terms: Vec<Term>,
    /// Number of linear parameters.
    pub n_params: usize,
    /// First index of `k2` (3), if present.
    pub k2: Option<usize>,
    /// First index of `G` (9, row-major), if present.
    pub g: Option<usize>,
    /// First index of the lever-arm offset (3), if present.
    pub lever_arm: Option<usize>,
}

impl Structure {
    /// The linear parameters' layout: `K` row-major first, then `k2`, `G`, lever arm.
    #[must_use]
    pub fn layout(&self) -> Layout {
        let mut terms = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                terms.push(Term {
                    channel: i,
                    param: 3 * i + j,
                    regressor: U + j,
                    filter: Filter::ChannelResonant(j),
                });
            }
        }
        let mut next = 9;
        let mut block = |n: usize, present: bool| {
            present.then(|| {
                next += n;
                next - n
            })
        };
        let k2 = block(3, self.k2);
        let g = block(9, self.g_sensitivity);
        let lever_arm = block(3, self.lever_arm);
        let n_params = next;
        if let Some(p) = k2 {
            terms.extend((0..3).map(|i| Term {
                channel: i,
                param: p + i,
                regressor: Q + i,
                filter: Filter::Channel,
            }));
        }
        if let Some(p) = g {
            for i in 0..3 {
                terms.extend((0..3).map(|j| Term {
                    channel: i,
                    param: p + 3 * i + j,
                    regressor: AUX + j,
                    filter: Filter::Delay,
                }));
            }
        }
        if let Some(p) = lever_arm {
            for i in 0..3 {
                terms.extend((0..3).map(|l| Term {
                    channel: i,
                    param: p + l,
                    regressor: AUX + 3 * i + l,
                    filter: Filter::Channel,
                }));
            }
        }
        Layout {
            terms,
            n_params,
            k2,
            g,
            lever_arm,
        }
    }

    /// Number of nonlinear parameters besides `tau`.
    #[must_use]
    pub fn n_nonlinear_extra(&self) -> usize {
        2 * usize::from(self.skew)
            + self.lag.map_or(0, LagShape::parameters)
            + usize::from(self.band_limit.is_some())
            + 2 * self.resonance_axes.len()
    }
}

/// The filters at one frequency.
#[derive(Clone, Copy, Debug)]
pub struct Filters {
    /// `c_i(s)` per channel.
    pub channel: [Complex64; 3],
    /// `M_j(s)` per input axis.
    pub resonant: [Complex64; 3],
    /// `e^(-tau s)`.
    pub delay: Complex64,
}

impl Filters {
    /// The filters of `structure` with `theta` at `f` Hz.
    #[must_use]
    pub fn at(structure: &Structure, theta: &Theta, f: f64) -> Self {
        let s = Complex64::new(0.0, 2.0 * PI * f);
        let lag = structure.lag.map_or(Complex64::from(1.0), |shape| {
            shape.response(theta.lag_s, theta.lag_damping, s)
        });
        let skew = if structure.skew {
            theta.channel_skew_s()
        } else {
            [0.0; 3]
        };
        let reference = structure
            .band_limit
            .map_or(Complex64::from(1.0), |r| r.inverse_at(theta.band_limit_t_s, f));
        // One complex exponential where the channels share the delay (`tau + 0.0` is `tau`: the
        // same value as each channel's own).
        let common = (-s * theta.tau_s).exp();
        let channel = skew.map(|d| {
            let own = if d == 0.0 {
                common
            } else {
                (-s * (theta.tau_s + d)).exp()
            };
            own * lag * reference
        });
        let mut resonant = [Complex64::from(1.0); 3];
        for (&axis, &(f_r, zeta)) in structure.resonance_axes.iter().zip(&theta.resonances) {
            let w = 2.0 * PI * f_r;
            resonant[axis] *= w * w / (s * s + 2.0 * zeta * w * s + w * w);
        }
        Self {
            channel,
            resonant,
            // The specific force the g-sensitivity reads is computed from the angles too.
            delay: common * reference,
        }
    }

    /// The factor of a term.
    #[must_use]
    pub fn factor(&self, term: &Term) -> Complex64 {
        match term.filter {
            Filter::Channel => self.channel[term.channel],
            Filter::ChannelResonant(j) => self.channel[term.channel] * self.resonant[j],
            Filter::Delay => self.delay,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LagShape;
    use crate::block::Block;
    use crate::effect::Effect;
    use serde_json::json;

    #[test]
    fn a_lag_s_shapes_are_named_and_read_back() {
        // The first order's name is the effect's.
        assert_eq!(
            LagShape::FirstOrder.name_on(Block::Gyro),
            Effect::SensorLag.name_on(Block::Gyro)
        );
        assert_eq!(
            LagShape::SecondOrder.name_on(Block::Accel),
            "accelerometer second-order low-pass"
        );
        for shape in LagShape::SHAPES {
            let p = json!({"T_s": 0.002, "shape": shape.name()});
            assert_eq!(LagShape::of_parameters(&p), shape);
        }
        // A first-order lag's parameters hold T_s alone.
        assert_eq!(
            LagShape::of_parameters(&json!({"T_s": 0.002})),
            LagShape::FirstOrder
        );
    }
}
