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
    let halves = [merged(first)?, merged(second)?];
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
/// averages as weights, which add up. `None` for no stretch or a zero total.
fn merged(parts: &[StretchSpectra]) -> Option<StretchSpectra> {
    let (head, last) = (parts.first()?, parts.last()?);
    let total: f64 = parts.iter().map(|p| p.equivalent_averages).sum();
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let average = |of: fn(&StretchSpectra) -> &Vec<Matrix3<Complex64>>| -> Vec<Matrix3<Complex64>> {
        let mut acc = vec![Matrix3::zeros(); of(head).len()];
        for p in parts {
            let w = Complex64::from(p.equivalent_averages / total);
            for (a, v) in acc.iter_mut().zip(of(p)) {
                *a += v * w;
            }
        }
        acc
    };
    Some(StretchSpectra {
        span_s: [head.span_s[0], last.span_s[1]],
        s_uu: average(|p| &p.s_uu),
        s_xu: average(|p| &p.s_xu),
        s_xx: average(|p| &p.s_xx),
        equivalent_averages: total,
        moments: parts
            .iter()
            .map(|p| p.moments.as_ref())
            .collect::<Option<Vec<_>>>()
            .and_then(|m| InputMoments::sum(&m)),
    })
}
