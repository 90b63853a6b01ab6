//! The chi-square distribution's quantiles, for the confidence intervals of Allan deviations
//! (NIST SP 1065 eq. 45: `edf s^2 / chi2_{1-p/2}(edf) <= sigma^2 <= edf s^2 / chi2_{p/2}(edf)`).
//!
//! Degrees of freedom are real and positive (an Allan variance's equivalent degrees of freedom
//! are not integers). Non-finite or non-positive arguments give NaN, never a panic.

/// `ln Gamma(x)` for `x > 0`: Stirling's series after shifting `x` above 10 (relative error
/// below 1e-14).
#[must_use]
pub fn ln_gamma(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return f64::NAN;
    }
    // Gamma(x) = Gamma(x + n) / (x (x+1) ... (x+n-1)): one logarithm of the product.
    let mut product = 1.0;
    let mut z = x;
    while z < 10.0 {
        product *= z;
        z += 1.0;
    }
    let shift = product.ln();
    let inv = 1.0 / z;
    let inv2 = inv * inv;
    let series = inv
        * (1.0 / 12.0 - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 / 1188.0))));
    (z - 0.5) * z.ln() - z + 0.5 * (2.0 * std::f64::consts::PI).ln() + series - shift
}

/// The regularised lower incomplete gamma function `P(a, x)` (series below `a + 1`, Lentz's
/// continued fraction above).
#[must_use]
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if !(a.is_finite() && a > 0.0 && x.is_finite()) {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // sum_n x^n / (a (a+1) ... (a+n))
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..100_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-17 {
                break;
            }
        }
        (sum.ln() + log_prefactor).exp()
    } else {
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -f64::from(i) * (f64::from(i) - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - (h.ln() + log_prefactor).exp()
    }
}

/// The chi-square cumulative distribution with `dof` degrees of freedom at `x`.
#[must_use]
pub fn chi2_cdf(x: f64, dof: f64) -> f64 {
    gamma_p(0.5 * dof, 0.5 * x)
}

/// The `p`-quantile of the chi-square distribution with `dof` degrees of freedom (`0 < p < 1`):
/// Wilson-Hilferty's start, then safeguarded Newton steps on [`chi2_cdf`] to full precision.
#[must_use]
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && dof.is_finite() && dof > 0.0) {
        return f64::NAN;
    }
    let z = normal_quantile(p);
    let h = 2.0 / (9.0 * dof);
    let base = 1.0 - h + z * h.sqrt();
    let mut x = if base > 0.0 {
        dof * base.powi(3)
    } else {
        // Far lower tail: P(a, y) ~ y^a / Gamma(a + 1), a = dof/2, y = x/2.
        2.0 * (p.ln() + ln_gamma(0.5 * dof + 1.0)).mul_add(2.0 / dof, 0.0).exp()
    };
    // Bracket [lo, hi] kept around the root; Newton steps leaving it are replaced by bisection.
    let (mut lo, mut hi) = (0.0_f64, f64::INFINITY);
    let half = 0.5 * dof;
    for _ in 0..200 {
        let f = chi2_cdf(x, dof) - p;
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        // Density of chi2(dof) at x, in logs.
        let log_pdf = (half - 1.0) * x.ln() - 0.5 * x - half * 2.0_f64.ln() - ln_gamma(half);
        let step = f / log_pdf.exp();
        // Newton, damped to a factor of four per step, bisected (geometrically) when it leaves
        // the bracket.
        let mut next = if (x - step).is_finite() {
            (x - step).clamp(0.25 * x, 4.0 * x)
        } else if f > 0.0 {
            0.25 * x
        } else {
            4.0 * x
        };
        if next <= lo || next >= hi {
            next = match (lo > 0.0, hi.is_finite()) {
                (true, true) => (lo * hi).sqrt(),
                (false, true) => 0.25 * hi,
                _ => 4.0 * lo,
            };
        }
        if (next - x).abs() <= 1e-15 * x {
            return next;
        }
        x = next;
    }
    x
}

/// The standard normal quantile (Acklam's rational approximation, relative error 1.2e-9; only a
/// starting point here).
fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials_and_the_half_integer_closed_form() {
        let mut factorial = 1.0_f64;
        for n in 1..30 {
            // Gamma(n) = (n-1)!
            let got = ln_gamma(f64::from(n));
            assert!(
                (got - factorial.ln()).abs() <= 1e-13 * factorial.ln().abs().max(1.0),
                "{n}"
            );
            factorial *= f64::from(n);
        }
        // Gamma(1/2) = sqrt(pi), Gamma(7/2) = 15 sqrt(pi) / 8.
        let sqrt_pi_ln = 0.5 * std::f64::consts::PI.ln();
        assert!((ln_gamma(0.5) - sqrt_pi_ln).abs() < 1e-14);
        assert!((ln_gamma(3.5) - (15.0_f64 / 8.0).ln() - sqrt_pi_ln).abs() < 1e-14);
        assert!(ln_gamma(0.0).is_nan() && ln_gamma(f64::NAN).is_nan());
    }

    #[test]
    fn chi2_cdf_matches_its_closed_forms() {
        // dof 2: 1 - exp(-x/2); dof 1: erf(sqrt(x/2)) at x = 1: 0.682689492137086.
        for x in [0.01_f64, 0.5, 1.0, 3.0, 10.0, 40.0] {
            let want = 1.0 - (-0.5 * x).exp();
            assert!((chi2_cdf(x, 2.0) - want).abs() < 1e-13, "{x}");
        }
        assert!((chi2_cdf(1.0, 1.0) - 0.682_689_492_137_086).abs() < 1e-14);
    }

    #[test]
    fn quantiles_invert_the_cdf_over_a_wide_range_of_dof() {
        for dof in [0.7, 1.0, 2.0, 3.3, 10.0, 57.5, 400.0, 12_345.0, 2.0e6] {
            for p in [1e-6, 0.001, 0.1585, 0.5, 0.8415, 0.999] {
                let x = chi2_quantile(p, dof);
                let back = chi2_cdf(x, dof);
                // Above 1e4 dof the cdf itself is good to ~1e-9 relative (the prefactor's logarithm).
                let tol = if dof > 1e4 { 1e-8 * p } else { 1e-10 * p.max(1e-3) };
                assert!((back - p).abs() <= tol + 1e-13, "{dof} {p}: {back}");
            }
        }
        // dof 2 closed form: x = -2 ln(1 - p).
        let x = chi2_quantile(0.9, 2.0);
        assert!((x + 2.0 * 0.1_f64.ln()).abs() < 1e-12);
        assert!(chi2_quantile(0.0, 3.0).is_nan() && chi2_quantile(0.5, -1.0).is_nan());
    }
}
