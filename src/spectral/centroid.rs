//! The frequency at which each Welch bin's input power actually lies: the power-weighted centroid
//! of the segments' content per bin (the reassignment operator of time-frequency analysis).
//!
//! A bin of a Welch estimate does not hold the bin's centre frequency `f_k` alone: its window's
//! main lobe gathers power from `f_k +- 2 df` (Hann). For a broadband input the power is spread
//! evenly there and `W = S_xu S_uu^-1` at the bin is the model at `f_k`, to first order. For an
//! input with strong lines (a stand's sine programme) a bin beside a line holds the line's power:
//! its `W` is the model at the line's frequency, not at `f_k`. A model evaluated at `f_k` then
//! misses by `dH/df (f_line - f_k)`, which for a delay `tau` is a phase of
//! `2 pi (f_line - f_k) tau`: at a strong line, hundreds of its standard deviations (a chi2/dof of
//! 3-25 on exact runs of an independent simulator with 2-5 degree sines) and a delay biased by up
//! to 0.17 ms. Evaluating the model at the centroid removes both when the inputs' lines share a
//! place in the bin; lines of different frequencies on different inputs need the offset matrix
//! (below).
//!
//! With `h` the window and `Dh` its time derivative (s^-1), per segment and input channel
//! `X_h(k)` and `X_Dh(k)` are the transforms of `h x` and `Dh x`; the centroid is
//!
//! `f_c(k) = f_k - (1 / 2 pi) Im(sum X_Dh conj(X_h)) / sum |X_h|^2`,
//!
//! summed over the segments and the channels (one centroid per bin for the three inputs). It is
//! exact for a line (any offset inside the main lobe) and averages to `f_k` for a flat spectrum.
//! It is held within [`MAIN_LOBE_BINS`] bins of `f_k`, at or above `f_k / 2` (a drift's image from
//! the negative frequencies put a bin at 0.12 Hz at -0.02 Hz) and at or below Nyquist.
//! `Dh` is the window's circular central difference times `fs`, which is its derivative only for a
//! window closing to 0 at its ends (Hann, Blackman-Harris); for the others (rectangular, Hamming)
//! the bin centres are kept.
//!
//! # Offset matrix
//! One centroid per bin serves all three inputs. When the inputs' lines lie at different places
//! in a bin (a stand's sines on each axis), each column of `H1 = S_xu S^-1` is the response where
//! its own input's power lies, not at the common centroid. With `S = sum X_h X_h^H` and
//! `E = sum (j X_Dh) X_h^H` over the segments (rad/s: `j X_Dh = (w - w_k) X_h` for a line at `w`),
//! a system `x = H u` smooth over the main lobe gives, to first order,
//! `S_xu = H(f_c) S + H'(f_c) (E / 2 pi - (f_c - f_k) S)`, so
//!
//! `H1 = H(f_c) + H'(f_c) G`,  `G = E S^-1 / 2 pi - (f_c - f_k) I`  (Hz, `H' = dH/df`),
//!
//! exact for lines at any offset inside the main lobe, `G = 0` when every input's power shares
//! the centroid, and `diag(f_j - f_c)` for uncorrelated lines at `f_j`
//! ([`WelchPlanner::input_centroids`]). `G` is formed direction by direction of `S`'s eigenvectors:
//! a direction where `S` is near singular, or whose own power lies past the main lobe (its
//! Rayleigh quotient `v^H G v` from `f_c`), is left out (compared at `f_c`) and the others kept
//! ([`super::offset`]). `G` is zero where `f_c` was held (a drift's image from the negative
//! frequencies) and at DC and Nyquist.
//!
//! Grid and units: the native grid of the segment (`k = 0..=N/2`, `f_k = k fs / N`, ascending), Hz.
//! Segments as the Welch estimate cuts them (start 0, step `N - noverlap`), detrended alike. A bin
//! with no power, or a non-finite centroid, keeps `f_k`. Empty or NaN input is refused as the
//! Welch estimate refuses it.

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::offset::offset;
use super::welch::WelchPlanner;
use super::{SpectralError, WelchSettings};

/// Half the widest main lobe of the windows offered (Hann, Hamming: 2 bins; Blackman-Harris: 4),
/// in bins: a centroid farther from its bin than [`MAIN_LOBE_BINS`] bins is held there. The
/// centroid is also held at or above half its bin's frequency: near 0 Hz a bin's main lobe
/// reaches the negative frequencies, whose image of a slow drift would put it below 0 Hz.
pub(super) const MAIN_LOBE_BINS: f64 = 4.0;

impl WelchPlanner {
    /// The three inputs' centroids and offset matrices (module docs, "Offset matrix"), Hz.
    ///
    /// # Errors
    /// As [`WelchPlanner::welch_matrix`] on the same input.
    pub fn input_centroids(
        &mut self,
        inputs: [&[f64]; 3],
        sample_rate_hz: f64,
        settings: &WelchSettings,
    ) -> Result<InputCentroids, SpectralError> {
        let parts = self.input_moments(inputs, sample_rate_hz, settings, 1)?;
        Ok(match parts {
            Some(parts) => parts[0].centroids(),
            None => InputCentroids::centres(sample_rate_hz, settings.segment_len),
        })
    }

    /// The three inputs' moments over `parts` consecutive groups of segments (group `p` holds
    /// segments `p n / parts .. (p + 1) n / parts`, as `welch_matrix_parts` groups them); their
    /// sum is the whole record's. `None` for a window open at its ends (no centroid then).
    ///
    /// # Errors
    /// As [`WelchPlanner::welch_matrix`] on the same input; `parts` of 0 or above the segment
    /// count is [`SpectralError::BadParts`].
    pub fn input_moments(
        &mut self,
        inputs: [&[f64]; 3],
        sample_rate_hz: f64,
        settings: &WelchSettings,
        parts: usize,
    ) -> Result<Option<Vec<InputMoments>>, SpectralError> {
        let channels = inputs;
        super::welch::check_input(&channels, sample_rate_hz, settings)?;
        let n_segments = settings.n_segments(channels[0].len());
        if parts == 0 || parts > n_segments.max(1) {
            return Err(SpectralError::BadParts { parts, n_segments });
        }
        let n = settings.segment_len;
        let window = self.window(settings.window, n);
        // The circular difference is the window's derivative only for a window that closes to 0
        // at its ends (Hann, Blackman-Harris); Hamming's and the rectangle's jump there.
        let peak = window.iter().copied().fold(0.0, f64::max);
        if window.first().is_none_or(|w0| w0.abs() > 1e-3 * peak) {
            return Ok(None);
        }
        let derivative: Vec<f64> = (0..n)
            .map(|i| 0.5 * (window[(i + 1) % n] - window[(i + n - 1) % n]) * sample_rate_hz)
            .collect();
        let fft = self.real_fft(n);
        let bins = n / 2 + 1;
        let (mut plain, mut weighted) = (fft.make_input_vec(), fft.make_input_vec());
        let mut x_h = [
            fft.make_output_vec(),
            fft.make_output_vec(),
            fft.make_output_vec(),
        ];
        let mut x_dh = x_h.clone();
        let mut scratch = fft.make_scratch_vec();
        let mut groups: Vec<InputMoments> = (0..parts)
            .map(|_| InputMoments {
                power: vec![Matrix3::zeros(); bins],
                shifted: vec![Matrix3::zeros(); bins],
                sample_rate_hz,
                segment_len: n,
            })
            .collect();
        let mut segment = vec![0.0; n];
        for s in 0..n_segments {
            let start = s * settings.step();
            for (a, channel) in channels.iter().enumerate() {
                segment.copy_from_slice(&channel[start..start + n]);
                settings.detrend.apply(&mut segment);
                for i in 0..n {
                    plain[i] = segment[i] * window[i];
                    weighted[i] = segment[i] * derivative[i];
                }
                fft.process_with_scratch(&mut plain, &mut x_h[a], &mut scratch)
                    .and_then(|()| fft.process_with_scratch(&mut weighted, &mut x_dh[a], &mut scratch))
                    .map_err(|e| SpectralError::Fft(e.to_string()))?;
            }
            // Segment `s` is in group `p` when `p n / parts <= s < (p + 1) n / parts`.
            let group = &mut groups[((s + 1) * parts - 1) / n_segments];
            for k in 0..bins {
                for a in 0..3 {
                    let shift = Complex64::i() * x_dh[a][k];
                    for b in 0..3 {
                        let conj = x_h[b][k].conj();
                        group.power[k][(a, b)] += x_h[a][k] * conj;
                        group.shifted[k][(a, b)] += shift * conj;
                    }
                }
            }
        }
        Ok(Some(groups))
    }
}

/// The three inputs' power centroids and offset matrices ([`WelchPlanner::input_centroids`]).
#[derive(Clone, Debug, PartialEq)]
pub struct InputCentroids {
    /// Per native bin, the inputs' power centroid `f_c`, Hz.
    pub hz: Vec<f64>,
    /// Per native bin, `G = E S^-1 / 2 pi - (f_c - f_k) I`, Hz (module docs): zero in the
    /// directions where the first-order relation is not trusted, and at the bins where it is not
    /// at all.
    pub offset_hz: Vec<Matrix3<Complex64>>,
}

impl InputCentroids {
    /// The bin centres with no offsets (a window without a derivative).
    #[must_use]
    pub fn centres(sample_rate_hz: f64, segment_len: usize) -> Self {
        let df = sample_rate_hz / segment_len as f64;
        let hz: Vec<f64> = (0..=segment_len / 2).map(|k| k as f64 * df).collect();
        Self {
            offset_hz: vec![Matrix3::zeros(); hz.len()],
            hz,
        }
    }
}

/// The three inputs' moments over a group of segments, per native bin: `S = sum X_h X_h^H` and
/// `E = sum (j X_Dh) X_h^H` (module docs, "Offset matrix"). Groups add up.
#[derive(Clone, Debug, PartialEq)]
pub struct InputMoments {
    power: Vec<Matrix3<Complex64>>,
    shifted: Vec<Matrix3<Complex64>>,
    sample_rate_hz: f64,
    segment_len: usize,
}

impl InputMoments {
    /// The sum of `parts` (consecutive groups of one record); `None` for no part.
    #[must_use]
    pub fn sum(parts: &[&Self]) -> Option<Self> {
        let (head, rest) = parts.split_first()?;
        let mut total = (*head).clone();
        for p in rest {
            for (t, v) in total.power.iter_mut().zip(&p.power) {
                *t += v;
            }
            for (t, v) in total.shifted.iter_mut().zip(&p.shifted) {
                *t += v;
            }
        }
        Some(total)
    }

    /// The centroids and offset matrices these moments give (module docs).
    #[must_use]
    pub fn centroids(&self) -> InputCentroids {
        let (hz, offset_hz) = (0..=self.segment_len / 2)
            .filter_map(|k| self.centroid_at(k))
            .unzip();
        InputCentroids { hz, offset_hz }
    }

    /// [`Self::centroids`]' entry for native bin `k` alone (a band's bins need no other); `None`
    /// past Nyquist.
    #[must_use]
    pub fn centroid_at(&self, k: usize) -> Option<(f64, Matrix3<Complex64>)> {
        let n = self.segment_len;
        if k > n / 2 {
            return None;
        }
        let (fc, held) = self.bin_centroid(k);
        // DC and Nyquist are their own images (`E S^-1` is not a shift there). Near 0 Hz the main
        // lobe also holds the negative frequencies' image of a line, which a rational model with
        // real coefficients continues analytically (`W(-f) = conj W(f)`), so the first order
        // holds there too: measured, zeroing the first four bins left misfits of 27-286 times the
        // noise at 0.24-0.73 Hz on an independent simulator's sines.
        // Where `f_c` was held (the bins near 0 Hz, whose image from the negative frequencies is
        // no first-order shift), no offsets either.
        if k == 0 || k == n / 2 || held {
            return Some((fc, Matrix3::zeros()));
        }
        let df = self.sample_rate_hz / n as f64;
        Some((
            fc,
            offset(&self.power[k], &self.shifted[k], fc, k as f64 * df, df),
        ))
    }
    /// The power centroid of native bin `k` from the moments' traces, held within
    /// [`MAIN_LOBE_BINS`] bins of `f_k`, at or above `f_k / 2` and at or below Nyquist (module docs;
    /// `f_k` for a bin without power or a non-finite centroid), and whether it was held.
    fn bin_centroid(&self, k: usize) -> (f64, bool) {
        let df = self.sample_rate_hz / self.segment_len as f64;
        let f = k as f64 * df;
        let den = self.power[k].trace().re;
        let c_hz = f + self.shifted[k].trace().re / den / (2.0 * std::f64::consts::PI);
        if !(den > 0.0 && c_hz.is_finite()) {
            return (f, true);
        }
        let held = c_hz.clamp(
            (f - MAIN_LOBE_BINS * df).max(0.5 * f),
            (f + MAIN_LOBE_BINS * df)
                .min(0.5 * self.sample_rate_hz)
                .max(0.5 * f),
        );
        (held, (held - c_hz).abs() > 1e-9 * df)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::Window;

    fn settings(n: usize, window: Window) -> WelchSettings {
        WelchSettings {
            segment_len: n,
            window,
            ..WelchSettings::default()
        }
    }

    /// A line between two bins: every bin of its main lobe is placed at the line (closed form).
    #[test]
    fn a_line_is_found_at_its_frequency_from_every_bin_of_its_main_lobe() {
        let (rate, n) = (500.0, 1024);
        let line = 10.0 * rate / n as f64 + 0.37 * rate / n as f64;
        let x: Vec<f64> = (0..20 * n)
            .map(|t| (2.0 * std::f64::consts::PI * line * t as f64 / rate + 0.4).sin())
            .collect();
        let c = WelchPlanner::new()
            .input_centroids([&x, &x, &x], rate, &settings(n, Window::Hann))
            .unwrap()
            .hz;
        for k in 9..=12 {
            assert!((c[k] - line).abs() < 1e-4, "bin {k}: {} against {line}", c[k]);
        }
    }

    /// Three inputs with lines at different places in one bin, through a delay and a gain: the
    /// `H1` estimate is `H(f_c) + H'(f_c) G` (module docs, "Offset matrix") to its second order,
    /// while `H(f_c)` alone misses by the first; uncorrelated lines give `G = diag(f_j - f_c)`.
    #[test]
    fn the_offset_matrix_places_each_column_of_h1_where_its_input_lies() {
        let (rate, n) = (500.0, 1024);
        let df = rate / n as f64;
        let lines = [10.1 * df, 10.45 * df, 10.8 * df];
        let (tau, k) = (
            0.004,
            [[1.0, 0.02, -0.01], [0.015, 0.98, 0.03], [-0.02, 0.01, 1.03]],
        );
        let len = 64 * n;
        let t = |i: usize| i as f64 / rate;
        let two_pi = 2.0 * std::f64::consts::PI;
        let phase = [0.3, 1.9, 4.1];
        let u: Vec<Vec<f64>> = (0..3)
            .map(|j| {
                (0..len)
                    .map(|i| (two_pi * lines[j] * t(i) + phase[j]).sin())
                    .collect()
            })
            .collect();
        let x: Vec<Vec<f64>> = (0..3)
            .map(|r| {
                (0..len)
                    .map(|i| {
                        (0..3)
                            .map(|j| k[r][j] * (two_pi * lines[j] * (t(i) - tau) + phase[j]).sin())
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let settings = settings(n, Window::Hann);
        let mut planner = WelchPlanner::new();
        let c = planner
            .input_centroids([&u[0], &u[1], &u[2]], rate, &settings)
            .unwrap();
        let channels: Vec<&[f64]> = u.iter().chain(&x).map(Vec::as_slice).collect();
        let s = planner.welch_matrix(&channels, rate, &settings).unwrap();
        let model = |f: f64| Matrix3::from_fn(|r, j| Complex64::from_polar(k[r][j], -two_pi * f * tau));
        let slope = |f: f64| model(f) * Complex64::new(0.0, -two_pi * tau);
        for bin in 9..=12 {
            let at = |r: usize, c: usize| s.get(bin, r, c).unwrap();
            let s_uu = Matrix3::from_fn(&at);
            let s_xu = Matrix3::from_fn(|a, b| at(a + 3, b));
            let h1 = s_xu * s_uu.try_inverse().unwrap();
            let (fc, g) = (c.hz[bin], c.offset_hz[bin]);
            let seen = model(fc) + slope(fc) * g;
            // Left: the second order, `(2 pi d tau)^2 / 2` for offsets `d` up to a bin.
            let (left, first) = ((h1 - seen).norm(), (h1 - model(fc)).norm());
            assert!(
                left < 1e-4 && left < 0.01 * first,
                "bin {bin}: {left:e} of {first:e}"
            );
            assert!(first > 1e-3, "bin {bin}: the columns do lie apart");
            for a in 0..3 {
                for b in 0..3 {
                    let want = if a == b { lines[a] - fc } else { 0.0 };
                    assert!(
                        (g[(a, b)] - want).norm() < 1e-3 * df,
                        "bin {bin} G[{a}][{b}] = {}",
                        g[(a, b)]
                    );
                }
            }
        }
    }

    /// A stepped programme (one line on each axis in the first half, other lines in the second):
    /// each half's moments place its own lines, and the halves add up to the record's.
    #[test]
    fn each_group_of_segments_places_its_own_lines_and_the_groups_add_up() {
        let (rate, n) = (500.0, 512);
        let df = rate / n as f64;
        let halves = [[20.2, 20.5, 20.8], [20.9, 20.1, 20.4]].map(|h| h.map(|b| b * df));
        let len = 16 * n;
        let u: Vec<Vec<f64>> = (0..3)
            .map(|j| {
                (0..len)
                    .map(|i| {
                        let f = halves[usize::from(i >= len / 2)][j];
                        (2.0 * std::f64::consts::PI * f * i as f64 / rate + j as f64).sin()
                    })
                    .collect()
            })
            .collect();
        let settings = WelchSettings {
            overlap: 0.0,
            ..settings(n, Window::Hann)
        };
        let mut planner = WelchPlanner::new();
        let parts = planner
            .input_moments([&u[0], &u[1], &u[2]], rate, &settings, 2)
            .unwrap()
            .unwrap();
        for (half, lines) in parts.iter().zip(&halves) {
            let c = half.centroids();
            let g = c.offset_hz[21];
            for (j, line) in lines.iter().enumerate() {
                let at = c.hz[21] + g[(j, j)].re;
                assert!((at - line).abs() < 1e-3 * df, "{at} against {line}");
            }
        }
        let whole = planner
            .input_centroids([&u[0], &u[1], &u[2]], rate, &settings)
            .unwrap();
        let summed = InputMoments::sum(&[&parts[0], &parts[1]]).unwrap().centroids();
        for k in 0..whole.hz.len() {
            assert!((whole.hz[k] - summed.hz[k]).abs() < 1e-9 * df, "bin {k}");
            assert!(
                (whole.offset_hz[k] - summed.offset_hz[k]).norm() < 1e-9 * df,
                "bin {k}"
            );
        }
    }

    /// Collinear inputs (one signal on all three axes): `S` has one direction, whose offset from
    /// the centroid (the line's) is none; the model is compared at the line.
    #[test]
    fn collinear_inputs_are_compared_at_their_line() {
        let (rate, n) = (500.0, 1024);
        let df = rate / n as f64;
        let line = 10.37 * df;
        let u: Vec<f64> = (0..16 * n)
            .map(|i| (2.0 * std::f64::consts::PI * line * i as f64 / rate).sin())
            .collect();
        let c = WelchPlanner::new()
            .input_centroids([&u, &u, &u], rate, &settings(n, Window::Hann))
            .unwrap();
        for k in 9..=12 {
            assert!((c.hz[k] - line).abs() < 1e-4, "bin {k}: {}", c.hz[k]);
            // The real sine's image at the negative frequency alone (2e-5 df).
            assert!(c.offset_hz[k].norm() < 1e-4 * df, "bin {k}: {}", c.offset_hz[k]);
        }
    }

    /// Two lines at different places in a bin on two inputs and their sum on the third (an
    /// accelerometer's specific forces near a plane): `S` is singular in one direction, and the
    /// other two keep their offsets, so `G S = E / 2 pi - (f_c - f_k) S` still holds (the whole
    /// matrix was zeroed before, leaving a misfit growing with the delay).
    #[test]
    fn a_singular_direction_leaves_the_others_their_offsets() {
        let (rate, n) = (500.0, 1024);
        let df = rate / n as f64;
        let lines = [10.15 * df, 10.7 * df];
        let wave = |f: f64, phase: f64| -> Vec<f64> {
            (0..16 * n)
                .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 / rate + phase).sin())
                .collect()
        };
        let (a, b) = (wave(lines[0], 0.3), wave(lines[1], 1.1));
        let sum: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
        let settings = settings(n, Window::Hann);
        let moments = WelchPlanner::new()
            .input_moments([&a, &b, &sum], rate, &settings, 1)
            .unwrap()
            .unwrap();
        let c = moments[0].centroids();
        for k in 9..=12 {
            let (s, e) = (moments[0].power[k], moments[0].shifted[k]);
            let want = e / Complex64::from(2.0 * std::f64::consts::PI)
                - s * Complex64::from(c.hz[k] - k as f64 * df);
            let got = c.offset_hz[k] * s;
            assert!(want.norm() > 1e-3 * df * s.norm(), "bin {k}: no offset to keep");
            // The singular direction (the third input less the other two) is left out.
            let null = nalgebra::Vector3::new(1.0, 1.0, -1.0).map(Complex64::from);
            let along = c.offset_hz[k] * null;
            assert!(along.norm() < 1e-6 * df, "bin {k}: {along}");
            assert!(
                (got - want).norm() < 1e-6 * want.norm(),
                "bin {k}: {:e} of {:e}",
                (got - want).norm(),
                want.norm()
            );
        }
    }

    /// White noise: the centroids scatter about the bin centres, unbiased (the mean offset over
    /// the bins is a small fraction of its scatter's standard error).
    #[test]
    fn white_noise_leaves_the_bin_centres_on_average() {
        let (rate, n) = (500.0, 256);
        let mut rng = crate::rng::Rng::new(9);
        let x: Vec<f64> = (0..400 * n).map(|_| rng.normal()).collect();
        let c = WelchPlanner::new()
            .input_centroids([&x, &x, &x], rate, &settings(n, Window::Hann))
            .unwrap()
            .hz;
        let df = rate / n as f64;
        let offsets: Vec<f64> = (5..n / 2 - 5).map(|k| (c[k] - k as f64 * df) / df).collect();
        let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
        let rms = (offsets.iter().map(|o| o * o).sum::<f64>() / offsets.len() as f64).sqrt();
        assert!(rms < 0.1, "scatter {rms} of a bin");
        assert!(
            mean.abs() < 3.0 * rms / (offsets.len() as f64).sqrt(),
            "mean {mean}, rms {rms}"
        );
    }

    /// A slow drift's power near 0 Hz reaches the first bins through the main lobe, its image from
    /// the negative frequencies too: the centroid stays at or above half the bin's frequency.
    #[test]
    fn near_zero_hertz_the_centroid_stays_positive() {
        let (rate, n) = (500.0, 1024);
        let x: Vec<f64> = (0..8 * n)
            .map(|t| {
                let s = f64::from(u32::try_from(t).unwrap()) / rate;
                1e-3 * s * s + 1e-6 * (2.0 * std::f64::consts::PI * 40.0 * s).sin()
            })
            .collect();
        let c = WelchPlanner::new()
            .input_centroids([&x, &x, &x], rate, &settings(n, Window::Hann))
            .unwrap()
            .hz;
        let df = rate / n as f64;
        for (k, f) in c.iter().enumerate().skip(1).take(8) {
            let centre = k as f64 * df;
            assert!(*f >= 0.5 * centre && *f <= centre + 4.0 * df, "bin {k}: {f}");
        }
    }

    /// Windows that do not close to 0 at their ends (rectangular, Hamming) have no derivative
    /// there: the bin centres are kept (a circular difference pushed Hamming's leakage bins
    /// away from the line, by 3 bins).
    #[test]
    fn windows_open_at_their_ends_keep_the_bin_centres() {
        let x: Vec<f64> = (0..4096_u32).map(|t| (0.3 * f64::from(t)).sin()).collect();
        for window in [Window::Rectangular, Window::Hamming] {
            let c = WelchPlanner::new()
                .input_centroids([&x, &x, &x], 100.0, &settings(256, window))
                .unwrap()
                .hz;
            for (k, f) in c.iter().enumerate() {
                assert!((f - k as f64 * 100.0 / 256.0).abs() < 1e-12, "{window:?} bin {k}");
            }
        }
        // Blackman-Harris closes to 0: its main lobe is placed at the line.
        let (rate, n) = (500.0, 1024);
        let line = 10.37 * rate / n as f64;
        let x: Vec<f64> = (0..20 * n)
            .map(|t| (2.0 * std::f64::consts::PI * line * t as f64 / rate).sin())
            .collect();
        let c = WelchPlanner::new()
            .input_centroids([&x, &x, &x], rate, &settings(n, Window::BlackmanHarris))
            .unwrap()
            .hz;
        assert!(
            (c[10] - line).abs() < 1e-3 && (c[11] - line).abs() < 1e-3,
            "{} {}",
            c[10],
            c[11]
        );
    }
}
