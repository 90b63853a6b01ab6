//! Where the usable band's top must end because the model stops explaining the data there.
//!
//! The usable band ([`super::band`]) is where the outputs are coherent with the inputs computed
//! from the angles. A deterministic change of the reference near its band limit (a zero-phase
//! smoothing filter, an interpolation kernel) keeps the coherence high: the inputs are filtered,
//! not noisy, and the estimate's gain rises towards the band's top by the filter's inverse, with no
//! phase a causal sensor would need for such a rise. Measured on simulated `--stand real` runs (a
//! zero-phase band limit at 30 Hz): the gyro's `H` gain 1 % above `K` at 20 Hz, 40-60 % at 30 Hz,
//! coherence still above 0.95, the band found reaching 32 Hz, and `K` off by 0.15-0.2 % (chi2/dof
//! 9) where the same runs fitted below 25 Hz are off by 0.05 % (chi2/dof 0.65).
//!
//! Rule ([`misfit_edge`]): the chosen model's chi2 per native bin, normalised by its expectation
//! (18, three complex rows of three elements), is split at each candidate edge into the band below
//! and the stretch above. The split that best explains the per-bin chi2 by two levels (profile
//! likelihood of scaled chi-square variables, `nu = 18 / bin_correlation` effective degrees of
//! freedom per bin) is kept when the stretch above is the worse one by at least
//! [`MIN_LEVEL_RATIO`] (in mean and in median: a line a few bins wide at the top is not a
//! stretch), is itself a misfit by the self-check's measure (mean chi2 per bin above
//! [`POOR_FIT`] times its expectation: a stretch the model explains to its stated noise is not
//! cut because the band below is explained better still; measured on an independent simulator's
//! runs once the columns were compared where they lie, `structural::align`: stretches at 0.6-1.2
//! of their expectation against 0.1-0.4 below, 17 of 58 runs, none with a band limit),
//! holds at least [`MIN_TOP_BINS`] bins, leaves at least half the band below,
//! and the likelihood ratio exceeds [`MIN_LIKELIHOOD_RATIO`] once divided by the dispersion of
//! the chi2 below the split (quasi-likelihood: their variance over a scaled chi-square's, at
//! least 1; a structured misfit over the whole band does not make a split significant, a noise
//! model off by a constant factor does not move the split). The band then ends at the split's lowest bin, and the block is
//! fitted again over it; the identification says so (`band_top_misfit`).
//!
//! Only the auto band is trimmed: a band the user gives is kept as given (its misfit is reported
//! by the self-check's `poor_fit`). The diagnosis fits over its own search limits and is not
//! affected. Units: Hz; chi2 values dimensionless. Non-finite chi2 values make no split.

use super::selfcheck::POOR_FIT;

/// Smallest ratio of the stretch's mean chi2 per bin to the band's below it.
pub const MIN_LEVEL_RATIO: f64 = 2.0;

/// Fewest native bins of the stretch above the split.
pub const MIN_TOP_BINS: usize = 8;

/// Smallest likelihood ratio of the two-level split (about a Bonferroni-corrected chi-square
/// test at 1e-3 over a few hundred candidate splits: the chi-square(1) quantile at 3e-6 is 21.7).
pub const MIN_LIKELIHOOD_RATIO: f64 = 25.0;

/// The split found: the stretch above `index` (into the band's bins) is left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MisfitEdge {
    /// Index of the first bin left out (into the band's bins, in frequency order).
    pub index: usize,
    /// Mean normalised chi2 per bin below the split.
    pub level_below: f64,
    /// Mean normalised chi2 per bin above it.
    pub level_above: f64,
    /// The likelihood ratio, divided by the overdispersion below.
    pub likelihood_ratio: f64,
}

/// The split of the band (see the module docs) given the chosen model's chi2 per native band bin
/// (`chi2`, in frequency order) and the bins' correlation factor, or `None`.
#[must_use]
pub fn misfit_edge(chi2: &[f64], bin_correlation: f64) -> Option<MisfitEdge> {
    let n = chi2.len();
    if n < 2 * MIN_TOP_BINS || chi2.iter().any(|c| !c.is_finite()) {
        return None;
    }
    // A chi2 a rounding error below zero is zero.
    let r: Vec<f64> = chi2.iter().map(|c| c.max(0.0) / 18.0).collect();
    let nu = 18.0 / bin_correlation.max(1.0);
    let mut below = vec![0.0; n + 1];
    for (k, v) in r.iter().enumerate() {
        below[k + 1] = below[k] + v;
    }
    let total = below[n];
    let log_level = |sum: f64, m: usize| (sum / m as f64).max(f64::MIN_POSITIVE).ln();
    let whole = n as f64 * log_level(total, n);
    let mut best: Option<MisfitEdge> = None;
    for index in n.div_ceil(2)..=(n - MIN_TOP_BINS) {
        let (low, high) = (below[index], total - below[index]);
        let (m_low, m_high) = (index, n - index);
        let level_below = low / m_low as f64;
        let level_above = high / m_high as f64;
        if level_above < MIN_LEVEL_RATIO * level_below || level_above <= POOR_FIT {
            continue;
        }
        let ratio =
            nu * (whole - m_low as f64 * log_level(low, m_low) - m_high as f64 * log_level(high, m_high));
        let likelihood_ratio = ratio / dispersion(&r[..index], nu);
        if best.is_none_or(|b| likelihood_ratio > b.likelihood_ratio) {
            best = Some(MisfitEdge {
                index,
                level_below,
                level_above,
                likelihood_ratio,
            });
        }
    }
    // The stretch must be worse as a whole, not through a few bins (a line at the top): its median
    // too.
    best.filter(|b| {
        b.likelihood_ratio > MIN_LIKELIHOOD_RATIO
            && median(&r[b.index..]) >= MIN_LEVEL_RATIO * median(&r[..b.index])
    })
}

/// The quasi-likelihood dispersion of `r` (chi2 per bin over its expectation): its variance over
/// the `2 mean^2 / nu` of a scaled chi-square with `nu` degrees of freedom, at least 1. Scale-free:
/// a noise model off by a constant factor leaves it unchanged, a misfit that varies from bin to
/// bin (a structured residual) raises it.
fn dispersion(r: &[f64], nu: f64) -> f64 {
    let n = r.len() as f64;
    let mean = r.iter().sum::<f64>() / n;
    let var = r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    if mean > 0.0 {
        (var * nu / (2.0 * mean * mean)).max(1.0)
    } else {
        1.0
    }
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    // The lower median: half the stretch or more must be worse.
    v.get(v.len().saturating_sub(1) / 2).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::{MIN_TOP_BINS, misfit_edge};

    /// Per-bin chi2 of a fit that explains the data: 18 times a level, with a deterministic
    /// wobble of +-30 % (the spread of a chi-square with about nine degrees of freedom).
    fn flat(n: usize, level: f64) -> Vec<f64> {
        (0..n)
            .map(|k| 18.0 * level * (1.0 + 0.3 * (k as f64 * 2.1).sin()))
            .collect()
    }

    #[test]
    fn a_fit_that_explains_the_band_keeps_it() {
        assert_eq!(misfit_edge(&flat(300, 0.7), 1.94), None);
        assert_eq!(misfit_edge(&flat(300, 1.0), 1.94), None);
    }

    #[test]
    fn a_misfit_rising_at_the_top_is_cut_where_it_starts() {
        // Level 0.7 up to bin 240, then a rise to 40 (a gain 40 % off at the top).
        let mut c = flat(300, 0.7);
        for (k, v) in c.iter_mut().enumerate().skip(240) {
            *v = 18.0 * (0.7 + 0.65 * (k - 240) as f64);
        }
        let edge = misfit_edge(&c, 1.94).expect("a split");
        assert!((240..=252).contains(&edge.index), "{edge:?}");
        assert!(edge.level_above > 5.0 * edge.level_below, "{edge:?}");
    }

    #[test]
    fn a_constant_factor_on_the_noise_changes_nothing_and_a_structured_misfit_below_weakens_a_split() {
        let mut c = flat(300, 0.7);
        for (k, v) in c.iter_mut().enumerate().skip(240) {
            *v = 18.0 * (0.7 + 0.05 * (k - 240) as f64);
        }
        let edge = misfit_edge(&c, 1.94).expect("a split");
        let scaled: Vec<f64> = c.iter().map(|v| 3.0 * v).collect();
        let again = misfit_edge(&scaled, 1.94).expect("a split");
        assert_eq!(again.index, edge.index, "scale-free");
        assert!((again.likelihood_ratio - edge.likelihood_ratio).abs() < 1e-9 * edge.likelihood_ratio);
        // The same top over a band whose misfit swings by 20x from bin to bin.
        let mut structured = c.clone();
        for (k, v) in structured.iter_mut().enumerate().take(240) {
            *v *= if k % 7 < 2 { 6.0 } else { 0.3 };
        }
        let weak = misfit_edge(&structured, 1.94).map_or(0.0, |e| e.likelihood_ratio);
        assert!(
            weak < edge.likelihood_ratio / 2.0,
            "{weak} vs {}",
            edge.likelihood_ratio
        );
    }

    /// The band explained better than its stated noise (weights that overstate it) and the top
    /// explained to it: no misfit to cut (an independent simulator's runs: 0.35 below, 0.9 above).
    /// The same shape at twice the level is a misfit above and is cut.
    #[test]
    fn a_top_within_its_stated_noise_is_not_a_misfit() {
        let mut c = flat(300, 0.35);
        for v in c.iter_mut().skip(240) {
            *v *= 2.6;
        }
        assert_eq!(misfit_edge(&c, 1.94), None);
        let doubled: Vec<f64> = c.iter().map(|v| 2.5 * v).collect();
        let edge = misfit_edge(&doubled, 1.94).expect("a misfit above");
        assert!((238..=242).contains(&edge.index), "{edge:?}");
    }

    #[test]
    fn a_misfit_spread_over_the_whole_band_is_not_a_split() {
        // A poor fit everywhere (level 4, the real runs' kind) with a mild rise at the top.
        let mut c = flat(300, 4.0);
        for v in c.iter_mut().skip(260) {
            *v *= 1.5;
        }
        assert_eq!(misfit_edge(&c, 1.94), None);
    }

    #[test]
    fn too_few_bins_above_or_a_lower_half_misfit_make_no_split() {
        let mut c = flat(300, 0.7);
        for v in c.iter_mut().skip(300 - MIN_TOP_BINS / 2) {
            *v = 18.0 * 50.0;
        }
        assert_eq!(misfit_edge(&c, 1.94), None, "a few bins at the very top (a line)");
        let mut low = flat(300, 0.7);
        for v in low.iter_mut().take(100) {
            *v = 18.0 * 30.0;
        }
        assert_eq!(
            misfit_edge(&low, 1.94),
            None,
            "a misfit low in the band is not the top's"
        );
        assert_eq!(misfit_edge(&[f64::NAN; 40], 1.94), None);
        assert_eq!(misfit_edge(&[], 1.94), None);
    }
}
