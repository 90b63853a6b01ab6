//! Spectral estimation and factorisation: Welch estimates of one-sided cross-spectral density
//! matrices (this page), and on the two-sided FFT grid the matrix spectral factorisation
//! ([`factor`], Wilson), the causal projection `[.]_+` ([`causal`]), one-/two-sided conversion
//! ([`grid`]), interpolation onto a finer grid ([`refine`]) and the scalar cepstral reference ([`cepstral`]); each states its conventions.
//!
//! # Conventions
//! - **Estimate.** The run is cut into segments of `N = segment_len` samples starting at sample 0
//!   and stepping by `N - noverlap`, with `noverlap = round(overlap * N)` (ties away from zero); a
//!   trailing partial segment is dropped (as scipy does). Each segment of each channel is
//!   detrended ([`Detrend`]), then multiplied by the periodic window `w` ([`Window`]), then
//!   transformed by one unnormalised real FFT: `X_i(f_k) = sum_t w_t x_i(t) e^(-2 pi i k t / N)`.
//! - **Scaling: one-sided density, units^2/Hz.** With `fs` the sample rate and `K` the number of
//!   segments,
//!   `S_ij(f_k) = c_k / (fs * sum_t w_t^2) * (1/K) sum_segments X_i(f_k) conj(X_j(f_k))`,
//!   with `c_k = 2` for `0 < f_k < fs/2` and `c_k = 1` at DC and at Nyquist. So `S = E[X X^H]`
//!   is Hermitian positive semi-definite per bin, `sum_k S_ii(f_k) * df` is the (windowed)
//!   variance of channel `i`, and a linear system `x = W u` gives `S_xu = W S_uu`.
//! - **Relation to scipy.** `S_ij` equals `scipy.signal.csd(x_j, x_i, fs, window, nperseg=N,
//!   noverlap, detrend, scaling='density')`: scipy's `csd(a, b)` is `conj(A) B`, the transpose of
//!   ours. `tests/welch_scipy.rs` checks this against stored scipy output.
//! - **Frequency ordering.** Bins `f_k = k fs / N`, `k = 0..=N/2` (`N` is even): ascending, DC
//!   first, Nyquist last; `N/2 + 1` bins spaced `df = fs / N`.
//! - **Layout.** [`SpectralMatrix`] stores `[frequency][row][col]`, row-major per bin.
//! - **NaN, empty input, units.** Input is refused, never propagated: no channels, channels of
//!   unequal length, fewer samples than one segment, bad settings, a non-finite or non-positive
//!   sample rate, or any NaN/inf sample give a [`SpectralError`] naming the numbers involved. Valid
//!   input gives finite output. Signals carry any unit `U`; `S` is in `U^2/Hz`, frequencies in Hz.
//! - **Determinism.** Results depend on the inputs and settings only, not on the rayon thread
//!   count (see [`welch`]).
//!
//! # Example
//! ```
//! use imu_attest::spectral::{WelchPlanner, WelchSettings, Window};
//! let x: Vec<f64> = (0..1024).map(|t| (0.3 * t as f64).sin()).collect();
//! let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
//! let settings = WelchSettings { segment_len: 256, window: Window::Hann, ..WelchSettings::default() };
//! let mut planner = WelchPlanner::new();
//! let s = planner.welch_matrix(&[&x, &y], 100.0, &settings)?;
//! assert_eq!((s.n_bins(), s.n_channels, s.n_averages), (129, 2, 7));
//! assert!(s.coherence(0, 1).iter().all(|&c| c > 0.999));
//! # Ok::<(), imu_attest::spectral::SpectralError>(())
//! ```

pub mod bands;
pub mod causal;
pub mod centroid;
pub mod cepstral;
mod detrend;
mod error;
pub mod factor;
pub mod grid;
mod matrix;
mod offset;
mod pad;
pub mod refine;
mod settings;
pub mod welch;
mod window;

pub use detrend::Detrend;
pub use error::SpectralError;
pub use matrix::SpectralMatrix;
pub use settings::{DEFAULT_SEGMENT_LEN, MIN_SEGMENT_LEN, WelchSettings};
pub use welch::{WelchPlanner, welch_matrix};
pub use window::Window;
