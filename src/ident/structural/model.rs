//! The prepared data (weights, normalised frequencies) and the rational model with delay in the
//! normalised variable `sigma = s / omega_ref`, shared by every order.

use nalgebra::DMatrix;
use num_complex::Complex64;

use super::ResponseEstimate;

/// Elements of a 3x3 block, row-major: element `e` is row `e / 3`, column `e % 3`.
pub(super) const ELEMENTS: usize = 9;

/// Real parameters of order `n`: `9 max(n, 1)` numerator coefficients, `n` denominator
/// coefficients and the delay.
pub(super) fn parameter_count(order: usize) -> usize {
    ELEMENTS * order.max(1) + order + 1
}

/// The input with what does not depend on the model precomputed.
pub(super) struct Prepared {
    /// Angular frequency of each bin, rad/s.
    pub omega: Vec<f64>,
    /// `omega / omega_ref`, in `(0, 1]`.
    pub x: Vec<f64>,
    /// The normalising angular frequency (the band's top), rad/s.
    pub omega_ref: f64,
    /// Weights `1 / variance`, element-major within a bin.
    pub w: Vec<[f64; ELEMENTS]>,
    /// The response, element-major within a bin.
    pub h: Vec<[Complex64; ELEMENTS]>,
}

impl Prepared {
    /// Precomputes from a validated estimate (non-empty, ascending positive frequencies).
    pub fn new(input: &ResponseEstimate) -> Self {
        let omega: Vec<f64> = input
            .frequency_hz
            .iter()
            .map(|f| 2.0 * std::f64::consts::PI * f)
            .collect();
        let omega_ref = omega.last().copied().unwrap_or(1.0);
        let x = omega.iter().map(|o| o / omega_ref).collect();
        let w = input
            .variance
            .iter()
            .map(|v| std::array::from_fn(|e| 1.0 / v[(e / 3, e % 3)]))
            .collect();
        let h = input
            .response
            .iter()
            .map(|r| std::array::from_fn(|e| r[(e / 3, e % 3)]))
            .collect();
        Self {
            omega,
            x,
            omega_ref,
            w,
            h,
        }
    }

    /// Number of bins.
    pub fn bins(&self) -> usize {
        self.omega.len()
    }

    /// Number of real data, `18 n_bins`.
    pub fn real_data(&self) -> usize {
        2 * ELEMENTS * self.bins()
    }
}

/// `N(sigma) / d(sigma) e^(-tau s)` with normalised coefficients: `num[m][e]` multiplies
/// `sigma^m`, `den[m - 1]` multiplies `sigma^m`, `sigma = s / omega_ref`.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Model {
    /// Numerator coefficients, `max(order, 1)` of them.
    pub num: Vec<[f64; ELEMENTS]>,
    /// Denominator coefficients `d_1..d_n` (the constant term is 1).
    pub den: Vec<f64>,
    /// Delay, s.
    pub tau: f64,
}

impl Model {
    /// The number of poles.
    pub fn order(&self) -> usize {
        self.den.len()
    }

    /// `sum_m c[m] sigma^(m + offset)` at `sigma = j x`.
    pub fn poly(c: impl Iterator<Item = f64>, x: f64, offset: i32) -> Complex64 {
        let sigma = Complex64::new(0.0, x);
        let mut p = sigma.powi(offset);
        let mut acc = Complex64::new(0.0, 0.0);
        for cm in c {
            acc += p * cm;
            p *= sigma;
        }
        acc
    }

    /// `d(j x)`.
    pub fn den_at(&self, x: f64) -> Complex64 {
        Complex64::new(1.0, 0.0) + Self::poly(self.den.iter().copied(), x, 1)
    }

    /// The weighted residual `chi2 = sum 2 w |h - model|^2`.
    pub fn chi2(&self, data: &Prepared) -> f64 {
        let mut chi2 = 0.0;
        for k in 0..data.bins() {
            let d = self.den_at(data.x[k]);
            let e = Complex64::from_polar(1.0, -data.omega[k] * self.tau) / d;
            for el in 0..ELEMENTS {
                let n = Self::poly(self.num.iter().map(|c| c[el]), data.x[k], 0);
                chi2 += 2.0 * data.w[k][el] * (data.h[k][el] - n * e).norm_sqr();
            }
        }
        chi2
    }

    /// Standard deviations of every parameter, in the order `num` (coefficient-major, then
    /// element), `den`, `tau * omega_ref`, from the Gauss–Newton covariance of the weighted
    /// real residuals (unscaled by `chi2 / dof`). `+inf` for an undetermined parameter.
    pub fn parameter_std(&self, data: &Prepared) -> Vec<f64> {
        let n_num = self.num.len();
        let p = ELEMENTS * n_num + self.den.len() + 1;
        let rows = data.real_data();
        let mut jac = faer::Mat::<f64>::zeros(rows, p);
        for k in 0..data.bins() {
            let x = data.x[k];
            let sigma = Complex64::new(0.0, x);
            let d = self.den_at(x);
            let e = Complex64::from_polar(1.0, -data.omega[k] * self.tau) / d;
            for el in 0..ELEMENTS {
                let sw = (2.0 * data.w[k][el]).sqrt();
                let row = 2 * (k * ELEMENTS + el);
                let n = Self::poly(self.num.iter().map(|c| c[el]), x, 0);
                let mut put = |col: usize, z: Complex64| {
                    jac[(row, col)] = sw * z.re;
                    jac[(row + 1, col)] = sw * z.im;
                };
                let mut pw = Complex64::new(1.0, 0.0);
                for m in 0..n_num {
                    put(m * ELEMENTS + el, pw * e);
                    pw *= sigma;
                }
                let mut pw = sigma;
                for m in 0..self.den.len() {
                    put(ELEMENTS * n_num + m, -n * pw * e / d);
                    pw *= sigma;
                }
                put(p - 1, -sigma * n * e);
            }
        }
        if (0..p).any(|c| jac.col(c).iter().any(|v| !v.is_finite())) {
            return vec![f64::INFINITY; p];
        }
        let qr = jac.qr();
        let r = qr.thin_R();
        let r = DMatrix::from_fn(p, p, |i, j| r[(i, j)]);
        std_from_r(&r)
    }
}

/// Diagonal of `(R^T R)^-1` through the SVD of `R`, square-rooted; directions with a singular
/// value below `1e-12` of the largest make the parameters that load on them `+inf`.
fn std_from_r(r: &DMatrix<f64>) -> Vec<f64> {
    let p = r.ncols();
    let svd = r.clone().svd(false, true);
    let (Some(v_t), s) = (svd.v_t, svd.singular_values) else {
        return vec![f64::INFINITY; p];
    };
    let s_max = s.iter().copied().fold(0.0, f64::max);
    (0..p)
        .map(|i| {
            let mut var = 0.0;
            for j in 0..s.len() {
                let v = v_t[(j, i)];
                if s[j] > 1e-12 * s_max {
                    var += (v / s[j]).powi(2);
                } else if v.abs() > 1e-9 {
                    return f64::INFINITY;
                }
            }
            if var.is_finite() {
                var.sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect()
}
