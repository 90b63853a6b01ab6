//! The overlapping Allan deviation of a rate series (IEEE 952 Annex C, NIST SP 1065 eq. 13) with
//! its equivalent degrees of freedom and confidence interval (SP 1065 Table 5 and eq. 45).
//!
//! Input: `rate` samples `y_n` at `sample_rate_hz` (output units, e.g. rad/s). With the phase
//! `x_k = tau0 sum_{n<k} y_n` (`N = len + 1` phase points) and `tau = m tau0`,
//! `sigma^2(tau) = sum_{k=0}^{N-2m-1} (x_{k+2m} - 2 x_{k+m} + x_k)^2 / (2 tau^2 (N - 2m))`,
//! which is `allantools.oadev(y, rate, data_type="freq")`. The mean is removed before the
//! cumulative sum (the deviation does not depend on it; rounding does). Factors `m` with
//! `N - 2m < 1` are skipped; an empty or non-finite series gives no points.

use serde::{Deserialize, Serialize};

use super::chi2::chi2_quantile;

/// Probability content of the stated intervals: one sigma of a normal distribution.
pub const ONE_SIGMA: f64 = 0.682_689_492_137_086;

/// The power-law noise type that sets the degrees of freedom of an Allan variance (the exponent
/// `alpha` of the fractional-frequency spectrum `S_y(f) ~ f^alpha`, SP 1065 Table 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PowerLaw {
    /// `alpha = 2`: white phase (angle quantisation, the reference's white angle noise).
    WhitePhase,
    /// `alpha = 0`: white rate (angle / velocity random walk).
    WhiteRate,
    /// `alpha = -1`: flicker rate (bias instability).
    FlickerRate,
    /// `alpha = -2`: random-walk rate (rate / acceleration random walk).
    RandomWalkRate,
}

/// One point of an Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AllanPoint {
    /// Averaging time, s.
    pub tau_s: f64,
    /// Overlapping Allan deviation, output units.
    pub adev: f64,
    /// Equivalent degrees of freedom (for the noise type dominant at this `tau`).
    pub edf: f64,
    /// Lower end of the one-sigma (68.3 %) confidence interval.
    pub lo: f64,
    /// Upper end of the one-sigma confidence interval.
    pub hi: f64,
}

/// Averaging factors `m`: about `per_octave` per octave from 1 up to a quarter of the record
/// (the longest `tau` keeps a few independent differences), ascending, no duplicates.
#[must_use]
pub fn averaging_factors(len: usize, per_octave: u32) -> Vec<usize> {
    let max = len / 4;
    let mut out: Vec<usize> = Vec::new();
    let step = 2.0_f64.powf(1.0 / f64::from(per_octave.max(1)));
    let mut m = 1.0_f64;
    while m.round() <= max as f64 {
        #[expect(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "m >= 1, below len"
        )]
        let mi = m.round() as usize;
        if out.last() != Some(&mi) {
            out.push(mi);
        }
        m *= step;
    }
    out
}

/// The phase `x_k` (`len + 1` points from 0) of the mean-removed rate series, in output units x s.
#[must_use]
pub fn phase(rate: &[f64], sample_rate_hz: f64) -> Vec<f64> {
    let tau0 = 1.0 / sample_rate_hz;
    let mean = rate.iter().sum::<f64>() / rate.len().max(1) as f64;
    let mut x = Vec::with_capacity(rate.len() + 1);
    let mut acc = 0.0;
    x.push(0.0);
    for y in rate {
        acc += (y - mean) * tau0;
        x.push(acc);
    }
    x
}

/// The overlapping Allan variance at factor `m` from the phase `x` (`None` when `x` is too short).
#[must_use]
pub fn overlapping_avar(x: &[f64], m: usize, tau0: f64) -> Option<f64> {
    let n = x.len();
    if m == 0 || n < 2 * m + 1 {
        return None;
    }
    let terms = n - 2 * m;
    let sum: f64 = (0..terms)
        .map(|k| {
            let d = x[k + 2 * m] - 2.0 * x[k + m] + x[k];
            d * d
        })
        .sum();
    let tau = m as f64 * tau0;
    Some(sum / (2.0 * tau * tau * terms as f64))
}

/// Equivalent degrees of freedom of the overlapping Allan variance (NIST SP 1065 Table 5, the
/// "simple" approximations), for `n` phase points, factor `m` and noise type `law`.
#[must_use]
pub fn edf(n: usize, m: usize, law: PowerLaw) -> f64 {
    let (n, m) = (n as f64, m as f64);
    let value = match law {
        PowerLaw::WhitePhase => (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m)),
        PowerLaw::WhiteRate => {
            (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * (4.0 * m * m / (4.0 * m * m + 5.0))
        }
        PowerLaw::FlickerRate if m < 1.5 => 2.0 * (n - 2.0).powi(2) / (2.3 * n - 4.9),
        PowerLaw::FlickerRate => 5.0 * n * n / (4.0 * m * (n + 3.0 * m)),
        PowerLaw::RandomWalkRate => {
            (n - 2.0) / (m * (n - 3.0).powi(2)) * ((n - 1.0).powi(2) - 3.0 * m * (n - 1.0) + 4.0 * m * m)
        }
    };
    // Never fewer than one degree of freedom: the formulas are asymptotic and can dip below
    // it at the longest averaging times.
    value.max(1.0)
}

/// The `probability` confidence interval `(lo, hi)` of an Allan deviation `adev` with `edf`
/// degrees of freedom (SP 1065 eq. 45: `edf s^2 / chi2_hi <= sigma^2 <= edf s^2 / chi2_lo`).
#[must_use]
pub fn confidence_interval(adev: f64, edf: f64, probability: f64) -> (f64, f64) {
    let tail = 0.5 * (1.0 - probability);
    let chi_lo = chi2_quantile(tail, edf);
    let chi_hi = chi2_quantile(1.0 - tail, edf);
    let var = adev * adev;
    ((edf * var / chi_hi).sqrt(), (edf * var / chi_lo).sqrt())
}

/// The overlapping Allan deviation of `rate` at the factors `ms`, with one-sigma intervals for
/// the noise type `law(m)` names at each factor. Non-finite samples give no points.
#[must_use]
pub fn overlapping_adev(
    rate: &[f64],
    sample_rate_hz: f64,
    ms: &[usize],
    law: impl Fn(usize) -> PowerLaw,
) -> Vec<AllanPoint> {
    if rate.is_empty()
        || !rate.iter().all(|v| v.is_finite())
        || sample_rate_hz.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return Vec::new();
    }
    let tau0 = 1.0 / sample_rate_hz;
    let x = phase(rate, sample_rate_hz);
    ms.iter()
        .filter_map(|&m| Some(point(overlapping_avar(&x, m, tau0)?, m, tau0, x.len(), law(m))))
        .collect()
}

/// The point of an Allan variance `avar` measured at factor `m` on `n_phase` phase points, with
/// its interval for the noise type `law`.
#[must_use]
pub fn point(avar: f64, m: usize, tau0: f64, n_phase: usize, law: PowerLaw) -> AllanPoint {
    let adev = avar.sqrt();
    let edf = edf(n_phase, m, law);
    let (lo, hi) = confidence_interval(adev, edf, ONE_SIGMA);
    AllanPoint {
        tau_s: m as f64 * tau0,
        adev,
        edf,
        lo,
        hi,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The definition written out with a fresh sum per difference (no shared phase).
    fn naive_avar(y: &[f64], m: usize, tau0: f64) -> f64 {
        let n = y.len();
        let mut sum = 0.0;
        let mut count = 0;
        for k in 0..=(n - 2 * m) {
            let a: f64 = y[k..k + m].iter().sum::<f64>() / m as f64;
            let b: f64 = y[k + m..k + 2 * m].iter().sum::<f64>() / m as f64;
            sum += (b - a) * (b - a);
            count += 1;
        }
        let _ = tau0;
        sum / (2.0 * f64::from(count))
    }

    #[test]
    fn the_phase_form_equals_averages_of_adjacent_clusters() {
        let mut rng = Rng::new(3);
        let y: Vec<f64> = (0..500)
            .map(|i| rng.normal() + 1e-3 * f64::from(i) + 7.0)
            .collect();
        let x = phase(&y, 100.0);
        for m in [1, 2, 5, 17, 100, 250] {
            let fast = overlapping_avar(&x, m, 0.01).expect("long enough");
            let naive = naive_avar(&y, m, 0.01);
            assert!((fast - naive).abs() <= 1e-10 * naive, "m {m}: {fast} vs {naive}");
        }
        assert_eq!(overlapping_avar(&x, 251, 0.01), None);
    }

    #[test]
    fn white_rate_noise_follows_its_closed_form() {
        // Two-sided density N^2 => sigma^2(tau) = N^2 / tau; samples of variance N^2 fs.
        let (fs, n_density) = (200.0_f64, 0.01);
        let mut rng = Rng::new(11);
        let y: Vec<f64> = (0..400_000)
            .map(|_| n_density * fs.sqrt() * rng.normal())
            .collect();
        let points = overlapping_adev(&y, fs, &averaging_factors(y.len(), 1), |_| PowerLaw::WhiteRate);
        let mut inside = 0;
        for p in &points {
            let want = n_density / p.tau_s.sqrt();
            inside += usize::from(p.lo <= want && want <= p.hi);
            assert!(p.lo < p.adev && p.adev < p.hi);
        }
        // One-sigma intervals: about 68 % hold the truth (neighbouring points are correlated).
        assert!(inside * 10 >= points.len() * 4, "{inside} of {}", points.len());
    }

    #[test]
    fn edf_formulas_match_their_known_limits() {
        // White rate at m = 1 and large N: (3N/2 - 2) 4/9 ~ 2N/3.
        let n = 1_000_001;
        assert!((edf(n, 1, PowerLaw::WhiteRate) / (2.0 * n as f64 / 3.0) - 1.0).abs() < 1e-5);
        // Random walk at m = 1: (N-2)/(N-3)^2 ((N-1)^2 - 3(N-1) + 4) ~ N.
        assert!((edf(n, 1, PowerLaw::RandomWalkRate) / n as f64 - 1.0).abs() < 1e-5);
        // The floor of one degree of freedom.
        assert!((edf(4, 2, PowerLaw::WhitePhase) - 1.0).abs() < 1e-12);
        let ms = averaging_factors(1000, 2);
        assert_eq!(ms[..6], [1, 2, 3, 4, 6, 8]);
        assert!(ms.last().is_some_and(|&m| m > 125 && m <= 250), "{ms:?}");
    }
}
