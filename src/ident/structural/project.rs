//! Variable projection: for a given denominator and delay, each element's numerator is a linear
//! weighted least-squares problem with `max(n, 1) <= 4` unknowns, solved exactly here.
//!
//! The basis `u_m = sigma^m e^(-j w tau) / d(sigma)` is shared by the nine elements (only their
//! weights differ), so it and the products `Re(conj(u_m) u_l)` are formed once per bin; the
//! per-element normal systems are at most 4x4 and solved by a Jacobi-scaled Cholesky
//! factorisation (with a tiny ridge only if it fails). The buffers are reused across calls, so
//! an evaluation inside the Levenberg–Marquardt loop does not allocate.

use num_complex::Complex64;

use super::model::{ELEMENTS, Prepared};

/// Largest numerator size (order 4).
const MAX_NUM: usize = 4;

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
    /// `out` (length `18 n_bins`), the weighted real residuals `sqrt(2 w) (Re, Im)(h - model)`.
    /// `None` when a normal system is singular beyond repair.
    pub fn project(&mut self, den: &[f64], tau: f64, out: &mut [f64]) -> Option<Vec<[f64; ELEMENTS]>> {
        let (data, nn) = (self.data, self.n_num);
        let mut gram = [[[0.0; MAX_NUM]; MAX_NUM]; ELEMENTS];
        let mut rhs = [[0.0; MAX_NUM]; ELEMENTS];
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
            let mut prod = [[0.0; MAX_NUM]; MAX_NUM];
            for m in 0..nn {
                for l in 0..=m {
                    prod[m][l] = u[m].re * u[l].re + u[m].im * u[l].im;
                }
            }
            for e in 0..ELEMENTS {
                let (w, h) = (data.w[k][e], data.h[k][e]);
                for m in 0..nn {
                    rhs[e][m] += w * (u[m].re * h.re + u[m].im * h.im);
                    for l in 0..=m {
                        gram[e][m][l] += w * prod[m][l];
                    }
                }
            }
        }
        let mut num = vec![[0.0; ELEMENTS]; nn];
        for e in 0..ELEMENTS {
            let b = solve_spd(&gram[e], &rhs[e], nn)?;
            for m in 0..nn {
                num[m][e] = b[m];
            }
        }
        for k in 0..data.bins() {
            let u = &self.u[k * nn..(k + 1) * nn];
            for e in 0..ELEMENTS {
                let fit: Complex64 = (0..nn).map(|m| u[m] * num[m][e]).sum();
                let r = (data.h[k][e] - fit) * (2.0 * data.w[k][e]).sqrt();
                let i = 2 * (k * ELEMENTS + e);
                out[i] = r.re;
                out[i + 1] = r.im;
            }
        }
        Some(num)
    }
}

/// Solves `G b = r` for the `n x n` leading block of a symmetric positive (semi)definite `G`
/// given by its lower triangle: Jacobi scaling, then Cholesky, retried with a ridge of `1e-13`
/// and `1e-10` (relative) if a pivot is not positive. `None` if all fail.
fn solve_spd(g: &[[f64; MAX_NUM]; MAX_NUM], r: &[f64; MAX_NUM], n: usize) -> Option<[f64; MAX_NUM]> {
    let mut scale = [1.0; MAX_NUM];
    for i in 0..n {
        if g[i][i] > 0.0 {
            scale[i] = 1.0 / g[i][i].sqrt();
        }
    }
    'ridge: for ridge in [0.0, 1e-13, 1e-10] {
        let mut l = [[0.0; MAX_NUM]; MAX_NUM];
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
        let mut y = [0.0; MAX_NUM];
        for i in 0..n {
            let s: f64 = (0..i).map(|m| l[i][m] * y[m]).sum();
            y[i] = (r[i] * scale[i] - s) / l[i][i];
        }
        let mut b = [0.0; MAX_NUM];
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
