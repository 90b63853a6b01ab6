//! Whether the block's gain changes across the band with no phase of its own: the self-check's
//! `gain_changes_across_band` ([`super::warnings::IdentWarning::GainChangesAcrossBand`]).
//!
//! A reference measured at a lower rate and interpolated onto the block's samples, or smoothed,
//! passes the motion through a zero-phase low-pass: linear interpolation from a rate `f_r`
//! weighs the angles by `sinc^2(f / f_r)` on average, `1 - (pi f / f_r)^2 / 3` at low frequency,
//! a cubic spline by a response flat to higher order that droops near `f_r / 3`. The inputs
//! computed from the angles then fall short of the motion by a factor even in `f`, and the
//! measured gain `W` rises with no phase: no delay or admissible order takes that (a rational
//! model pays for a gain rise with phase), so the delay-only model takes `K` as the band's
//! information-weighted mean gain, above the gain at low frequency. Found by a helper's hand-held
//! simulator (a 120 Hz optical reference interpolated linearly onto the gyro's samples, as the
//! real recordings' dataset was made): every diagonal of `K` read high by 0.1-1.7 %, 5 of its
//! standard deviations on average, with nothing said on most runs; the three real recordings'
//! gain rises by 6-10 % from their band's bottom to its top.
//!
//! [`curvature`] fits one common even gain `1 + b_2 omega^2 + b_4 omega^4` to the chosen model's
//! residual by generalised least squares, beside each output row's own constant `c_i` (the row's
//! gain at low frequency relative to the model's, whose `K` row took its band's mean), with the
//! weights of the self-check's per-bin chi2; two terms, so that a droop steeper than `omega^2`
//! near the band's top (a cubic spline's) is not extrapolated to low frequency as one.
//! The covariance is widened as the fit's is (the bins' correlation and `chi2/dof` where above 1).
//! How far each row of `K` reads from the gain at low frequency follows from the delay-only fit's
//! normal equations, row by row ([`Curvature::row_bias`]): a row whose weight lies at higher
//! frequencies (an axis moved faster) reads higher, and rows that share collinear inputs can read
//! low (the accelerometer's on a simulated stand).
//!
//! Units: `omega` in rad/s, `b_2` in s^2, `b_4` in s^4; `K`'s bias and the rise are relative
//! (fractions). Non-finite bins are skipped; no bins, or no information in them, give `None`.

use nalgebra::{Matrix3, RowVector3};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// One band bin: the model and the estimate there, and the weights of the estimate's rows.
#[derive(Clone, Copy, Debug)]
pub struct Bin {
    /// Angular frequency, rad/s.
    pub omega: f64,
    /// The chosen model's response as the estimate sees it.
    pub model: Matrix3<Complex64>,
    /// The estimate (`W_u`).
    pub estimate: Matrix3<Complex64>,
    /// Each output row's weight `Omega_i` (the inverse covariance of the estimate's row).
    pub weights: [Matrix3<Complex64>; 3],
}

impl Bin {
    /// The bin's chi2: `2 sum_i r_i Omega_i r_i^H` of the residual `r = estimate - model` (18
    /// real degrees of freedom expected).
    #[must_use]
    pub fn chi2(&self) -> f64 {
        let r = self.estimate - self.model;
        (0..3)
            .map(|i| {
                let row = r.row(i);
                2.0 * (row * self.weights[i] * row.adjoint())[(0, 0)].re
            })
            .sum()
    }
}

/// The fitted even gain of a block over its band (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// `[b_2, b_4]` (s^2, s^4): the gain of output row `i` relative to the model's is
    /// `1 + c_i + b_2 omega^2 + b_4 omega^4`.
    pub b: [f64; 2],
    /// Their covariance (widened).
    pub b_cov: [[f64; 2]; 2],
    /// `c_i`: each row's gain at low frequency relative to the model's, less 1 (the model's `K`
    /// row is its band's mean gain).
    pub c: [f64; 3],
    /// The band's lowest and highest `omega`, rad/s.
    pub omega_range: [f64; 2],
    /// Per output row `i` of `K`, the relative change of its scale the even gain gives the
    /// delay-only fit, against the gain at low frequency: the projection of
    /// [`Self::row_change`] on the fitted row `k_i`, over `1 + c_i`, with `A_i = sum Re Omega_i`
    /// and `M_pi = sum omega^p Re Omega_i` over the bins (its normal equations). Close to `-c_i`
    /// where the row's change is a scale alone.
    pub row_bias: [f64; 3],
    /// Per output row `i`, the whole change the even gain gives the delay-only fit's row,
    /// `k_i sum_p b_p M_pi A_i^-1` with `k_i` that fit's row (`b` is relative to the model, so no
    /// `1 + c_i` here; its scale over `1 + c_i` is [`Self::row_bias`]): that fit's `K` less this is
    /// the gain at low frequency (exactly for noise-free data and the same weights).
    pub row_change: [[f64; 3]; 3],
    /// The standard deviation of each element of [`Self::row_change`], from `b`'s covariance (the
    /// change is linear in `b`).
    pub row_change_std: [[f64; 3]; 3],
}

/// The even gain a delay-only model carries beside `K e^(-tau s)` when its block's gain changes
/// across the band with no phase ([`Curvature`]): the model's response is `g(omega) K e^(-tau s)`,
/// `g = 1 + b_2 omega^2 + b_4 omega^4`, `K` the gain at low frequency (`g(0) = 1`). Units:
/// `omega` in rad/s, `b_2` in s^2, `b_4` in s^4.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvenGain {
    /// `[b_2, b_4]`, s^2 and s^4.
    pub coefficients: [f64; 2],
    /// Their standard deviations (widened as the fit's), s^2 and s^4.
    pub coefficients_std: [f64; 2],
    /// The delay-only fit's `K` (the band's mean gain) less the gain at low frequency: the
    /// first-order [`Curvature::row_change`] from the curvature, the difference of the two fits
    /// once the block is fitted over `g` (`super::even_gain`).
    pub k_change: [[f64; 3]; 3],
    /// What `g`'s own uncertainty moves each element of `K` by (from [`Curvature::row_change`]'s
    /// deviation), added in quadrature to `K`'s.
    pub k_change_std: [[f64; 3]; 3],
    /// The top of the band it was fitted on, Hz: above it `g` is held at its value there (a
    /// polynomial in `omega` is no model of anything beyond its data; the residual, validation
    /// and noise terms evaluate the model up to the Nyquist frequency).
    pub band_top_hz: f64,
}

impl EvenGain {
    /// `g` at `f_hz` (Hz), held constant above [`Self::band_top_hz`].
    #[must_use]
    pub fn at(&self, f_hz: f64) -> f64 {
        let w2 = (std::f64::consts::TAU * f_hz.abs().min(self.band_top_hz)).powi(2);
        1.0 + self.coefficients[0] * w2 + self.coefficients[1] * w2 * w2
    }
}

impl Curvature {
    /// The common shape's gain at `omega`, relative to that at low frequency.
    fn shape(&self, omega: f64) -> f64 {
        let w2 = omega * omega;
        let level = 1.0 + self.c.iter().sum::<f64>() / 3.0;
        1.0 + (self.b[0] * w2 + self.b[1] * w2 * w2) / level
    }

    /// How far `K` reads above the gain at low frequency, relative: the mean of the rows'.
    #[cfg(test)]
    fn k_bias(&self) -> f64 {
        self.row_bias.iter().sum::<f64>() / 3.0
    }

    /// The gain's change from the band's bottom to its top, relative to the bottom's.
    #[must_use]
    pub fn rise(&self) -> f64 {
        self.shape(self.omega_range[1]) / self.shape(self.omega_range[0]) - 1.0
    }

    /// The even gain relative to the gain at low frequency, for the model ([`EvenGain`]): `b` over
    /// the rows' mean level `1 + mean(c)`.
    #[must_use]
    pub fn even_gain(&self) -> EvenGain {
        let level = 1.0 + self.c.iter().sum::<f64>() / 3.0;
        EvenGain {
            coefficients: self.b.map(|b| b / level),
            coefficients_std: [self.b_cov[0][0], self.b_cov[1][1]].map(|v| v.max(0.0).sqrt() / level),
            k_change: self.row_change,
            k_change_std: self.row_change_std,
            band_top_hz: self.omega_range[1] / std::f64::consts::TAU,
        }
    }

    /// The standard deviation of [`Self::rise`] (to first order in `b`).
    #[must_use]
    pub fn rise_std(&self) -> f64 {
        let (lo, hi) = (self.omega_range[0].powi(2), self.omega_range[1].powi(2));
        let level = 1.0 + self.c.iter().sum::<f64>() / 3.0;
        let d = [(hi - lo) / level, (hi * hi - lo * lo) / level];
        let c = &self.b_cov;
        (d[0] * d[0] * c[0][0] + 2.0 * d[0] * d[1] * c[0][1] + d[1] * d[1] * c[1][1])
            .max(0.0)
            .sqrt()
    }
}

/// `Re(x Omega r^H)` for rows `x` and `r`, `Omega` Hermitian.
fn form(x: &[Complex64; 3], omega: &Matrix3<Complex64>, r: &[Complex64; 3]) -> f64 {
    let mut q = Complex64::new(0.0, 0.0);
    for j in 0..3 {
        for l in 0..3 {
            q += x[j] * omega[(j, l)] * r[l].conj();
        }
    }
    q.re
}

fn row(m: &Matrix3<Complex64>, i: usize) -> [Complex64; 3] {
    [m[(i, 0)], m[(i, 1)], m[(i, 2)]]
}

fn finite(b: &Bin) -> bool {
    b.omega.is_finite()
        && b.model
            .iter()
            .chain(b.estimate.iter())
            .chain(b.weights.iter().flat_map(|w| w.iter()))
            .all(|z| z.re.is_finite() && z.im.is_finite())
}

/// The common even gain of `bins` (module docs) of a block whose static gain is `gain`, its
/// covariance widened by `sqrt(bin_correlation x max(1, chi2/dof))` of this fit's own residual
/// (on the bins' weights, not the structural fit's narrowed ones).
///
/// Five parameters by generalised least squares: each row's own constant `c_i` (the regressor
/// `W_i`, the model's row) and the common `b_2`, `b_4` (`omega^2 W_i`, `omega^4 W_i`), so each
/// row's mean is its own and the shape is shared. The rows' biases take the delay as fixed: the
/// even gain has no phase, so it moves the delay only through the weights' imaginary
/// cross-terms, a second-order coupling this leaves out. `None` without bins or information, or
/// when a row's bias is not finite (a zero row of `gain`).
#[must_use]
pub fn curvature(bins: &[Bin], gain: &[[f64; 3]; 3], bin_correlation: f64) -> Option<Curvature> {
    let bins: Vec<&Bin> = bins.iter().filter(|b| finite(b)).collect();
    let mut normal = nalgebra::SMatrix::<f64, 5, 5>::zeros();
    let mut rhs = nalgebra::SVector::<f64, 5>::zeros();
    let mut a = [Matrix3::<f64>::zeros(); 3];
    let mut m = [[Matrix3::<f64>::zeros(); 3]; 2];
    for b in &bins {
        let powers = [1.0, b.omega.powi(2), b.omega.powi(4)];
        for i in 0..3 {
            let re = b.weights[i].map(|z| z.re);
            a[i] += re;
            m[0][i] += re * powers[1];
            m[1][i] += re * powers[2];
            let w = row(&b.model, i);
            let r: [Complex64; 3] = std::array::from_fn(|j| b.estimate[(i, j)] - b.model[(i, j)]);
            // Parameters: c_0, c_1, c_2, b_2, b_4; this row's are c_i and the b's.
            let index = [i, 3, 4];
            let base = form(&w, &b.weights[i], &w);
            let projected = form(&w, &b.weights[i], &r);
            for p in 0..3 {
                rhs[index[p]] += powers[p] * projected;
                for q in 0..3 {
                    normal[(index[p], index[q])] += powers[p] * powers[q] * base;
                }
            }
        }
    }
    let inverse = normal.try_inverse()?;
    let solution = inverse * rhs;
    if !solution.iter().all(|v| v.is_finite()) {
        return None;
    }
    // This fit's own chi2: the residual less the fitted even gain, 18 real degrees of freedom per
    // bin less the five parameters.
    let mut chi2 = 0.0;
    for b in &bins {
        let w2 = b.omega * b.omega;
        for i in 0..3 {
            let factor = solution[i] + solution[3] * w2 + solution[4] * w2 * w2;
            let left: [Complex64; 3] =
                std::array::from_fn(|j| b.estimate[(i, j)] - b.model[(i, j)] * (1.0 + factor));
            chi2 += 2.0 * form(&left, &b.weights[i], &left);
        }
    }
    let dof = (18 * bins.len()).saturating_sub(5).max(1) as f64;
    let scale = bin_correlation.max(1.0) * (chi2 / dof).max(1.0) / 2.0;
    let (lo, hi) = bins.iter().fold((f64::INFINITY, 0.0_f64), |(l, h), b| {
        (l.min(b.omega), h.max(b.omega))
    });
    let c = [solution[0], solution[1], solution[2]];
    let bs = [solution[3], solution[4]];
    // Each row's change is linear in b: k_i M_pi A_i^-1 per unit b_p, `k_i` the fitted row (the
    // fit's K_i = k0_i (I + beta M A^-1) and b = beta (1 + c_i), so K_i b M A^-1 = K_i - k0_i).
    let mut per_b = [[RowVector3::<f64>::zeros(); 3]; 2];
    for i in 0..3 {
        let k = RowVector3::from(gain[i]);
        let a_inverse = a[i].try_inverse()?;
        for p in 0..2 {
            per_b[p][i] = k * m[p][i] * a_inverse;
        }
    }
    let b_cov = [
        [inverse[(3, 3)] * scale, inverse[(3, 4)] * scale],
        [inverse[(4, 3)] * scale, inverse[(4, 4)] * scale],
    ];
    let row_change: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| bs[0] * per_b[0][i][j] + bs[1] * per_b[1][i][j]));
    let row_change_std: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let d = [per_b[0][i][j], per_b[1][i][j]];
            (d[0] * d[0] * b_cov[0][0] + 2.0 * d[0] * d[1] * b_cov[0][1] + d[1] * d[1] * b_cov[1][1])
                .max(0.0)
                .sqrt()
        })
    });
    // The scale relative to the gain at low frequency, k0_i = K_i (1 + c_i) for a scale alone.
    let row_bias: [f64; 3] = std::array::from_fn(|i| {
        let k = RowVector3::from(gain[i]);
        RowVector3::from(row_change[i]).dot(&k) / k.norm_squared() / (1.0 + c[i])
    });
    let level = 1.0 + c.iter().sum::<f64>() / 3.0;
    if !row_bias
        .iter()
        .chain(row_change.iter().flatten())
        .chain(row_change_std.iter().flatten())
        .chain(b_cov.iter().flatten())
        .all(|v| v.is_finite())
        || !level.is_finite()
        || level <= 0.5
    {
        return None;
    }
    Some(Curvature {
        b: bs,
        b_cov,
        c,
        omega_range: [lo, hi],
        row_bias,
        row_change,
        row_change_std,
    })
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use nalgebra::Matrix3;
    use num_complex::Complex64;

    use super::{Bin, curvature};
    use crate::rng::Rng;

    const K: [[f64; 3]; 3] = [
        [1.002, 0.003, -0.001],
        [0.002, 0.998, 0.004],
        [-0.003, 0.001, 1.001],
    ];

    /// Bins of `K e^(-j omega tau) (1 + b omega^2)` with complex noise of covariance `sigma^2 I` per
    /// row, compared with the delay-only model that takes `K` as the band's mean gain.
    fn bins(rng: &mut Rng, b: f64, sigma: f64) -> Vec<Bin> {
        let k = Matrix3::new(1.002, 0.003, -0.001, 0.002, 0.998, 0.004, -0.003, 0.001, 1.001)
            .map(Complex64::from);
        let tau = 0.0042;
        let omegas: Vec<f64> = (1..=120)
            .map(|i| 2.0 * std::f64::consts::PI * 0.125 * f64::from(i))
            .collect();
        let weights = [Matrix3::identity() * Complex64::from(1.0 / (sigma * sigma)); 3];
        // Equal information per bin: the mean of omega^2.
        let mean = omegas.iter().map(|w| w * w).sum::<f64>() / omegas.len() as f64;
        omegas
            .iter()
            .map(|&omega| {
                let delay = Complex64::from_polar(1.0, -omega * tau);
                let noise = Matrix3::from_fn(|_, _| {
                    Complex64::new(rng.normal(), rng.normal()) * (sigma / std::f64::consts::SQRT_2)
                });
                Bin {
                    omega,
                    model: k * delay * Complex64::from(1.0 + b * mean),
                    estimate: k * delay * Complex64::from(1.0 + b * omega * omega) + noise,
                    weights,
                }
            })
            .collect()
    }

    /// The rise from the bins' bottom (0.125 Hz) to their top (15 Hz) of a gain `1 + b omega^2`.
    fn true_rise(b: f64) -> f64 {
        let (bottom, top) = ((2.0 * PI * 0.125).powi(2), (2.0 * PI * 15.0).powi(2));
        b * (top - bottom) / (1.0 + b * bottom)
    }

    /// Over 200 seeds the rise's error over its standard deviation has rms near 1, with and
    /// without a curvature; noise-free, the rise, `K`'s bias and each row's follow from `b`.
    #[test]
    fn the_curvature_is_recovered_within_its_deviation() {
        let mut rng = Rng::new(31);
        for b in [0.0, 1e-5] {
            let z: Vec<f64> = (0..200)
                .map(|_| {
                    let c = curvature(&bins(&mut rng, b, 2e-3), &K, 1.0).unwrap();
                    (c.rise() - true_rise(b)) / c.rise_std()
                })
                .collect();
            let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
            assert!((0.85..1.15).contains(&rms), "b {b}: z rms {rms}");
        }
        // Weights that understate the noise fourfold: the fit's own chi2/dof (about 4) widens the
        // deviation to the scatter again.
        let z: Vec<f64> = (0..200)
            .map(|_| {
                let mut understated = bins(&mut rng, 1e-5, 2e-3);
                for b in &mut understated {
                    b.weights = b.weights.map(|w| w * Complex64::from(4.0));
                }
                let c = curvature(&understated, &K, 1.0).unwrap();
                (c.rise() - true_rise(1e-5)) / c.rise_std()
            })
            .collect();
        let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
        assert!((0.85..1.15).contains(&rms), "understated weights: z rms {rms}");
        let c = curvature(&bins(&mut rng, 1e-5, 1e-9), &K, 1.0).unwrap();
        assert!(
            (c.rise() - true_rise(1e-5)).abs() < 1e-8,
            "{} against {}",
            c.rise(),
            true_rise(1e-5)
        );
        assert!(c.b[1].abs() < 1e-12, "{:?}", c.b);
        assert!((c.omega_range[1] - 2.0 * PI * 15.0).abs() < 1e-9);
        // The model's K reads b <omega^2> high, every row alike (equal weights everywhere).
        let mean: f64 = (1..=120)
            .map(|i| (2.0 * PI * 0.125 * f64::from(i)).powi(2))
            .sum::<f64>()
            / 120.0;
        assert!(
            (c.k_bias() - 1e-5 * mean).abs() < 1e-8,
            "{} against {}",
            c.k_bias(),
            1e-5 * mean
        );
        for (bias, offset) in c.row_bias.iter().zip(c.c) {
            assert!((bias - 1e-5 * mean).abs() < 1e-8, "{bias}");
            assert!(
                (offset + 1e-5 * mean / (1.0 + 1e-5 * mean)).abs() < 1e-8,
                "{offset}"
            );
        }
        // The bins' correlation widens the deviation alone.
        let wide = curvature(&bins(&mut Rng::new(2), 0.0, 2e-3), &K, 9.0).unwrap();
        let plain = curvature(&bins(&mut Rng::new(2), 0.0, 2e-3), &K, 1.0).unwrap();
        assert!((wide.rise_std() - 3.0 * plain.rise_std()).abs() < 1e-12 * plain.rise_std());
        assert_eq!(wide.b.map(f64::to_bits), plain.b.map(f64::to_bits));
    }

    /// A gain flat at low frequency that rises as `omega^4` near the band's top (a cubic spline's
    /// droop) is not extrapolated to low frequency as a curvature: `K`'s bias is the small mean of
    /// the rise, not the `omega^2` fit's.
    #[test]
    fn a_steep_rise_at_the_top_is_not_read_as_a_low_frequency_curvature() {
        let mut rng = Rng::new(9);
        let c4 = 1e-9;
        let mut steep = bins(&mut rng, 0.0, 1e-9);
        let mean4 = steep.iter().map(|b| b.omega.powi(4)).sum::<f64>() / steep.len() as f64;
        for b in &mut steep {
            let delay = Complex64::from_polar(1.0, -b.omega * 0.0042);
            let k = Matrix3::from_fn(|i, j| Complex64::from(K[i][j]));
            b.model = k * delay * Complex64::from(1.0 + c4 * mean4);
            b.estimate = k * delay * Complex64::from(1.0 + c4 * b.omega.powi(4));
        }
        let c = curvature(&steep, &K, 1.0).unwrap();
        assert!(
            (c.k_bias() - c4 * mean4).abs() < 1e-6 * c4 * mean4,
            "{} against {}",
            c.k_bias(),
            c4 * mean4
        );
        let (bottom, top) = (2.0 * PI * 0.125, 2.0 * PI * 15.0);
        let rise = c4 * (top.powi(4) - bottom.powi(4)) / (1.0 + c4 * bottom.powi(4));
        assert!((c.rise() - rise).abs() < 1e-9, "{} against {rise}", c.rise());
    }

    /// Each row's bias against a brute-force fit: the delay-only `K` fitted by whitened least
    /// squares (an SVD of the stacked real system, not the normal equations) to noise-free bins of
    /// `K_0 e^(-j omega tau) (1 + b omega^2)`, with weights that differ by row and bin; the row's
    /// scale change against the bias the curvature says, for the curvature it fits.
    #[test]
    fn each_row_s_bias_is_the_delay_only_fit_s() {
        let mut rng = Rng::new(12);
        let (b, tau) = (2e-6, 0.004);
        let k0 = nalgebra::Matrix3::from_fn(|i, j| K[i][j]);
        let omegas: Vec<f64> = (1..=150)
            .map(|i| 2.0 * std::f64::consts::PI * 0.2 * f64::from(i))
            .collect();
        // Hermitian positive definite weights, from random factors, scaled by the bin.
        let weights: Vec<[Matrix3<Complex64>; 3]> = omegas
            .iter()
            .map(|w| {
                std::array::from_fn(|_| {
                    let l = Matrix3::from_fn(|_, _| Complex64::new(rng.normal(), rng.normal()));
                    (l * l.adjoint() + Matrix3::identity() * Complex64::from(0.5))
                        * Complex64::from(1.0 + 1e3 / w)
                })
            })
            .collect();
        let data: Vec<Matrix3<Complex64>> = omegas
            .iter()
            .map(|&w| k0.map(Complex64::from) * Complex64::from_polar(1.0 + b * w * w, -w * tau))
            .collect();
        // Brute force, row by row: minimise sum |(h - k e) L|^2 over real k (L L^H = Omega).
        let mut fitted = [[0.0; 3]; 3];
        for (i, row) in fitted.iter_mut().enumerate() {
            let mut design = nalgebra::DMatrix::<f64>::zeros(6 * omegas.len(), 3);
            let mut target = nalgebra::DVector::<f64>::zeros(6 * omegas.len());
            for (n, &w) in omegas.iter().enumerate() {
                let l = weights[n][i].cholesky().expect("positive definite").l();
                let e = Complex64::from_polar(1.0, -w * tau);
                for c in 0..3 {
                    let h: Complex64 = (0..3).map(|j| data[n][(i, j)] * l[(j, c)]).sum();
                    target[6 * n + 2 * c] = h.re;
                    target[6 * n + 2 * c + 1] = h.im;
                    for p in 0..3 {
                        let x = e * l[(p, c)];
                        design[(6 * n + 2 * c, p)] = x.re;
                        design[(6 * n + 2 * c + 1, p)] = x.im;
                    }
                }
            }
            let solution = design.svd(true, true).solve(&target, 1e-14).expect("solved");
            *row = [solution[0], solution[1], solution[2]];
        }
        let bins: Vec<Bin> = omegas
            .iter()
            .zip(&data)
            .zip(&weights)
            .map(|((&omega, &estimate), &weights)| Bin {
                omega,
                model: nalgebra::Matrix3::from_fn(|i, j| Complex64::from(fitted[i][j]))
                    * Complex64::from_polar(1.0, -omega * tau),
                estimate,
                weights,
            })
            .collect();
        let c = curvature(&bins, &fitted, 1.0).unwrap();
        for i in 0..3 {
            let k = nalgebra::RowVector3::from(K[i]);
            let actual = (nalgebra::RowVector3::from(fitted[i]) - k).dot(&k) / k.norm_squared();
            assert!(
                (c.row_bias[i] - actual).abs() < 0.02 * actual.abs(),
                "row {i}: said {} against {actual}",
                c.row_bias[i]
            );
        }
        // The rows differ (their weights do), so one common bias would not do.
        assert!(
            (c.row_bias[0] - c.row_bias[1]).abs() > 0.05 * c.row_bias[0].abs(),
            "{:?}",
            c.row_bias
        );
        // The whole change of each row, cross-couplings included, is the brute-force fit's less
        // the gain at low frequency (within 2 % of the row's change).
        for i in 0..3 {
            let actual: [f64; 3] = std::array::from_fn(|j| fitted[i][j] - K[i][j]);
            let size = actual.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for j in 0..3 {
                assert!(
                    (c.row_change[i][j] - actual[j]).abs() < 0.02 * size,
                    "row {i}: change {:?} against {actual:?}",
                    c.row_change[i]
                );
            }
        }
    }

    /// Over 200 seeds each element of a row's change scatters about its noise-free value as its
    /// standard deviation says (z rms near 1, the nine elements pooled).
    #[test]
    fn each_row_s_change_scatters_as_its_deviation_says() {
        let clean = curvature(&bins(&mut Rng::new(5), 1e-5, 1e-9), &K, 1.0).unwrap();
        let mut rng = Rng::new(77);
        let z: Vec<f64> = (0..200)
            .flat_map(|_| {
                let c = curvature(&bins(&mut rng, 1e-5, 2e-3), &K, 1.0).unwrap();
                (0..9)
                    .map(|e| {
                        let (i, j) = (e / 3, e % 3);
                        (c.row_change[i][j] - clean.row_change[i][j]) / c.row_change_std[i][j]
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
        assert!((0.85..1.15).contains(&rms), "z rms {rms}");
        // The model's even gain is relative to the gain at low frequency: `g` at the bins' top
        // over `g` at their bottom is the rise.
        let g = clean.even_gain();
        let (bottom, top) = (0.125, 15.0);
        assert!(
            (g.at(top) / g.at(bottom) - 1.0 - clean.rise()).abs() < 1e-9,
            "{} against {}",
            g.at(top) / g.at(bottom) - 1.0,
            clean.rise()
        );
        assert_eq!(g.k_change, clean.row_change);
        // Above the band's top g is held at its value there.
        assert_eq!(g.at(15.0).to_bits(), g.at(250.0).to_bits());
        assert!(g.at(14.0) < g.at(15.0));
    }

    /// Noise-free, with the model's own `K` (the band's mean gain `K (1 + b <omega^2>)`, as the
    /// identifier passes it): each row's change is exactly that less `K`, the rows' bias is
    /// `b <omega^2>`, and the model's even gain is `b` itself, relative to the gain at low
    /// frequency.
    #[test]
    fn with_the_model_s_own_k_the_change_and_the_even_gain_are_exact() {
        let b = 1e-5;
        let mean: f64 = (1..=120)
            .map(|i| (2.0 * PI * 0.125 * f64::from(i)).powi(2))
            .sum::<f64>()
            / 120.0;
        let fitted: [[f64; 3]; 3] = K.map(|r| r.map(|v| v * (1.0 + b * mean)));
        let c = curvature(&bins(&mut Rng::new(6), b, 1e-12), &fitted, 1.0).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let want = fitted[i][j] - K[i][j];
                assert!(
                    (c.row_change[i][j] - want).abs() < 1e-9 * want.abs().max(1e-6),
                    "{i} {j}: {} against {want}",
                    c.row_change[i][j]
                );
            }
            assert!((c.row_bias[i] - b * mean).abs() < 1e-9, "{:?}", c.row_bias);
        }
        let g = c.even_gain();
        assert!((g.coefficients[0] - b).abs() < 1e-9 * b, "{:?}", g.coefficients);
        assert!(g.coefficients[1].abs() < 1e-16, "{:?}", g.coefficients);
    }

    /// No bins, or only non-finite ones, or a zero row of the gain give nothing; a non-finite bin
    /// among good ones is skipped.
    #[test]
    fn empty_or_non_finite_bins_give_nothing() {
        assert!(curvature(&[], &K, 1.0).is_none());
        // A zero row of the gain has no scale to read a bias of: nothing, rather than a NaN.
        let mut zero_row = K;
        zero_row[1] = [0.0; 3];
        assert!(curvature(&bins(&mut Rng::new(3), 1e-5, 1e-9), &zero_row, 1.0).is_none());
        let mut rng = Rng::new(4);
        let mut some = bins(&mut rng, 1e-5, 1e-9);
        some[3].estimate[(1, 1)] = Complex64::new(f64::NAN, 0.0);
        let c = curvature(&some, &K, 1.0).unwrap();
        assert!((c.rise() / true_rise(1e-5) - 1.0).abs() < 1e-3, "{}", c.rise());
        for b in &mut some {
            b.omega = f64::NAN;
        }
        assert!(curvature(&some, &K, 1.0).is_none());
    }
}
