//! Per-segment detrending, applied before the window (as scipy's `_fft_helper` does).

use serde::{Deserialize, Serialize};

/// What is removed from each segment before it is windowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Detrend {
    /// Nothing (scipy `detrend=False`).
    None,
    /// The segment's mean (scipy `detrend='constant'`).
    #[default]
    Mean,
    /// The segment's least-squares straight line (scipy `detrend='linear'`).
    Linear,
}

impl Detrend {
    /// Detrends `segment` in place. A segment of length 0 is left alone; a segment of length 1
    /// becomes 0 under `Mean` and `Linear`.
    pub fn apply(self, segment: &mut [f64]) {
        let n = segment.len();
        if n == 0 {
            return;
        }
        match self {
            Self::None => {}
            Self::Mean => {
                let mean = segment.iter().sum::<f64>() / n as f64;
                for x in segment.iter_mut() {
                    *x -= mean;
                }
            }
            Self::Linear => {
                // Centred abscissa t_k = k - (n-1)/2, so the fit decouples:
                // intercept = mean, slope = sum(t x) / sum(t^2), sum(t^2) = n (n^2 - 1) / 12.
                let nf = n as f64;
                let centre = (nf - 1.0) / 2.0;
                let mean = segment.iter().sum::<f64>() / nf;
                let stt = nf * (nf * nf - 1.0) / 12.0;
                let stx: f64 = segment
                    .iter()
                    .enumerate()
                    .map(|(k, &x)| (k as f64 - centre) * (x - mean))
                    .sum();
                let slope = if stt > 0.0 { stx / stt } else { 0.0 };
                for (k, x) in segment.iter_mut().enumerate() {
                    *x -= mean + slope * (k as f64 - centre);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Detrend;
    use crate::rng::Rng;

    #[test]
    fn linear_removes_a_line_and_leaves_orthogonal_residual() {
        let mut rng = Rng::new(7);
        let noise: Vec<f64> = (0..37).map(|_| rng.normal()).collect();
        let mut x: Vec<f64> = noise
            .iter()
            .enumerate()
            .map(|(k, e)| 3.0 - 0.25 * k as f64 + e)
            .collect();
        Detrend::Linear.apply(&mut x);
        // Residual is orthogonal to 1 and to k (normal equations of the least-squares fit).
        let s0: f64 = x.iter().sum();
        let s1: f64 = x.iter().enumerate().map(|(k, r)| k as f64 * r).sum();
        assert!(s0.abs() < 1e-12 && s1.abs() < 1e-10, "{s0} {s1}");
        // A pure line detrends to zero.
        let mut line: Vec<f64> = (0..10_u32).map(|k| 1.5 + 2.0 * f64::from(k)).collect();
        Detrend::Linear.apply(&mut line);
        assert!(line.iter().all(|r| r.abs() < 1e-12), "{line:?}");
    }

    #[test]
    fn mean_and_none() {
        let mut x = vec![1.0, 2.0, 6.0];
        Detrend::None.apply(&mut x);
        assert_eq!(x, [1.0, 2.0, 6.0]);
        Detrend::Mean.apply(&mut x);
        assert_eq!(x, [-2.0, -1.0, 3.0]);
        let mut one = vec![5.0];
        Detrend::Linear.apply(&mut one);
        assert_eq!(one, [0.0]);
    }

    #[test]
    fn serde_names() {
        let names: Vec<String> = [Detrend::None, Detrend::Mean, Detrend::Linear]
            .iter()
            .map(|d| serde_json::to_string(d).unwrap())
            .collect();
        assert_eq!(names, ["\"none\"", "\"mean\"", "\"linear\""]);
    }
}
