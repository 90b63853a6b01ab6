//! Band-limited interpolation at arbitrary instants, independent of the FFT-based synthesis: an
//! 8-point Lagrange interpolator, for delaying or time-warping a smooth, oversampled record
//! (tests use it as an independent reference; a clock that runs at another rate is a time warp).
//!
//! Units: `rate` in Hz, `t` in s from the first sample; instants outside the record use the
//! nearest samples (clamped). An empty record gives 0.

/// `x` (sampled at `rate`) interpolated at time `t` by the 8-point Lagrange polynomial through
/// the samples around it.
#[must_use]
pub fn lagrange(x: &[f64], rate: f64, t: f64) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let pos = t * rate;
    let base = pos.floor() as isize - 3;
    let mut sum = 0.0;
    for m in 0..8 {
        let i = (base + m).clamp(0, x.len() as isize - 1) as usize;
        let mut w = 1.0;
        for q in 0..8 {
            if q != m {
                w *= (pos - (base + q) as f64) / (m - q) as f64;
            }
        }
        sum += w * x[i];
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::lagrange;

    #[test]
    fn a_cubic_is_interpolated_exactly_and_samples_are_kept() {
        let x: Vec<f64> = (0..32)
            .map(|i| f64::from(i).powi(3) - 2.0 * f64::from(i))
            .collect();
        let t = 12.37;
        assert!((lagrange(&x, 1.0, t) - (t * t * t - 2.0 * t)).abs() < 1e-9);
        assert!((lagrange(&x, 1.0, 5.0) - x[5]).abs() < 1e-12);
        assert!(lagrange(&[], 1.0, 0.5).abs() < f64::EPSILON);
    }
}
