//! Whether the block's gain changes across the band with no phase of its own: the self-check's
//! `gain_changes_across_band` ([`super::warnings::IdentWarning::GainChangesAcrossBand`]).
//!
//! A reference measured at a lower rate and interpolated onto the block's samples, or smoothed,
//! passes the motion through a zero-phase low-pass: linear interpolation from a rate `f_r`
//! weighs the angles by `sinc^2(f / f_r)` on average, `1 - (pi f / f_r)^2 / 3` at low frequency.
//! The inputs computed from the angles then fall short of the motion by a factor even in `f`,
//! and the measured gain `W` rises as `1 + b omega^2` with no phase: no delay or admissible
//! order takes that (a rational model pays for a gain rise with phase), so the delay-only model
//! takes `K` as the band's information-weighted mean gain, `K_0 (1 + b <omega^2>)`, above the gain
//! at low frequency. Found by a helper's hand-held simulator (a 120 Hz optical reference
//! interpolated linearly onto the gyro's samples, as the real recordings' dataset was made): every
//! diagonal of `K` read high by 0.1-1.7 %, 5 of its standard deviations on average, with nothing
//! said on most runs; the three real recordings' gain rises by 4-7 % from their band's bottom to
//! 10-15 Hz.
//!
//! [`curvature`] fits the one common `b` to the chosen model's residual by generalised least
//! squares, with the regressor `(omega^2 - <omega^2>) W` (the part the model's own `K` has not
//! already taken) and the weights of the self-check's per-bin chi2. Its standard deviation is
//! widened as the fit's are (the bins' correlation and `sqrt(chi2/dof)` where above 1). How far
//! each row of `K` then reads from the gain at low frequency follows from the delay-only fit's
//! normal equations, row by row ([`Curvature::row_bias`]): a row whose weight lies at higher
//! frequencies (an axis moved faster) reads higher, and rows that share collinear inputs can read
//! low (the accelerometer's on a simulated stand).
//!
//! Units: `omega` in rad/s, `b` in s^2; `K`'s bias and the rise are relative (fractions).
//! Non-finite bins are skipped; no bins, or no information in them, give `None`.

use nalgebra::Matrix3;
use num_complex::Complex64;

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

/// The fitted gain curvature of a block over its band (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// `b`, s^2: the gain is `1 + b (omega^2 - <omega^2>)` relative to the model's (whose `K` is
    /// the band's mean gain), so `1 + b omega^2` relative to that at low frequency up to
    /// `1 / (1 - b <omega^2>)`.
    pub b_s2: f64,
    /// Its standard deviation (widened), s^2.
    pub b_std_s2: f64,
    /// `<omega^2>`, the bins' information-weighted mean, rad^2/s^2: the model's gain is the gain
    /// at low frequency times `1 / (1 - b <omega^2>)`.
    pub mean_omega2: f64,
    /// Per output row `i` of `K`, the relative change of its scale the curvature gives the
    /// delay-only fit: its row is `k_i (I + b_0 M_i A_i^-1)`, with `A_i = sum Re Omega_i` and
    /// `M_i = sum omega^2 Re Omega_i` over the bins (its normal equations) and `b_0` the curvature
    /// against the gain at low frequency; the scale is the change's projection on `k_i`.
    pub row_bias: [f64; 3],
    /// The band's lowest and highest `omega^2`, rad^2/s^2.
    pub omega2_range: [f64; 2],
}

impl Curvature {
    /// How far `K` (the band's mean gain) reads above the gain at low frequency, relative.
    #[must_use]
    pub fn k_bias(&self) -> f64 {
        1.0 / (1.0 - self.b_s2 * self.mean_omega2) - 1.0
    }

    /// The gain's change from the band's bottom to its top, relative to the bottom's.
    #[must_use]
    pub fn rise(&self) -> f64 {
        let at = |w2: f64| 1.0 + self.b_s2 * (w2 - self.mean_omega2);
        at(self.omega2_range[1]) / at(self.omega2_range[0]) - 1.0
    }
}

/// `r Omega r^H` for rows `x` and `r` (real part), `Omega` Hermitian.
fn form(x: &[Complex64], omega: &Matrix3<Complex64>, r: &[Complex64]) -> f64 {
    let mut q = Complex64::new(0.0, 0.0);
    for j in 0..3 {
        for l in 0..3 {
            q += x[j] * omega[(j, l)] * r[l].conj();
        }
    }
    q.re
}

/// The common gain curvature of `bins` (module docs) of a block whose static gain is `gain`;
/// `widening` multiplies its standard deviation (`sqrt(bin correlation x max(1, chi2/dof))`).
#[must_use]
pub fn curvature(bins: &[Bin], gain: &[[f64; 3]; 3], widening: f64) -> Option<Curvature> {
    let row = |m: &Matrix3<Complex64>, i: usize| [m[(i, 0)], m[(i, 1)], m[(i, 2)]];
    let finite = |b: &&Bin| {
        b.omega.is_finite()
            && b.model
                .iter()
                .chain(b.estimate.iter())
                .chain(b.weights.iter().flat_map(|w| w.iter()))
                .all(|z| z.re.is_finite() && z.im.is_finite())
    };
    let bins: Vec<&Bin> = bins.iter().filter(finite).collect();
    let information = |b: &Bin| -> f64 {
        (0..3)
            .map(|i| form(&row(&b.model, i), &b.weights[i], &row(&b.model, i)))
            .sum()
    };
    let (mut total, mut moment) = (0.0, 0.0);
    let (mut a, mut m) = ([Matrix3::<f64>::zeros(); 3], [Matrix3::<f64>::zeros(); 3]);
    for b in &bins {
        let info = information(b);
        let w2 = b.omega * b.omega;
        total += info;
        moment += info * w2;
        for i in 0..3 {
            let re = b.weights[i].map(|z| z.re);
            a[i] += re;
            m[i] += re * w2;
        }
    }
    if !total.is_finite() || total <= 0.0 {
        return None;
    }
    let mean_omega2 = moment / total;
    let (mut num, mut den) = (0.0, 0.0);
    for b in &bins {
        let shift = b.omega * b.omega - mean_omega2;
        for i in 0..3 {
            let x = row(&b.model, i).map(|z| z * shift);
            let r: Vec<Complex64> = (0..3).map(|j| b.estimate[(i, j)] - b.model[(i, j)]).collect();
            num += form(&x, &b.weights[i], &r);
            den += form(&x, &b.weights[i], &x);
        }
    }
    if !den.is_finite() || den <= 0.0 {
        return None;
    }
    let omega2 = bins.iter().map(|b| b.omega * b.omega);
    let lo = omega2.clone().fold(f64::INFINITY, f64::min);
    let hi = omega2.fold(0.0, f64::max);
    let b_s2 = num / den;
    let b_0 = b_s2 / (1.0 - b_s2 * mean_omega2);
    let row_bias = std::array::from_fn(|i| {
        let k = nalgebra::RowVector3::from(gain[i]);
        let change = a[i].try_inverse().map(|inv| k * m[i] * inv * b_0);
        let scale = k.norm_squared();
        change.map_or(f64::NAN, |c| c.dot(&k) / scale)
    });
    Some(Curvature {
        b_s2,
        b_std_s2: widening / (2.0 * den).sqrt(),
        mean_omega2,
        row_bias,
        omega2_range: [lo, hi],
    })
}

#[cfg(test)]
mod tests {
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

    /// The curvature relative to the band's mean gain of a gain `1 + b omega^2`.
    fn relative_to_the_mean(b: f64, mean_omega2: f64) -> f64 {
        b / (1.0 + b * mean_omega2)
    }

    /// Over 200 seeds the curvature's error over its standard deviation has rms near 1, with
    /// and without a curvature; the bias of `K` and the rise follow from `b`.
    #[test]
    fn the_curvature_is_recovered_within_its_deviation() {
        let mut rng = Rng::new(31);
        for b in [0.0, 1e-5] {
            let z: Vec<f64> = (0..200)
                .map(|_| {
                    let c = curvature(&bins(&mut rng, b, 2e-3), &K, 1.0).unwrap();
                    (c.b_s2 - relative_to_the_mean(b, c.mean_omega2)) / c.b_std_s2
                })
                .collect();
            let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
            assert!((0.85..1.15).contains(&rms), "b {b}: z rms {rms}");
        }
        let c = curvature(&bins(&mut rng, 1e-5, 1e-9), &K, 1.0).unwrap();
        assert!(
            (c.b_s2 - relative_to_the_mean(1e-5, c.mean_omega2)).abs() < 1e-12,
            "{}",
            c.b_s2
        );
        // Against the gain at low frequency: the model's K reads b <omega^2> high, and the gain
        // rises by 1e-5 (top - bottom) over its value at the bottom.
        let top = (2.0 * std::f64::consts::PI * 15.0).powi(2);
        let bottom = (2.0 * std::f64::consts::PI * 0.125).powi(2);
        let rise = 1e-5 * (top - bottom) / (1.0 + 1e-5 * bottom);
        assert!((c.rise() - rise).abs() < 1e-8, "{} against {rise}", c.rise());
        assert!((c.omega2_range[1] - top).abs() < 1e-6 * top);
        assert!((c.k_bias() - 1e-5 * c.mean_omega2).abs() < 1e-8, "{}", c.k_bias());
        // Equal weights everywhere: every row's scale reads the same.
        for bias in c.row_bias {
            assert!((bias - 1e-5 * c.mean_omega2).abs() < 1e-8, "{bias}");
        }
        // Widening scales the deviation alone.
        let wide = curvature(&bins(&mut Rng::new(2), 0.0, 2e-3), &K, 3.0).unwrap();
        let plain = curvature(&bins(&mut Rng::new(2), 0.0, 2e-3), &K, 1.0).unwrap();
        assert!((wide.b_std_s2 - 3.0 * plain.b_std_s2).abs() < 1e-12 * plain.b_std_s2);
        assert_eq!(wide.b_s2.to_bits(), plain.b_s2.to_bits());
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
    }

    /// No bins, or only non-finite ones, give nothing; a non-finite bin among good ones is skipped.
    #[test]
    fn empty_or_non_finite_bins_give_nothing() {
        assert!(curvature(&[], &K, 1.0).is_none());
        let mut rng = Rng::new(4);
        let mut some = bins(&mut rng, 1e-5, 1e-9);
        some[3].estimate[(1, 1)] = Complex64::new(f64::NAN, 0.0);
        let c = curvature(&some, &K, 1.0).unwrap();
        assert!(
            (c.b_s2 / relative_to_the_mean(1e-5, c.mean_omega2) - 1.0).abs() < 1e-3,
            "{}",
            c.b_s2
        );
        for b in &mut some {
            b.omega = f64::NAN;
        }
        assert!(curvature(&some, &K, 1.0).is_none());
    }
}
