//! The prepared data (weights, normalised frequencies) and the rational model with delay in the
//! normalised variable `sigma = s / omega_ref`, shared by every order.

use faer::Par;
use faer::Spec;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor as qr;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, OnceLock};

use nalgebra::DMatrix;
use num_complex::Complex64;

use super::ResponseEstimate;
use super::phasor::{Phasors, uniform_step};
use super::weights::RowWeight;

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
    /// The common spacing of `omega` when its bins are equally spaced ([`super::phasor`]).
    pub omega_step: Option<f64>,
    /// The diagonal approximation `Re(Omega_i)_jj` of the weights (exactly `1 / variance` on
    /// the variance path), element-major within a bin: for the Sanathanan–Koerner starts only.
    pub w: Vec<[f64; ELEMENTS]>,
    /// The row weights and their square roots, per bin and output row (shared: a retune on the
    /// same weights, none of them narrowed, reuses them, `super::placed`).
    pub rows: Arc<[[RowWeight; 3]]>,
    /// The response, element-major within a bin.
    pub h: Vec<[Complex64; ELEMENTS]>,
    /// `Omega_i` of the rows, flattened as `(re, im)` pairs, row-major within each row's matrix,
    /// row `i` at `18 i..18 i + 18`, per bin.
    pub omega_flat: Vec<[f64; 54]>,
    /// `(Omega_i W_i^H)_j` at element `3 i + j`, per bin (the projection's right-hand side).
    pub g: Vec<[Complex64; ELEMENTS]>,
    /// [`Self::fingerprint`], computed at its first use (the move's order-0 passes never ask).
    fingerprint: OnceLock<u64>,
}

impl Prepared {
    /// Precomputes from a validated estimate (non-empty, positive frequencies) and its
    /// validated row weights.
    pub fn new(input: &ResponseEstimate, rows: Arc<[[RowWeight; 3]]>) -> Self {
        let omega: Vec<f64> = input
            .frequency_hz
            .iter()
            .map(|f| 2.0 * std::f64::consts::PI * f)
            .collect();
        let omega_ref = omega.iter().copied().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let x = omega.iter().map(|o| o / omega_ref).collect();
        let w = rows
            .iter()
            .map(|r| std::array::from_fn(|e| r[e / 3].omega[(e % 3, e % 3)].re))
            .collect();
        let h: Vec<[Complex64; ELEMENTS]> = input
            .response
            .iter()
            .map(|r| std::array::from_fn(|e| r[(e / 3, e % 3)]))
            .collect();
        let omega_flat = rows
            .iter()
            .map(|r| {
                std::array::from_fn(|f| {
                    let z = r[f / 18].omega[((f % 18) / 6, (f / 2) % 3)];
                    if f % 2 == 0 { z.re } else { z.im }
                })
            })
            .collect();
        let g = rows
            .iter()
            .zip(&h)
            .map(|(r, h): (&[RowWeight; 3], &[Complex64; ELEMENTS])| {
                std::array::from_fn(|e| {
                    let (i, j) = (e / 3, e % 3);
                    (0..3).map(|l| r[i].omega[(j, l)] * h[3 * i + l].conj()).sum()
                })
            })
            .collect();
        let omega_step = uniform_step(&omega);
        Self {
            omega_step,
            omega,
            x,
            omega_ref,
            w,
            rows,
            h,
            omega_flat,
            g,
            fingerprint: OnceLock::new(),
        }
    }

    /// Hash of the bits of the frequencies, the response and the row weights: what tells a refit
    /// on the same data from one on other data ([`super::refit_structure`]).
    pub fn fingerprint(&self) -> u64 {
        *self
            .fingerprint
            .get_or_init(|| fingerprint(&self.omega, &self.h, &self.rows))
    }

    /// `e^(-j omega_k tau)` over the bins, in order.
    pub fn phasors(&self, tau: f64) -> Phasors<'_> {
        Phasors::new(&self.omega, self.omega_step, tau)
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

/// Hash of the bits of everything the fit reads from the data.
fn fingerprint(omega: &[f64], h: &[[Complex64; ELEMENTS]], rows: &[[RowWeight; 3]]) -> u64 {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    let mut put = |v: f64| v.to_bits().hash(&mut hasher);
    for ((&o, hk), rk) in omega.iter().zip(h).zip(rows) {
        put(o);
        for z in hk {
            put(z.re);
            put(z.im);
        }
        for row in rk {
            for z in &row.omega {
                put(z.re);
                put(z.im);
            }
        }
    }
    hasher.finish()
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

    /// The same physical model normalised with `ratio` times the reference frequency: `den[m]`
    /// multiplies `sigma^(m + 1)` and `num[m]` multiplies `sigma^m`, `sigma = s / omega_ref`.
    pub fn rescaled(&self, ratio: f64) -> Self {
        Self {
            num: self
                .num
                .iter()
                .zip(0_i32..)
                .map(|(c, p)| c.map(|v| v * ratio.powi(p)))
                .collect(),
            den: self
                .den
                .iter()
                .zip(1_i32..)
                .map(|(d, p)| d * ratio.powi(p))
                .collect(),
            tau: self.tau,
        }
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

    /// The model's rows at bin `k`: `num(j x) e^(-j w tau) / d(j x)`.
    fn at(&self, data: &Prepared, k: usize) -> [Complex64; ELEMENTS] {
        let x = data.x[k];
        let e = Complex64::from_polar(1.0, -data.omega[k] * self.tau) / self.den_at(x);
        std::array::from_fn(|el| Self::poly(self.num.iter().map(|c| c[el]), x, 0) * e)
    }

    /// The generalised least-squares residual `chi2 = sum 2 r_i Omega_i r_i^H`.
    pub fn chi2(&self, data: &Prepared) -> f64 {
        (0..data.bins())
            .map(|k| self.bin_chi2(data, k).iter().sum::<f64>())
            .sum()
    }

    /// [`Self::chi2`]'s terms, per bin and output row (six real degrees of freedom each).
    pub fn chi2_rows(&self, data: &Prepared) -> Vec<[f64; 3]> {
        (0..data.bins()).map(|k| self.bin_chi2(data, k)).collect()
    }

    /// The three rows' `2 r_i Omega_i r_i^H` at bin `k`.
    fn bin_chi2(&self, data: &Prepared, k: usize) -> [f64; 3] {
        let m = self.at(data, k);
        std::array::from_fn(|i| {
            let r = std::array::from_fn(|j| data.h[k][3 * i + j] - m[3 * i + j]);
            2.0 * data.rows[k][i].quadratic(&r)
        })
    }

    /// Standard deviations of every parameter, in the order `num` (coefficient-major, then
    /// element), `den`, `tau * omega_ref`, from the Gauss–Newton covariance of the whitened
    /// real residuals `sqrt(2) (Re, Im)(r_i L_i)` (unscaled by `chi2 / dof`). `+inf` for an
    /// undetermined parameter.
    pub fn parameter_std(&self, data: &Prepared) -> Vec<f64> {
        self.standard_deviations(data, false).0
    }

    /// [`Self::parameter_std`] and, per parameter, the sandwich variance `(J^T J)^-1 M (J^T J)^-1`
    /// of the bins' scores (`super::sandwich`; `None` where it cannot be formed).
    pub fn parameter_std_and_sandwich(&self, data: &Prepared) -> (Vec<f64>, Option<Vec<f64>>) {
        self.standard_deviations(data, true)
    }

    fn standard_deviations(&self, data: &Prepared, sandwich: bool) -> (Vec<f64>, Option<Vec<f64>>) {
        let n_num = self.num.len();
        let p = ELEMENTS * n_num + self.den.len() + 1;
        let rows = data.real_data();
        let mut jac = faer::Mat::<f64>::zeros(rows, p);
        // The whitened real residuals, laid out as the Jacobian's rows (for the sandwich).
        let mut residual = vec![0.0; rows];
        let sqrt2 = std::f64::consts::SQRT_2;
        for k in 0..data.bins() {
            let x = data.x[k];
            let sigma = Complex64::new(0.0, x);
            let d = self.den_at(x);
            let e = Complex64::from_polar(1.0, -data.omega[k] * self.tau) / d;
            let model = self.at(data, k);
            for (i, weight) in data.rows[k].iter().enumerate() {
                let base = 2 * (k * ELEMENTS + 3 * i);
                // Column `col` of the Jacobian from the derivative of the model's row `i`.
                let mut put = |col: usize, dm: [Complex64; 3]| {
                    for (l, z) in weight.whiten(&dm).iter().enumerate() {
                        jac[(base + 2 * l, col)] = sqrt2 * z.re;
                        jac[(base + 2 * l + 1, col)] = sqrt2 * z.im;
                    }
                };
                for j in 0..3 {
                    let mut pw = e;
                    for m in 0..n_num {
                        let mut dm = [Complex64::new(0.0, 0.0); 3];
                        dm[j] = pw;
                        put(m * ELEMENTS + 3 * i + j, dm);
                        pw *= sigma;
                    }
                }
                let row: [Complex64; 3] = std::array::from_fn(|j| model[3 * i + j]);
                let r: [Complex64; 3] = std::array::from_fn(|j| data.h[k][3 * i + j] - row[j]);
                for (l, z) in weight.whiten(&r).iter().enumerate() {
                    residual[base + 2 * l] = sqrt2 * z.re;
                    residual[base + 2 * l + 1] = sqrt2 * z.im;
                }
                let mut pw = sigma;
                for m in 0..self.den.len() {
                    put(ELEMENTS * n_num + m, row.map(|z| -z * pw / d));
                    pw *= sigma;
                }
                put(p - 1, row.map(|z| -sigma * z));
            }
        }
        if (0..p).any(|c| jac.col(c).iter().any(|v| !v.is_finite())) {
            return (vec![f64::INFINITY; p], None);
        }
        let scores = if sandwich {
            super::sandwich::bin_scores(&jac, &residual, data.bins())
        } else {
            Vec::new()
        };
        // Householder QR in place, sequential: at this size (at most ~6000 x 41) the threaded
        // version is about twice as slow, and a retune runs the blocks in parallel already.
        let block_size = qr::recommended_block_size::<f64>(rows, p);
        let mut coefficients = faer::Mat::<f64>::zeros(block_size, rows.min(p));
        let scratch = qr::qr_in_place_scratch::<f64>(rows, p, block_size, Par::Seq, Spec::default());
        let mut buffer = MemBuffer::new(scratch);
        qr::qr_in_place(
            jac.as_mut(),
            coefficients.as_mut(),
            Par::Seq,
            MemStack::new(&mut buffer),
            Spec::default(),
        );
        let r = DMatrix::from_fn(p, p, |i, j| if j >= i { jac[(i, j)] } else { 0.0 });
        let plain = std_from_r(&r);
        let robust = (sandwich && plain.iter().all(|v| v.is_finite()))
            .then(|| super::sandwich::variances(&r, &scores))
            .flatten();
        (plain, robust)
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
