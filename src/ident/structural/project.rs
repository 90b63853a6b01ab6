//! Variable projection: for a given denominator and delay, the numerator is a linear
//! generalised least-squares problem, solved exactly here.
//!
//! The basis `u_m = sigma^m e^(-j w tau) / d(sigma)` is shared by the nine elements. Row `i`'s
//! `3 max(n, 1) <= 12` numerator coefficients `n_mij` are coupled by the row weight `Omega_i`:
//! minimising `sum_k r_i Omega_i r_i^H`, `r_i = W_i - sum_m u_m n_mi`, gives the normal system
//! `G[(m, j), (l, j')] = sum_k Re(u_m conj(u_l) Omega_i[j, j'])`,
//! `rhs[(m, j)] = sum_k Re(u_m (Omega_i W_i^H)_j)`. Since `sigma = j x`,
//! `u_m conj(u_l) = x^(m + l) j^(m - l) / |d|^2` (the delay cancels), so `G` is assembled from
//! the `2 n - 1` moments `M_s = sum_k x_k^s Omega_ik / |d_k|^2` as `Re(j^(m - l) M_(m + l))`, and
//! `Omega_i W_i^H` is precomputed ([`Prepared::g`]). The system is solved by a Jacobi-scaled Cholesky
//! factorisation (with a tiny ridge only if it fails, e.g. a gain direction no bin weighs). The
//! buffers are reused across calls, so an evaluation inside the Levenberg–Marquardt loop does not
//! allocate.

use num_complex::Complex64;

use super::model::{ELEMENTS, Prepared};

/// Largest numerator size (order 4).
const MAX_NUM: usize = 4;
/// Largest normal system: one row's coefficients.
const MAX_SYS: usize = 3 * MAX_NUM;
/// Powers of `x` in the normal system: `0..=2 (MAX_NUM - 1)`.
const MAX_MOMENTS: usize = 2 * MAX_NUM - 1;

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
        // moments[s][18 i + f] = sum_k |1 / d_k|^2 x_k^s Omega_ik, flattened (re, im) row-major
        // (contiguous, so that the accumulation vectorises).
        let mut moments = [[0.0; 54]; MAX_MOMENTS];
        let mut rhs = [[0.0; MAX_SYS]; 3];
        for (k, phase) in data.phasors(tau).enumerate() {
            let x = data.x[k];
            let sigma = Complex64::new(0.0, x);
            let mut d = Complex64::new(0.0, 0.0);
            for c in den.iter().rev() {
                d = (d + c) * sigma;
            }
            let d = d + 1.0;
            let mut p = phase / d;
            let u = &mut self.u[k * nn..(k + 1) * nn];
            for um in u.iter_mut() {
                *um = p;
                p *= sigma;
            }
            let mut c = 1.0 / d.norm_sqr();
            let weight = &data.omega_flat[k];
            for moment in &mut moments[..2 * nn - 1] {
                for (a, w) in moment.iter_mut().zip(weight) {
                    *a += c * w;
                }
                c *= x;
            }
            for (i, rhs) in rhs.iter_mut().enumerate() {
                let g = &data.g[k][3 * i..3 * i + 3];
                for (m, um) in u.iter().enumerate() {
                    for (j, gj) in g.iter().enumerate() {
                        rhs[3 * m + j] += (um * gj).re;
                    }
                }
            }
        }
        // G[(m, j), (l, jj)] = Re(j^(m - l) M[m + l][j][jj]), lower triangle (l <= m there).
        let mut gram = [[[0.0; MAX_SYS]; MAX_SYS]; 3];
        for (i, gram) in gram.iter_mut().enumerate() {
            for q in 0..size {
                let (m, j) = (q / 3, q % 3);
                for q2 in 0..=q {
                    let (l, jj) = (q2 / 3, q2 % 3);
                    let e = 18 * i + 2 * (3 * j + jj);
                    let (re, im) = (moments[m + l][e], moments[m + l][e + 1]);
                    gram[q][q2] = match (m - l) % 4 {
                        0 => re,
                        1 => -im,
                        2 => -re,
                        _ => im,
                    };
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
