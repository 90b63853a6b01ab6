//! Variable projection: for a given denominator and delay, the numerator is a linear
//! generalised least-squares problem, solved exactly here.
//!
//! The basis `u_m = sigma^m e^(-j w tau) / d(sigma)` is shared by the nine elements. Row `i`'s
//! `3 max(n, 1) <= 12` numerator coefficients `n_mij` are coupled by the row weight `Omega_i`:
//! minimising `sum_k r_i Omega_i r_i^H`, `r_i = W_i - sum_m u_m n_mi`, gives the normal system
//! `G[(m, j), (l, j')] = sum_k Re(u_m conj(u_l) Omega_i[j, j'])`,
//! `rhs[(m, j)] = sum_k Re(u_m (Omega_i W_i^H)_j)`, solved by a Jacobi-scaled Cholesky
//! factorisation (with a tiny ridge only if it fails, e.g. a gain direction no bin weighs). The
//! buffers are reused across calls, so an evaluation inside the Levenberg–Marquardt loop does not
//! allocate.

use num_complex::Complex64;

use super::model::{ELEMENTS, Prepared};

/// Largest numerator size (order 4).
const MAX_NUM: usize = 4;
/// Largest normal system: one row's coefficients.
const MAX_SYS: usize = 3 * MAX_NUM;

/// Reusable buffers of the projection.
pub(super) struct Projector<'a> {
    data: &'a Prepared,
    n_num: usize,
    /// `u[k * n_num + m]`.
    u: Vec<Complex64>,
}

impl<'a> Projector<'a> {
    /// Buffers for numerators of `n_num` coefficients (`1..=4`).
    pub fn new(data: &'a Prepared, n_num: usize) -> Self {
        Self {
            data,
            n_num: n_num.clamp(1, MAX_NUM),
            u: vec![Complex64::new(0.0, 0.0); data.bins() * n_num.clamp(1, MAX_NUM)],
        }
    }

    /// The projected numerator for `(den, tau)` (normalised coefficients, delay in s) and, into
    /// `out` (length `18 n_bins`), the whitened real residuals `sqrt(2) (Re, Im)(r_i L_i)`.
    /// `None` when a normal system is singular beyond repair.
    pub fn project(&mut self, den: &[f64], tau: f64, out: &mut [f64]) -> Option<Vec<[f64; ELEMENTS]>> {
        let (data, nn) = (self.data, self.n_num);
        let size = 3 * nn;
        let mut gram = [[[0.0; MAX_SYS]; MAX_SYS]; 3];
        let mut rhs = [[0.0; MAX_SYS]; 3];
        for k in 0..data.bins() {
            let x = data.x[k];
            let sigma = Complex64::new(0.0, x);
            let mut d = Complex64::new(0.0, 0.0);
            for c in den.iter().rev() {
                d = (d + c) * sigma;
            }
            let mut p = Complex64::from_polar(1.0, -data.omega[k] * tau) / (d + 1.0);
            let u = &mut self.u[k * nn..(k + 1) * nn];
            for um in u.iter_mut() {
                *um = p;
                p *= sigma;
            }
            let mut prod = [[Complex64::new(0.0, 0.0); MAX_NUM]; MAX_NUM];
            for m in 0..nn {
                for l in 0..nn {
                    prod[m][l] = u[m] * u[l].conj();
                }
            }
            for (i, weight) in data.rows[k].iter().enumerate() {
                let omega = &weight.omega;
                let h = &data.h[k][3 * i..3 * i + 3];
                for j in 0..3 {
                    let g: Complex64 = (0..3).map(|l| omega[(j, l)] * h[l].conj()).sum();
                    for m in 0..nn {
                        let q = 3 * m + j;
                        rhs[i][q] += (u[m] * g).re;
                        for l in 0..=m {
                            for jj in 0..3 {
                                let q2 = 3 * l + jj;
                                if q2 <= q {
                                    let (a, b) = (prod[m][l], omega[(j, jj)]);
                                    gram[i][q][q2] += a.re * b.re - a.im * b.im;
                                }
                            }
                        }
                    }
                }
            }
        }
        let mut num = vec![[0.0; ELEMENTS]; nn];
        for i in 0..3 {
            let b = solve_spd(&gram[i], &rhs[i], size)?;
            for m in 0..nn {
                for j in 0..3 {
                    num[m][3 * i + j] = b[3 * m + j];
                }
            }
        }
        let sqrt2 = std::f64::consts::SQRT_2;
        for k in 0..data.bins() {
            let u = &self.u[k * nn..(k + 1) * nn];
            for (i, weight) in data.rows[k].iter().enumerate() {
                let r: [Complex64; 3] = std::array::from_fn(|j| {
                    let e = 3 * i + j;
                    data.h[k][e] - (0..nn).map(|m| u[m] * num[m][e]).sum::<Complex64>()
                });
                let base = 2 * (k * ELEMENTS + 3 * i);
                for (l, z) in weight.whiten(&r).iter().enumerate() {
                    out[base + 2 * l] = sqrt2 * z.re;
                    out[base + 2 * l + 1] = sqrt2 * z.im;
                }
            }
        }
        Some(num)
    }
}

/// Solves `G b = r` for the `n x n` leading block of a symmetric positive (semi)definite `G`
/// given by its lower triangle: Jacobi scaling, then Cholesky, retried with a ridge of `1e-13`
/// and `1e-10` (relative) if a pivot is not positive. `None` if all fail.
fn solve_spd(g: &[[f64; MAX_SYS]; MAX_SYS], r: &[f64; MAX_SYS], n: usize) -> Option<[f64; MAX_SYS]> {
    let mut scale = [1.0; MAX_SYS];
    for i in 0..n {
        if g[i][i] > 0.0 {
            scale[i] = 1.0 / g[i][i].sqrt();
        }
    }
    'ridge: for ridge in [0.0, 1e-13, 1e-10] {
        let mut l = [[0.0; MAX_SYS]; MAX_SYS];
        for i in 0..n {
            for j in 0..=i {
                let mut v = g[i][j] * scale[i] * scale[j] + if i == j { ridge } else { 0.0 };
                for m in 0..j {
                    v -= l[i][m] * l[j][m];
                }
                if i == j {
                    if !(v > 0.0 && v.is_finite()) {
                        continue 'ridge;
                    }
                    l[i][i] = v.sqrt();
                } else {
                    l[i][j] = v / l[j][j];
                }
            }
        }
        let mut y = [0.0; MAX_SYS];
        for i in 0..n {
            let s: f64 = (0..i).map(|m| l[i][m] * y[m]).sum();
            y[i] = (r[i] * scale[i] - s) / l[i][i];
        }
        let mut b = [0.0; MAX_SYS];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|m| l[m][i] * b[m]).sum();
            b[i] = (y[i] - s) / l[i][i];
        }
        for i in 0..n {
            b[i] *= scale[i];
        }
        if b[..n].iter().all(|v| v.is_finite()) {
            return Some(b);
        }
    }
    None
}
