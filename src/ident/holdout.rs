//! Held-out validation of the order choice: the record's first half predicts its second, and the
//! second its first.
//!
//! The stretches of the stationarity check ([`super::stretches`]) are merged into two halves
//! (the first `M / 2` stretches and the rest, each an average weighted by its equivalent number
//! of averages), each half gets its own `H1` estimate and residual weights over the block's band
//! (native bins), and [`held_out_chi2`] fits every order to each and evaluates it on the other.
//! The structural fit then keeps an order above 0 only when it predicts the other half better
//! than every lower order (admissibility rule 7, [`super::structural::admissible`]).
//!
//! Why halves and not the stretches: a rational order needs the whole band's resolution and
//! enough averages per bin to be fitted at all; two halves are the most data each fit can have
//! while both stay disjoint. Why `H1` (whatever the settings' estimate): the halves are only
//! compared with each other, and `H1` needs no factorisation per half.
//!
//! A record too short to cut into stretches has no held-out figures (rule 7 is then not applied,
//! and the candidates carry no `held_out_chi2`). Units: s, Hz.

use std::sync::Arc;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::band::native_bins;
use super::spectra::BlockSpectra;
use super::stretches::{StretchSpectra, compared_at, h1_estimate};
use super::structural::{MAX_ORDER, ResponseEstimate, StructuralSettings, Weights, held_out_chi2};
use crate::spectral::centroid::InputMoments;

/// The held-out figures of a block over one band.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOut {
    /// The two halves' spans, s from the first sample.
    pub halves_s: [[f64; 2]; 2],
    /// Each order's held-out chi2 (index = order; `None` where not fitted to both halves).
    pub chi2: [Option<f64>; MAX_ORDER + 1],
}

/// The value of [`held_out`], cached in the spectra per band.
pub type HeldOutCache = super::band_cache::BandCache<HeldOut>;

/// [`held_out`], cached in `spectra` per band (a retune reuses it).
#[must_use]
pub fn cached_held_out(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Option<Arc<HeldOut>> {
    spectra
        .held_out_cache
        .get_or(band_hz, || held_out(spectra, band_hz))
}

/// The held-out figures over `band_hz`; `None` without stretches, when a half's `H1` estimate
/// cannot be formed (a singular `S_uu`), or when a half's fit is refused.
#[must_use]
pub fn held_out(spectra: &BlockSpectra, band_hz: [f64; 2]) -> Option<HeldOut> {
    let m = spectra.stretches.len();
    if m < 2 {
        return None;
    }
    let (first, second) = spectra.stretches.split_at(m / 2);
    let (lag, rate) = (spectra.aligned_samples, spectra.sample_rate_hz);
    let halves = [merged(first, lag, rate)?, merged(second, lag, rate)?];
    let native = native_bins(spectra, band_hz);
    let step = spectra.native_step();
    let centres: Vec<f64> = native.iter().map(|&k| spectra.frequency_hz[k]).collect();
    let [(w1, o1), (w2, o2)] = [
        h1_estimate(&halves[0], &native, step)?,
        h1_estimate(&halves[1], &native, step)?,
    ];
    // Each half compared where its own inputs' power lies.
    let [(f1, g1), (f2, g2)] = [
        compared_at(spectra, &halves[0], &native, &centres),
        compared_at(spectra, &halves[1], &native, &centres),
    ];
    let estimate = |frequency_hz, response, weights, offset_hz| ResponseEstimate {
        frequency_hz,
        response,
        weights: Weights::RowWeight(weights),
        offset_hz,
    };
    let chi2 = held_out_chi2(
        &estimate(&f1, &w1, &o1, g1.as_deref()),
        &estimate(&f2, &w2, &o2, g2.as_deref()),
        &StructuralSettings {
            aligned_s: spectra.aligned_s(),
            ..StructuralSettings::default()
        },
    )
    .ok()?;
    Some(HeldOut {
        halves_s: [halves[0].span_s, halves[1].span_s],
        chi2,
    })
}

/// Consecutive stretches as one: spectral matrices averaged with their equivalent numbers of
/// averages as weights, which add up. Outputs moved by `lag` samples before the estimate
/// (`super::alignment`) had each stretch's delay given back where that stretch is compared (its
/// inputs' centroid per bin, else the bin's centre; `super::spectra::block_spectra`): each is
/// turned to where the merged half is compared first, `e^(-i 2 pi (f_half - f_own) lag / fs)`, so
/// the half holds the delay at its own centroid, not a mix of its stretches' (a first-order term
/// where lines move between stretches). `None` for no stretch or a zero total.
fn merged(parts: &[StretchSpectra], lag: i64, sample_rate_hz: f64) -> Option<StretchSpectra> {
    let (head, last) = (parts.first()?, parts.last()?);
    let total: f64 = parts.iter().map(|p| p.equivalent_averages).sum();
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let moments = parts
        .iter()
        .map(|p| p.moments.as_ref())
        .collect::<Option<Vec<_>>>()
        .and_then(|m| InputMoments::sum(&m));
    let average =
        |of: fn(&StretchSpectra) -> &Vec<Matrix3<Complex64>>, turned: bool| -> Vec<Matrix3<Complex64>> {
            let mut acc = vec![Matrix3::zeros(); of(head).len()];
            for p in parts {
                let w = p.equivalent_averages / total;
                // The stretch's native grid: bin `b` at `b fs / segment`.
                let df = sample_rate_hz / (2 * of(p).len().saturating_sub(1)).max(1) as f64;
                for (b, (a, v)) in acc.iter_mut().zip(of(p)).enumerate() {
                    let turn = if turned {
                        let at = |m: Option<&InputMoments>| {
                            m.and_then(|m| m.centroid_at(b))
                                .map_or(b as f64 * df, |(fc, _)| fc)
                        };
                        delay_turn(at(p.moments.as_ref()), at(moments.as_ref()), lag, sample_rate_hz)
                    } else {
                        Complex64::new(1.0, 0.0)
                    };
                    *a += v * (turn * w);
                }
            }
            acc
        };
    Some(StretchSpectra {
        span_s: [head.span_s[0], last.span_s[1]],
        s_uu: average(|p| &p.s_uu, false),
        s_xu: average(|p| &p.s_xu, lag != 0),
        s_xx: average(|p| &p.s_xx, false),
        equivalent_averages: total,
        moments,
    })
}

/// The phase turn that moves a delay of `lag` samples given back at `own_hz` to `half_hz`
/// (each the inputs' centroid at the bin, else its centre, as
/// [`super::stretches::compared_at`] compares them); none for a non-finite frequency.
fn delay_turn(own_hz: f64, half_hz: f64, lag: i64, sample_rate_hz: f64) -> Complex64 {
    let turns = (half_hz - own_hz) * lag as f64 / sample_rate_hz;
    if turns.is_finite() {
        Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * turns)
    } else {
        Complex64::new(1.0, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::{WelchPlanner, WelchSettings, Window};

    /// Inputs whose colour changes at the record's middle (an AR(1) pole of 0.9, then -0.6), so
    /// the two halves' centroids differ within each bin.
    fn inputs(n: usize, seed: u64) -> [Vec<f64>; 3] {
        let mut rng = crate::rng::Rng::new(seed);
        std::array::from_fn(|_| {
            let mut y = 0.0;
            (0..n)
                .map(|t| {
                    let pole = if t < n / 2 { 0.9 } else { -0.6 };
                    y = pole * y + rng.normal();
                    y
                })
                .collect()
        })
    }

    /// Two stretches whose `S_xu` had the delay of `lag` samples given back each at its own
    /// centroid merge into the average of the unturned spectra given it back at the merged
    /// centroid (reconstructed bin by bin); with no lag, the plain average.
    #[test]
    fn a_half_holds_the_delay_at_its_own_centroid() {
        let (fs, segment) = (200.0, 256_usize);
        let settings = WelchSettings {
            segment_len: segment,
            window: Window::Hann,
            ..WelchSettings::default()
        };
        let u = inputs(segment * 16, 5);
        let moments = WelchPlanner::new()
            .input_moments([&u[0], &u[1], &u[2]], fs, &settings, 2)
            .expect("moments")
            .expect("two parts");
        let bins = segment / 2 + 1;
        let df = fs / segment as f64;
        let at = |m: &InputMoments, b: usize| m.centroid_at(b).map_or(b as f64 * df, |(fc, _)| fc);
        // The halves' centroids must differ, or the test could not tell a mix from the mend.
        let apart = (1..bins - 1)
            .map(|b| (at(&moments[0], b) - at(&moments[1], b)).abs())
            .fold(0.0, f64::max);
        assert!(apart > 0.05 * df, "centroids {apart} Hz apart");
        let unturned = |i: usize, b: usize| {
            Matrix3::from_fn(|r, c| {
                Complex64::new(0.1 * (r + 2 * c + i) as f64 + 1.0, (b as f64 * 0.3).sin())
            })
        };
        let turn =
            |f: f64, lag: i64| Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * lag as f64 / fs);
        let weights = [3.0, 5.0];
        let whole = InputMoments::sum(&[&moments[0], &moments[1]]).expect("sum");
        // Both stretches with their moments (compared at the centroids), and the second without
        // (then every stretch and the half at the bins' centres).
        for with_moments in [true, false] {
            for lag in [0_i64, 37, -60] {
                let parts: Vec<StretchSpectra> = (0..2)
                    .map(|i| {
                        let moments = (with_moments || i == 0).then(|| moments[i].clone());
                        // Given back as the spectral stage gives it back.
                        let mut s_xu: Vec<_> = (0..bins).map(|b| unturned(i, b)).collect();
                        crate::ident::alignment::restore_delay(&mut s_xu, lag, fs, |b| {
                            moments.as_ref().and_then(|m| m.centroid_at(b)).map(|(fc, _)| fc)
                        });
                        StretchSpectra {
                            span_s: [i as f64, i as f64 + 1.0],
                            s_uu: vec![Matrix3::identity(); bins],
                            s_xu,
                            s_xx: vec![Matrix3::identity(); bins],
                            equivalent_averages: weights[i],
                            moments,
                        }
                    })
                    .collect();
                let half = merged(&parts, lag, fs).expect("merged");
                assert_eq!(half.moments.is_some(), with_moments);
                for b in 0..bins {
                    let mean = (unturned(0, b) * Complex64::from(weights[0])
                        + unturned(1, b) * Complex64::from(weights[1]))
                        / Complex64::from(weights[0] + weights[1]);
                    let f_half = if with_moments {
                        at(&whole, b)
                    } else {
                        b as f64 * df
                    };
                    let expected = if lag == 0 { mean } else { mean * turn(f_half, lag) };
                    let error = (half.s_xu[b] - expected).norm();
                    assert!(
                        error < 1e-9 * (1.0 + expected.norm()),
                        "moments {with_moments}, lag {lag}, bin {b}: {error:e}"
                    );
                }
                assert!((half.equivalent_averages - 8.0).abs() < 1e-12);
            }
        }
    }
}
