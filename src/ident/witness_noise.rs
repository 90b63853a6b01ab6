//! The gyro's own noise in the angle-noise model: a first-order estimate of the gain bias it
//! causes, put into the gyro's `K` standard deviations and said when it matters.
//!
//! With a gyro block the observer colours its angle-noise model by what the gyro's outputs do
//! not explain (`stand::colour`). That part also holds the gyro's own noise, seen in angle units;
//! in one run the two noises cannot be told apart. The observer takes out the gyro's level at the
//! unexplained part's minimum in rate units; what it leaves (for one, a minimum over noisy per-bin
//! estimates lies below the level) is taken for angle noise: the observer then shrinks its input
//! estimate by the gyro's noise-to-signal ratio in each bin, `1 / SNR_k`, and the gain fitted
//! there reads high by that much. The structural fit weighs a bin by its output's signal-to-noise
//! ratio, so over the band the gain of output `i` reads high by about
//!
//! `b_i = n / sum_k SNR_ik`,  `SNR_ik = gamma2_ik / (1 - gamma2_ik)`,
//!
//! with `gamma2_ik` the multiple coherence of output `i` with the inputs in band bin `k` and `n`
//! the band's bins: the inverse of the band's mean signal-to-noise ratio, if the whole residual
//! were the gyro's own noise. On a real recording it is not: an optical reference's noise and
//! what the model misses fill the residual (the slow real run: a residual of 6e-5 (rad/s)^2/Hz in
//! band against a gyro floor of 4e-8, flat from 60 to 120 Hz: 1500 times). So each bin's share
//! is capped by the gyro's white floor `S_g,i`, its output's median level between 0.70 and 0.95
//! of Nyquist (where the motion has no power):
//!
//! `b_i = sum_k min(1, S_g,i / S_psi,ik) / sum_k SNR_ik`,  `S_psi,ik = (1 - gamma2_ik) S_xx,ik`.
//!
//! Since 30 Nov the observer takes the gyro's white floor, as the witness's fit sees it, out of
//! the unexplained part itself (`stand::witness_floor`), so what this estimate stands for is
//! mostly gone where the gyro's noise is white up to 0.7 of Nyquist; it is kept (deviations wider,
//! not narrower) until it is measured again with that. The measurements below are from before.
//!
//! It is a first-order estimate, not a bound. Measured: on an independent simulator's weak
//! motions (0.02 degrees, white gyro noise near the motion) estimates of 0.1-1.2 % beside gain
//! errors of 0.05-1.4 % (1 to 1.9 times the estimate on the noisiest axes) that the fit's own
//! standard deviations had called up to 5.4 sigma; on `simulate`'s runs with white gyro noise of
//! a third of the signal added, errors of 1.0-3.3 % for estimates near 1 % (1 to 3 times;
//! `tests/identify_accuracy.rs`). On the independent simulator's other runs the estimate is below
//! 3e-4. On the real recordings about 1e-6 (broad07) and 4e-6 (broad11), with scipy from the
//! files, and 1.4e-3 on broad25 from the program (its taps are in the gyro, not in the
//! reference). A gyro whose own filter cuts its noise below 0.7 of Nyquist gets too small a
//! floor, and so too small an estimate.
//!
//! What is done, in the identification of a gyro block whose spectra say so
//! ([`super::spectra::BlockSpectra::gyro_witnessed`]), after the stretches' widening and before
//! the self-check (whose `imprecise_gain` so judges the widened deviations): each element `K_ij`
//! gets `b_j |K_ij|` added in quadrature to its standard deviation (column `j`: the input axis
//! whose estimate was shrunk; for a calibrated block output `j` measures it), and an estimate
//! above [`WITNESS_BIAS_SAID`] is said
//! ([`IdentWarning::WitnessNoiseBias`]). The delay is untouched: the observer's gain is
//! zero-phase. The accelerometer's inputs come from the same observer, but its gains are set by
//! the angles' tilt of gravity and the lever arm, not one axis each; it is not widened here, but
//! says so beside the gyro's warning ([`IdentWarning::WitnessNoiseShared`], added in
//! [`super::session`]: a drifting gyro bias, whose noise the white floor does not see, put an
//! accelerometer's gain 2.6-8 % off, 8-16 of its deviations, on simulated runs of 1 Dec). An
//! extended model's refitted gains (accepted effects) keep the estimate in their deviations
//! (`model::BlockModel::set_effects`).
//!
//! Contracts: a bin with a NaN coherence or level is skipped; a band without bins gives no estimate
//! (nothing is widened or said). A coherence of exactly 1 in any bin is an infinite ratio, so the
//! channel's estimate is 0 (an output with no residual there: no noise of the gyro's to take for
//! angle noise). A grid without bins between 0.70 and 0.95 of Nyquist (a segment under 8 samples)
//! has no floor: every bin's whole residual counts, the conservative side.

use super::spectra::BlockSpectra;
use super::structural::StructuralFit;
use super::warnings::IdentWarning;

/// The largest estimate that is applied silently: a tenth of a percent, a certification's usual
/// scale-factor requirement.
pub const WITNESS_BIAS_SAID: f64 = 1e-3;

/// `b_i` per output channel (module docs) over the `band` bins of `spectra`, with the multiple
/// `coherence` per bin; 0 where nothing can be said.
#[must_use]
pub fn bias_estimate(spectra: &BlockSpectra, coherence: &[[f64; 3]], band: &[usize]) -> [f64; 3] {
    let nyquist = 0.5 * spectra.sample_rate_hz;
    std::array::from_fn(|i| {
        let output = |k: usize| spectra.s_xx.get(k).map_or(f64::NAN, |s| s[(i, i)].re);
        let mut top: Vec<f64> = (0..spectra.frequency_hz.len())
            .filter(|&k| (0.70 * nyquist..=0.95 * nyquist).contains(&spectra.frequency_hz[k]))
            .map(output)
            .filter(|v| v.is_finite())
            .collect();
        top.sort_by(f64::total_cmp);
        let floor = top.get(top.len() / 2).copied().unwrap_or(f64::INFINITY);
        let (mut share, mut snr) = (0.0, 0.0);
        for &k in band {
            let Some(c) = coherence.get(k) else { continue };
            let (g, level) = (c[i].clamp(0.0, 1.0), output(k));
            if !(g.is_finite() && level.is_finite()) {
                continue;
            }
            let residual = (1.0 - g) * level;
            share += (floor / residual).min(1.0);
            snr += g / (1.0 - g);
        }
        let b = share / snr;
        if b.is_finite() && b > 0.0 { b } else { 0.0 }
    })
}

/// The standard deviation `std` of a gain `k` of input column `j` with that column's `estimate`
/// in quadrature: also what an extended model's deviations get (`model::BlockModel::set_effects`).
#[must_use]
pub fn widened_std(std: f64, estimate: f64, k: f64) -> f64 {
    std.hypot(estimate * k.abs())
}

/// Widens the gyro fit's `K` deviations by `estimate` (module docs) and returns the warning when the
/// largest estimate exceeds [`WITNESS_BIAS_SAID`].
pub fn widen_for_witness_noise(fit: &mut StructuralFit, estimate: [f64; 3]) -> Option<IdentWarning> {
    for i in 0..3 {
        for j in 0..3 {
            fit.set_k_std(i, j, widened_std(fit.k_std[i][j], estimate[j], fit.k[i][j]));
        }
    }
    let (axis, &largest) = estimate.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    (largest > WITNESS_BIAS_SAID).then_some(IdentWarning::WitnessNoiseBias {
        estimate: largest,
        axis,
        estimates: estimate,
    })
}

/// Spectra and fits for the tests here and in [`super::left_out_noise`].
#[cfg(test)]
pub(super) mod tests_support {
    use super::*;
    use nalgebra::Matrix3;
    use num_complex::Complex64;

    /// Spectra on a 0..100 Hz grid (fs 200 Hz, 101 bins) with output level `band_level` below
    /// 50 Hz and `top_level` above.
    pub fn spectra(band_level: f64, top_level: f64) -> BlockSpectra {
        let frequency_hz: Vec<f64> = (0..=100).map(f64::from).collect();
        let s_xx = frequency_hz
            .iter()
            .map(|&f| {
                Matrix3::from_diagonal_element(Complex64::from(if f < 50.0 { band_level } else { top_level }))
            })
            .collect();
        BlockSpectra {
            aligned_samples: 0,
            frequency_hz,
            s_uu: Vec::new(),
            s_xu: Vec::new(),
            s_xx,
            n_averages: 20,
            equivalent_averages: 20.0,
            stretches: Vec::new(),
            finer_stretches: None,
            stationarity_cache: super::super::stretches::StationarityCache::default(),
            held_out_cache: super::super::holdout::HeldOutCache::default(),
            usable_band_cache: super::super::band_cache::BandCache::default(),
            bin_correlation: 1.0,
            centroid_hz: Vec::new(),
            centroid_offset_hz: Vec::new(),
            gyro_witnessed: true,
            left_out_noise: None,
            sample_rate_hz: 200.0,
            fft_len: 200,
            segment_len: 200,
        }
    }

    /// An order-0 fit of gain `k`, every element's standard deviation `std`.
    pub fn fit(k: [[f64; 3]; 3], std: f64) -> StructuralFit {
        StructuralFit {
            order: 0,
            k,
            k_std: [[std; 3]; 3],
            tau_s: 0.004,
            tau_std_s: 1e-5,
            denominator: Vec::new(),
            denominator_std: Vec::new(),
            numerator: vec![k],
            poles: Vec::new(),
            chi2: 100.0,
            dof: 100,
            stable: true,
            criterion: crate::ident::structural::InformationCriterion::default(),
            candidates: Vec::new(),
            scale_factor_error_ppm: [0.0; 3],
            scale_factor_error_std_ppm: [std * 1e6; 3],
            misalignment_mrad: [[0.0; 3]; 3],
            misalignment_std_mrad: [[std * 1e3; 3]; 3],
            even_gain: None,
            zeros_lag_s: None,
            fitted: crate::ident::structural::FittedOrders::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tests_support::{fit as order0_fit, spectra};
    use super::*;

    /// The widening in quadrature per column, the static figures alike, and the warning for the
    /// largest estimate only above 1e-3.
    #[test]
    fn the_widening_is_per_column_in_quadrature_and_said_above_a_tenth_of_a_percent() {
        let mut fit = order0_fit([[1.0, 0.02, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]], 1e-3);
        let said = widen_for_witness_noise(&mut fit, [0.0, 0.003, 0.004]);
        assert!((fit.k_std[0][0] - 1e-3).abs() < 1e-15, "{:?}", fit.k_std);
        assert!((fit.k_std[0][1] - 1e-3_f64.hypot(0.003 * 0.02)).abs() < 1e-15);
        assert!((fit.k_std[2][2] - 1e-3_f64.hypot(0.008)).abs() < 1e-15);
        assert!((fit.scale_factor_error_std_ppm[2] - fit.k_std[2][2] * 1e6).abs() < 1e-9);
        assert!((fit.misalignment_std_mrad[0][1] - fit.k_std[0][1] * 1e3).abs() < 1e-12);
        match said {
            Some(IdentWarning::WitnessNoiseBias { estimate, axis, .. }) => {
                assert!((estimate - 0.004).abs() < 1e-15 && axis == 2, "{estimate} {axis}");
            }
            other => panic!("{other:?}"),
        }
        let mut quiet = order0_fit([[1.0, 0.0, 0.0]; 3], 1e-3);
        assert!(widen_for_witness_noise(&mut quiet, [0.001, 0.0009, 0.0]).is_none());
    }

    /// A NaN in one bin is skipped, not the whole channel.
    #[test]
    fn a_nan_bin_is_skipped() {
        let mut coherence = vec![[0.99; 3]; 101];
        coherence[4] = [f64::NAN; 3];
        let b = bias_estimate(&spectra(1.0, 1.0), &coherence, &[2, 3, 4, 5]);
        assert!((b[0] - 0.01 / 0.99).abs() < 1e-15, "{b:?}");
    }

    /// Closed forms. The whole residual the gyro's (its floor at the residual's level or above):
    /// a constant coherence `g` gives `(1 - g) / g`. A floor a tenth of the residual: a tenth of
    /// that. A coherence of 1, a NaN or an empty band: no estimate.
    #[test]
    fn the_estimate_is_the_gyro_s_share_of_the_inverse_mean_signal_to_noise_ratio() {
        let band: Vec<usize> = (2..8).collect();
        let coherence = vec![[0.99, 0.5, 1.0]; 101];
        // Residual in band: (1 - g) * 1; floor 1: the whole residual.
        let b = bias_estimate(&spectra(1.0, 1.0), &coherence, &band);
        assert!((b[0] - 0.01 / 0.99).abs() < 1e-15, "{b:?}");
        assert!((b[1] - 1.0).abs() < 1e-15, "{b:?}");
        assert!(b[2].abs() < f64::MIN_POSITIVE, "{b:?}");
        // Floor 0.001 against residuals 0.01 (g 0.99) and 0.5 (g 0.5).
        let b = bias_estimate(&spectra(1.0, 0.001), &coherence, &band);
        assert!((b[0] - 0.1 * 0.01 / 0.99).abs() < 1e-15, "{b:?}");
        assert!((b[1] - 0.002).abs() < 1e-15, "{b:?}");
        // Two bins at SNR 1 and 99, the whole residual the gyro's: the fit's weights give
        // 2 / 100, not the plain mean of the noise-to-signal ratios (0.505).
        let mut two = vec![[0.5; 3]; 101];
        two[1] = [0.99; 3];
        let b = bias_estimate(&spectra(1.0, 1.0), &two, &[0, 1]);
        assert!((b[0] - 0.02).abs() < 1e-12, "{b:?}");
        let none = |b: [f64; 3]| b.iter().all(|v| v.abs() < f64::MIN_POSITIVE);
        assert!(none(bias_estimate(&spectra(1.0, 1.0), &coherence, &[])));
        assert!(none(bias_estimate(
            &spectra(1.0, 1.0),
            &[[f64::NAN; 3]; 101],
            &[3]
        )));
    }
}
