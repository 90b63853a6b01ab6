//! The parametric model the diagnosis fits: the paper's `x = K e^(-tau s) u` extended by any set
//! of catalogue effects, split into the parameters it is linear in (`K`, `k2`, `G`, the lever-arm
//! offset: solved by weighted least squares) and those it is not (`tau`, channel skews, the lag's
//! time constant, resonances: searched). Tones are fitted apart, on the whole-record bins
//! (`tone.rs`), since they are incoherent with every regressor.
//!
//! Per output channel `i`, with `s = 2 pi i f`:
//! `x_i = c_i(s) [sum_j K_ij M_j(s) u_j + k2_i q_i + sum_l dr_l df_i/dr_l] + d(s) sum_j G_ij f_j`,
//! `d(s) = e^(-tau s) g(s)`,
//! `c_i(s) = g(s) e^(-(tau + skew_i) s) / (T s + 1)`, `M_j(s) = w^2 / (s^2 + 2 zeta w s + w^2)` on
//! resonant axes (1 elsewhere), `q_i = u_i |u_i|`. The lever-arm term uses `K ~ I` (its gain
//! errors, of order 1e-3, change the offset's estimate by as little). `g(s) = 1 / H(s)` undoes the
//! stand's band limit (the angle measurement through a low-pass `H`, so the inputs computed from
//! the angles fall short of the motion), 1 unless [`Structure::band_limit`] gives its shape
//! (`super::band_limit`); its time constant `T >= 0` ([`Theta::band_limit_t_s`]) is searched.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::band_limit::BandLimitShape;
use super::design::{AUX, Q, U};

/// Which effects the model holds (besides tones).
#[derive(Clone, Debug, Default, PartialEq)]
#[expect(
    clippy::struct_excessive_bools,
    reason = "each flag is one catalogue effect present or not; a set type would only hide that"
)]
pub struct Structure {
    /// First-order lag `1/(T s + 1)`.
    pub lag: bool,
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
            + usize::from(self.lag)
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
        let lag = if structure.lag {
            1.0 / (1.0 + s * theta.lag_s)
        } else {
            Complex64::from(1.0)
        };
        let skew = if structure.skew {
            theta.channel_skew_s()
        } else {
            [0.0; 3]
        };
        let reference = structure
            .band_limit
            .map_or(Complex64::from(1.0), |r| r.inverse_at(theta.band_limit_t_s, f));
        let channel = skew.map(|d| (-s * (theta.tau_s + d)).exp() * lag * reference);
        let mut resonant = [Complex64::from(1.0); 3];
        for (&axis, &(f_r, zeta)) in structure.resonance_axes.iter().zip(&theta.resonances) {
            let w = 2.0 * PI * f_r;
            resonant[axis] *= w * w / (s * s + 2.0 * zeta * w * s + w * w);
        }
        Self {
            channel,
            resonant,
            // The specific force the g-sensitivity reads is computed from the angles too.
            delay: (-s * theta.tau_s).exp() * reference,
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
