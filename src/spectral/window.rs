//! Segment windows, periodic ("DFT-even") as `scipy.signal.get_window(name, n)` makes them.
//!
//! A periodic window of length `n` is the symmetric window of length `n + 1` with its last
//! sample dropped: `w[k] = f(2 pi k / n)` for `k = 0..n`. That is the form spectral analysis
//! wants (the window tiles the DFT period exactly) and scipy's default for `get_window`.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The taper applied to each Welch segment after detrending.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Window {
    /// All ones (scipy `"boxcar"`).
    Rectangular,
    /// `0.5 - 0.5 cos(2 pi k / n)` (scipy `"hann"`).
    #[default]
    Hann,
    /// `0.54 - 0.46 cos(2 pi k / n)` (scipy `"hamming"`).
    Hamming,
    /// The 4-term minimum-sidelobe Blackman-Harris window (scipy `"blackmanharris"`).
    BlackmanHarris,
}

/// Blackman-Harris cosine coefficients, as in scipy's `blackmanharris`.
const BLACKMAN_HARRIS: [f64; 4] = [0.35875, 0.48829, 0.14128, 0.01168];

impl Window {
    /// The name scipy's `get_window` knows this window by.
    #[must_use]
    pub fn scipy_name(self) -> &'static str {
        match self {
            Self::Rectangular => "boxcar",
            Self::Hann => "hann",
            Self::Hamming => "hamming",
            Self::BlackmanHarris => "blackmanharris",
        }
    }

    /// Sample `k` of the periodic window of length `n` (`n > 0`, `k < n`).
    #[must_use]
    pub fn value(self, k: usize, n: usize) -> f64 {
        let theta = TAU * k as f64 / n as f64;
        match self {
            Self::Rectangular => 1.0,
            Self::Hann => 0.5 - 0.5 * theta.cos(),
            Self::Hamming => 0.54 - 0.46 * theta.cos(),
            Self::BlackmanHarris => {
                let [a0, a1, a2, a3] = BLACKMAN_HARRIS;
                a0 - a1 * theta.cos() + a2 * (2.0 * theta).cos() - a3 * (3.0 * theta).cos()
            }
        }
    }

    /// The whole periodic window of length `n` (empty for `n == 0`).
    #[must_use]
    pub fn coefficients(self, n: usize) -> Vec<f64> {
        (0..n).map(|k| self.value(k, n)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::Window;

    #[test]
    fn periodic_windows_match_closed_forms() {
        // n = 8: the periodic Hann is the symmetric 9-point Hann without its last sample.
        let hann = Window::Hann.coefficients(8);
        let expect = [0.0, 0.146_446_609_406_726_24, 0.5, 0.853_553_390_593_273_8, 1.0];
        for (k, e) in expect.iter().enumerate() {
            assert!((hann[k] - e).abs() < 1e-15, "hann[{k}] = {}", hann[k]);
        }
        // Periodic, not symmetric: w[k] == w[n - k] for 0 < k < n, and w[0] has no partner.
        for k in 1..8 {
            assert!((hann[k] - hann[8 - k]).abs() < 1e-15);
        }
        let hamming = Window::Hamming.coefficients(4);
        for (got, e) in hamming.iter().zip([0.08, 0.54, 1.0, 0.54]) {
            assert!((got - e).abs() < 1e-15);
        }
        let bh = Window::BlackmanHarris.coefficients(16);
        assert!(
            (bh[0] - 6e-5).abs() < 1e-15,
            "Blackman-Harris starts at 6e-5, got {}",
            bh[0]
        );
        assert!(
            (bh[8] - 1.0).abs() < 1e-15,
            "and peaks at 1 in the middle, got {}",
            bh[8]
        );
        assert!(
            Window::Rectangular
                .coefficients(5)
                .iter()
                .all(|&w| (w - 1.0).abs() < f64::EPSILON)
        );
    }

    #[test]
    fn serde_names() {
        let names: Vec<String> = [
            Window::Rectangular,
            Window::Hann,
            Window::Hamming,
            Window::BlackmanHarris,
        ]
        .iter()
        .map(|w| serde_json::to_string(w).unwrap())
        .collect();
        assert_eq!(
            names,
            [
                "\"rectangular\"",
                "\"hann\"",
                "\"hamming\"",
                "\"blackman_harris\""
            ]
        );
        let back: Window = serde_json::from_str("\"blackman_harris\"").unwrap();
        assert_eq!(back, Window::BlackmanHarris);
    }
}
