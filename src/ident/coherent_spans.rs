//! Where in the record a block's outputs are coherent with the inputs computed from the angles,
//! when the record as a whole is not (the refusal [`super::IdentError::NoUsableBand`]). A
//! recording whose outputs, from some time on, are of another motion than its angles (a splice,
//! a block of samples lost from one stream, a stalled logger) has no usable band over the whole
//! record, yet its stretches before the fault are as coherent as any: the refusal then says where,
//! so that the engineer can look there and analyse the good part alone (`span_s`).
//!
//! Each stretch of the stationarity check ([`super::stretches`], or its finer stretches on a
//! short record) is *coherent* when at least [`super::band::MIN_BAND_BINS`] of its native bins
//! inside the search limits have a median (over the three outputs) multiple coherence of at least
//! [`super::band::MIN_COHERENCE`], the bar of a usable band; otherwise not. A stretch of a few
//! Welch averages overestimates a coherence of zero by about 3 over its averages (0.3 at ten), far
//! below the bar. Only a record with both kinds is localised; consecutive coherent stretches are
//! merged into spans, each ended at its last stretch's middle where an incoherent stretch follows
//! (and begun at its first's middle where one precedes): a stretch that holds the fault near its
//! end still reads coherent (a real recording spliced at 42.6 s: its stretch of 21.5-50.2 s did),
//! and the span said is one to analyse. Units: s from the first sample analysed, Hz. A singular input spectrum at a
//! bin counts as not coherent there; without stretches there is nothing to say (`None`).

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::band::{MIN_BAND_BINS, MIN_COHERENCE, native_bins};
use super::spectra::BlockSpectra;
use super::stretches::{MIN_STRETCHES, StretchSpectra};

/// The median over outputs of the multiple coherence at one stretch bin
/// ([`super::band::coherence_of`]).
fn median_coherence(s_uu: &Matrix3<Complex64>, s_xu: &Matrix3<Complex64>, s_xx: &Matrix3<Complex64>) -> f64 {
    let mut c = super::band::coherence_of(s_uu, s_xu, s_xx);
    c.sort_by(f64::total_cmp);
    c[1]
}

/// Whether stretch `s` is coherent at the stretch bins `bins`.
fn coherent(s: &StretchSpectra, bins: &[usize]) -> bool {
    bins.iter()
        .filter(|&&b| match (s.s_uu.get(b), s.s_xu.get(b), s.s_xx.get(b)) {
            (Some(uu), Some(xu), Some(xx)) => median_coherence(uu, xu, xx) >= MIN_COHERENCE,
            _ => false,
        })
        .count()
        >= MIN_BAND_BINS
}

/// The spans (s from the first sample) over which `spectra`'s stretches are coherent inside
/// `limits_hz`, merged where they overlap; `None` unless some stretches are and some are not.
#[must_use]
pub fn coherent_spans(spectra: &BlockSpectra, limits_hz: [f64; 2]) -> Option<Vec<[f64; 2]>> {
    let (stretches, bins): (&[StretchSpectra], Vec<usize>) = if spectra.stretches.len() >= MIN_STRETCHES {
        let step = spectra.native_step();
        let bins = native_bins(spectra, limits_hz)
            .iter()
            .map(|&k| k / step)
            .collect();
        (&spectra.stretches, bins)
    } else {
        let finer = spectra.finer_stretches.as_ref()?;
        let bin_hz = |k: usize| k as f64 * spectra.sample_rate_hz / finer.segment_len as f64;
        let bins = (0..=finer.segment_len / 2)
            .filter(|&k| (limits_hz[0]..=limits_hz[1]).contains(&bin_hz(k)))
            .collect();
        (&finer.stretches, bins)
    };
    let flags: Vec<bool> = stretches.iter().map(|s| coherent(s, &bins)).collect();
    if flags.iter().all(|&c| c) || !flags.iter().any(|&c| c) {
        return None;
    }
    let middle = |s: &StretchSpectra| 0.5 * (s.span_s[0] + s.span_s[1]);
    let mut spans: Vec<[f64; 2]> = Vec::new();
    let mut i = 0;
    while i < flags.len() {
        if !flags[i] {
            i += 1;
            continue;
        }
        let first = i;
        while i + 1 < flags.len() && flags[i + 1] {
            i += 1;
        }
        let start = if first > 0 {
            middle(&stretches[first])
        } else {
            stretches[first].span_s[0]
        };
        let end = if i + 1 < flags.len() {
            middle(&stretches[i])
        } else {
            stretches[i].span_s[1]
        };
        spans.push([start, end]);
        i += 1;
    }
    Some(spans)
}
