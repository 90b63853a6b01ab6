//! The part of a block's residual that is the reference's, not the sensor's: the block's input
//! is computed from the stand's measured angles, and the observer's angle error `e` (its
//! [`ErrorPsd`]) reaches the residual through the model (`r = n - K e_u`). It is independent of
//! the sensor's own noise `n`, so its Allan variance adds to the sensor's and is subtracted.
//!
//! First order in the angle error: at each instant the block's input is a function of the
//! Euler angles, rates and accelerations (`stand::kinematics`), so an angle error `e_j` at
//! angular frequency `w` moves input channel `i` by `(A_ij + j w B_ij - w^2 C_ij) e_j`, where
//! `A`, `B`, `C` are the Jacobians with respect to angle, rate and acceleration. Through the
//! model's gain `K` and averaged over the record (256 instants), channel `i` receives
//! `S_i(f) = sum_j E[(A'_ij - w^2 C'_ij)^2 + w^2 B'_ij^2] S_e,j(f)`, `A' = K A` and so on: the
//! rate error for the gyro, the tilt against gravity and the lever-arm acceleration for the
//! accelerometer, with the stand's own attitudes. The Allan variance of a one-sided density is
//! `2 int S(f) sin^4(pi f tau) / (pi f tau)^2 df` (IEEE 952 eq. C.2).

use nalgebra::{Matrix3, Vector3};

use crate::block::Block;
use crate::stand::kinematics::{EulerSeries, EulerState, body_rate, specific_force};
use crate::stand::observer::ErrorPsd;

/// What the reference contributes to one channel's residual: a one-sided density on bands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReferencePsd {
    /// Band edges, Hz.
    pub edges_hz: Vec<f64>,
    /// Mean density per band, output units^2/Hz.
    pub psd: Vec<f64>,
}

/// The geometry the accelerometer's input depends on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelGeometry {
    /// Gravity, m/s^2.
    pub g_mps2: f64,
    /// Declared lever arm, m.
    pub lever_arm_m: [f64; 3],
}

impl AccelGeometry {
    /// The geometry declared in `run`'s sidecar.
    #[must_use]
    pub fn of(run: &crate::run::Run) -> Self {
        Self {
            g_mps2: run.sidecar.g_mps2,
            lever_arm_m: run.sidecar.accel_lever_arm_m,
        }
    }
}

/// Instants the Jacobians are averaged over.
const INSTANTS: usize = 256;

/// Time averages of the squared Jacobians through `K`: `E[A^2], E[A C], E[C^2], E[B^2]` per
/// (channel, angle axis).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sensitivity {
    a2: [[f64; 3]; 3],
    ac: [[f64; 3]; 3],
    c2: [[f64; 3]; 3],
    b2: [[f64; 3]; 3],
}

fn sensitivity(
    block: Block,
    k: &[[f64; 3]; 3],
    motion: &EulerSeries,
    geometry: AccelGeometry,
) -> Sensitivity {
    let kk = Matrix3::from_fn(|i, j| k[i][j]);
    let arm = Vector3::from(geometry.lever_arm_m);
    let input = |e: &EulerState| match block {
        Block::Gyro => body_rate(e),
        Block::Accel => specific_force(e, &arm, geometry.g_mps2),
    };
    let mut out = Sensitivity::default();
    let n = motion.len();
    if n == 0 {
        return out;
    }
    let count = INSTANTS.min(n);
    let h = 1e-6;
    for s in 0..count {
        let e = motion.at(s * n / count);
        let base = input(&e);
        let column = |perturb: &dyn Fn(&mut EulerState)| {
            let mut p = e;
            perturb(&mut p);
            kk * (input(&p) - base) / h
        };
        for j in 0..3 {
            let a = column(&|p| p.angle[j] += h);
            let b = column(&|p| p.rate[j] += h);
            let c = column(&|p| p.accel[j] += h);
            for i in 0..3 {
                out.a2[i][j] += a[i] * a[i];
                out.ac[i][j] += a[i] * c[i];
                out.c2[i][j] += c[i] * c[i];
                out.b2[i][j] += b[i] * b[i];
            }
        }
    }
    let scale = 1.0 / count as f64;
    for m in [&mut out.a2, &mut out.ac, &mut out.c2, &mut out.b2] {
        m.iter_mut().flatten().for_each(|v| *v *= scale);
    }
    out
}

/// The reference's density in each output channel of `block` with static gain `k`, for the
/// observer's angle error `error` along the record's `motion`.
#[must_use]
pub fn reference_psd(
    block: Block,
    k: &[[f64; 3]; 3],
    motion: &EulerSeries,
    error: &ErrorPsd,
    geometry: AccelGeometry,
) -> [ReferencePsd; 3] {
    let sens = sensitivity(block, k, motion, geometry);
    std::array::from_fn(|i| ReferencePsd {
        edges_hz: error.edges_hz.clone(),
        psd: error
            .frequency_hz
            .iter()
            .zip(&error.psd)
            .map(|(f, se)| {
                let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
                (0..3)
                    .map(|j| {
                        let gain = sens.a2[i][j] - 2.0 * w2 * sens.ac[i][j]
                            + w2 * w2 * sens.c2[i][j]
                            + w2 * sens.b2[i][j];
                        gain.max(0.0) * se[j]
                    })
                    .sum()
            })
            .collect(),
    })
}

impl ReferencePsd {
    /// Its Allan variance at `tau_s`.
    #[must_use]
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.psd
            .iter()
            .enumerate()
            .map(|(b, s)| s * kernel_integral(self.edges_hz[b], self.edges_hz[b + 1], tau_s))
            .sum()
    }
}

/// `int_a^b 2 sin^4(pi f tau) / (pi f tau)^2 df`: exact mean of `sin^4` (3/8) where the band
/// holds many of its periods, midpoint sums otherwise.
fn kernel_integral(a: f64, b: f64, tau: f64) -> f64 {
    if !(b > a && a >= 0.0 && tau > 0.0) {
        return 0.0;
    }
    let pi_tau = std::f64::consts::PI * tau;
    let periods = (b - a) * tau;
    if periods > 8.0 && a * tau > 1.0 {
        // 2 (3/8) / (pi tau)^2 int f^-2 df
        return 0.75 / (pi_tau * pi_tau) * (1.0 / a - 1.0 / b);
    }
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "periods <= 8 here"
    )]
    let steps = (32.0 * periods.max(1.0)).ceil() as usize;
    let h = (b - a) / steps as f64;
    (0..steps)
        .map(|i| {
            let x = pi_tau * (a + (i as f64 + 0.5) * h);
            if x == 0.0 {
                0.0
            } else {
                2.0 * x.sin().powi(4) / (x * x)
            }
        })
        .sum::<f64>()
        * h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_density_gives_the_white_rate_allan_variance() {
        // One-sided density S0 from 0 to a high cut: sigma^2 = S0 / (2 tau) once tau >> 1/cut.
        let mut edges = vec![0.0];
        let mut f = 1e-3;
        while f < 2000.0 {
            edges.push(f);
            f *= 10.0_f64.powf(0.05);
        }
        let r = ReferencePsd {
            psd: vec![4e-6; edges.len() - 1],
            edges_hz: edges,
        };
        for tau in [0.05, 1.0, 20.0] {
            let want = 4e-6 / (2.0 * tau);
            let got = r.avar(tau);
            assert!((got / want - 1.0).abs() < 0.02, "tau {tau}: {got} vs {want}");
        }
    }

    #[test]
    fn high_frequency_noise_looks_like_white_phase() {
        // Noise in 50..60 Hz seen at tau = 2 s: 0.75/(pi tau)^2 (1/50 - 1/60) S0.
        let r = ReferencePsd {
            edges_hz: vec![50.0, 60.0],
            psd: vec![1.0],
        };
        let pi_tau = std::f64::consts::PI * 2.0;
        let want = 0.75 / (pi_tau * pi_tau) * (1.0 / 50.0 - 1.0 / 60.0);
        assert!((r.avar(2.0) / want - 1.0).abs() < 1e-12);
        // ... and the sampled branch agrees with the averaged one where both apply.
        let sampled = kernel_integral(50.0, 50.5, 2.0);
        let averaged = 0.75 / (pi_tau * pi_tau) * (1.0 / 50.0 - 1.0 / 50.5);
        assert!((sampled / averaged - 1.0).abs() < 0.01, "{sampled} vs {averaged}");
    }
}

#[cfg(test)]
mod warning_tests {
    use super::ReferencePsd;
    use crate::block::Block;
    use crate::noise::{NoiseWarning, block_noise};
    use crate::rng::Rng;

    #[test]
    fn a_dominating_reference_is_named_and_a_negligible_one_is_not() {
        let fs = 100.0;
        let mut rng = Rng::new(9);
        let r: [Vec<f64>; 3] = std::array::from_fn(|_| (0..20_000).map(|_| 1e-3 * rng.normal()).collect());
        let names = ["gx", "gy", "gz"];
        let band = |density: f64| {
            std::array::from_fn(|_| ReferencePsd {
                edges_hz: vec![20.0, 50.0],
                psd: vec![density],
            })
        };
        // White residual of one-sided density 2e-6 / 100 = 2e-8: a reference of 1e-6 above 20 Hz
        // dominates the shortest averaging times; one of 1e-12 does not.
        let strong = block_noise(Block::Gyro, names, &r, fs, Some(&band(1e-6))).expect("figures");
        assert!(
            matches!(strong.warnings[..], [NoiseWarning::ReferenceDominated { up_to_tau_s }] if up_to_tau_s < 1.0)
        );
        let weak = block_noise(Block::Gyro, names, &r, fs, Some(&band(1e-12))).expect("figures");
        assert!(weak.warnings.is_empty(), "{:?}", weak.warnings);
        assert!(
            block_noise(
                Block::Gyro,
                names,
                &[vec![0.0; 10], vec![0.0; 10], vec![0.0; 10]],
                fs,
                None
            )
            .is_none()
        );
    }
}
