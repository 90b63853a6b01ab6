//! Band-limited synthesis on a periodic grid: shaped Gaussian noise with prescribed one-sided
//! spectral density, exact derivatives and exact (fractional) delays and linear filters applied in
//! the frequency domain.
//!
//! A bin carries `X_k = sqrt(L fs / 2) B(f_k) xi_k` with `xi_k` unit complex normal, which makes
//! the one-sided density of the inverse transform `B B^H` (see `fourier` for the transform
//! conventions). DC and Nyquist bins are kept at zero, so every signal is zero-mean and its
//! derivatives are well defined.

use num_complex::Complex64;

use crate::fourier::RecordFft;
use crate::rng::Rng;

/// The synthesis grid: plans plus the angular frequency of every one-sided bin.
pub struct Grid {
    /// Plans for the padded record length.
    pub fft: RecordFft,
    /// `2 pi f_k`, rad/s.
    pub omega: Vec<f64>,
}

impl Grid {
    /// A grid of `len` samples at `rate_hz`.
    #[must_use]
    pub fn new(len: usize, rate_hz: f64) -> Self {
        let fft = RecordFft::new(len, rate_hz);
        let omega = (0..fft.n_bins())
            .map(|k| 2.0 * std::f64::consts::PI * fft.frequency_hz(k))
            .collect();
        Self { fft, omega }
    }

    /// One unit complex-normal draw per bin (zero at DC and Nyquist), scaled so that a shape
    /// `B(f)` multiplying it yields one-sided density `|B|^2`.
    pub fn white(&self, rng: &mut Rng) -> Vec<Complex64> {
        let scale = (self.fft.len() as f64 * self.fft.sample_rate_hz() / 2.0).sqrt()
            * std::f64::consts::FRAC_1_SQRT_2;
        let last = self.omega.len() - 1;
        (0..self.omega.len())
            .map(|k| {
                let z = Complex64::new(rng.normal(), rng.normal()) * scale;
                if k == 0 || k == last {
                    Complex64::default()
                } else {
                    z
                }
            })
            .collect()
    }

    /// `spectrum * shape(f)` bin by bin.
    #[must_use]
    pub fn shape(&self, spectrum: &[Complex64], shape: impl Fn(f64) -> Complex64) -> Vec<Complex64> {
        let two_pi = 2.0 * std::f64::consts::PI;
        spectrum
            .iter()
            .zip(&self.omega)
            .map(|(x, w)| x * shape(w / two_pi))
            .collect()
    }

    /// The `order`-th time derivative (`(j w)^order`).
    #[must_use]
    pub fn derivative(&self, spectrum: &[Complex64], order: i32) -> Vec<Complex64> {
        spectrum
            .iter()
            .zip(&self.omega)
            .map(|(x, w)| x * Complex64::new(0.0, *w).powi(order))
            .collect()
    }

    /// Delayed by `tau_s` seconds, exactly for a band-limited periodic signal.
    #[must_use]
    pub fn delay(&self, spectrum: &[Complex64], tau_s: f64) -> Vec<Complex64> {
        spectrum
            .iter()
            .zip(&self.omega)
            .map(|(x, w)| x * Complex64::from_polar(1.0, -w * tau_s))
            .collect()
    }

    /// Mean square of the time signal whose spectrum is `spectrum` (Parseval on the one-sided
    /// storage, DC and Nyquist zero).
    #[must_use]
    pub fn mean_square(&self, spectrum: &[Complex64]) -> f64 {
        let l = self.fft.len() as f64;
        2.0 * spectrum.iter().map(Complex64::norm_sqr).sum::<f64>() / (l * l)
    }
}

/// Second-order resonant low-pass `1 / (1 - (f/f0)^2 + 2 j zeta f/f0)`.
#[must_use]
pub fn resonant_lowpass(f: f64, f0: f64, zeta: f64) -> Complex64 {
    let r = f / f0;
    Complex64::new(1.0 - r * r, 2.0 * zeta * r).inv()
}

/// Causal second-order Butterworth low-pass at `fc`, Hz: the resonant low-pass damped at
/// `1 / sqrt(2)`, `1 / (1 + sqrt(2) j f/fc - (f/fc)^2)`.
#[must_use]
pub fn butterworth2(f: f64, fc: f64) -> Complex64 {
    resonant_lowpass(f, fc, std::f64::consts::FRAC_1_SQRT_2)
}

/// First-order low-pass `1 / (1 + j f / fc)`.
#[must_use]
pub fn first_order_lowpass(f: f64, fc: f64) -> Complex64 {
    Complex64::new(1.0, f / fc).inv()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_has_the_prescribed_density_and_variance() {
        let grid = Grid::new(1 << 16, 200.0);
        let mut rng = Rng::new(3);
        // One-sided density 0.02 units^2/Hz from 0 to 100 Hz: variance 2.0.
        let x = grid.shape(&grid.white(&mut rng), |_| Complex64::from(0.02f64.sqrt()));
        let ms = grid.mean_square(&x);
        let mut grid = grid;
        let t = grid.fft.inverse(x.clone());
        let var = t.iter().map(|v| v * v).sum::<f64>() / t.len() as f64;
        assert!((ms - var).abs() < 1e-9 * var, "Parseval: {ms} vs {var}");
        assert!((var - 2.0).abs() < 0.05, "variance {var}");
    }

    #[test]
    fn derivative_and_delay_are_exact_for_a_sinusoid() {
        let n = 1000;
        let rate = 100.0;
        let mut grid = Grid::new(n, rate);
        let f0 = 7.0; // bin 70 exactly
        let x: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * f0 * i as f64 / rate).sin())
            .collect();
        let spec = grid.fft.forward(&x);
        let d = grid.fft.inverse(grid.derivative(&spec, 1));
        let tau = 0.00123;
        let delayed = grid.fft.inverse(grid.delay(&spec, tau));
        let w = 2.0 * std::f64::consts::PI * f0;
        for i in 0..n {
            let t = i as f64 / rate;
            assert!((d[i] - w * (w * t).cos()).abs() < 1e-9 * w);
            assert!((delayed[i] - (w * (t - tau)).sin()).abs() < 1e-9);
        }
    }

    #[test]
    fn filters_have_their_textbook_values() {
        assert!((resonant_lowpass(0.0, 10.0, 0.3) - Complex64::from(1.0)).norm() < 1e-15);
        // At f0 the gain is 1/(2 zeta) with -90 degrees of phase.
        assert!((resonant_lowpass(10.0, 10.0, 0.25) - Complex64::new(0.0, -2.0)).norm() < 1e-12);
        assert!((first_order_lowpass(5.0, 5.0).norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
    }
}
