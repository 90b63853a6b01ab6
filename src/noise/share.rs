//! Where a block's disturbance is the reference's: the part of each output channel's
//! disturbance density `S_psi,ii` (the identification's residual PSD, the model's `noise_psd`)
//! that the reference's angle error explains ([`ReferencePsd`]: the observer's error through the
//! model, differentiated for the gyro), and the frequency ranges where that part is at least
//! [`DOMINANT_SHARE`] of it. There the disturbance is the stand's angle measurement, not the
//! sensor: a lab engineer reading the disturbance PSD must not take it for the sensor's noise.
//!
//! Units: both densities one-sided, in the channel's output units^2/Hz (the spectral module's
//! convention); frequencies in Hz. Empty input gives no ranges; a bin whose disturbance is not
//! finite and positive, or which lies outside the reference's bands, is never dominated.

use crate::block::Block;
use crate::model::BlockModel;
use crate::stand::observer::ObserverEstimate;

use super::reference::{AccelGeometry, ReferencePsd, reference_psd};

/// The reference's share of the disturbance from which a bin counts as the reference's.
pub const DOMINANT_SHARE: f64 = 0.5;

/// Fewest bins a range holds (single bins are the estimates' scatter).
pub const MIN_RANGE_BINS: usize = 3;

/// Longest run of bins below the share inside a range (the estimates' scatter).
pub const MAX_GAP_BINS: usize = 3;

/// The reference's part of one block's disturbance, on the model's frequencies.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReferenceShare {
    /// The reference's density at each of the model's frequencies, per output channel,
    /// units^2/Hz (0 outside the observer's error bands).
    pub psd: [Vec<f64>; 3],
    /// Per output channel, the frequency ranges `[from, to]` (Hz, both bins included) where the
    /// reference's density is at least [`DOMINANT_SHARE`] of the disturbance's.
    pub dominated_hz: [Vec<[f64; 2]>; 3],
}

/// The reference's share of `model`'s disturbance, for the observer's `motion` (its angles and
/// error density) and the accelerometer's `geometry`.
#[must_use]
pub fn reference_share(
    block: Block,
    model: &BlockModel,
    motion: &ObserverEstimate,
    geometry: AccelGeometry,
) -> ReferenceShare {
    let reference = reference_psd(block, &model.k, &motion.euler, &motion.error_psd, geometry);
    let psd: [Vec<f64>; 3] = std::array::from_fn(|i| {
        model
            .frequency_hz
            .iter()
            .map(|&f| reference[i].at(f).unwrap_or(0.0))
            .collect()
    });
    let dominated_hz = std::array::from_fn(|i| {
        let disturbance: Vec<f64> = (0..model.frequency_hz.len())
            .map(|k| model.noise_psd.re.get(k).map_or(f64::NAN, |m| m[i][i]))
            .collect();
        dominated_ranges(&model.frequency_hz, &disturbance, &psd[i])
    });
    ReferenceShare { psd, dominated_hz }
}

/// The ranges of `frequency_hz` where `reference >= DOMINANT_SHARE * disturbance`: runs of at
/// least [`MIN_RANGE_BINS`] such bins, gaps of up to [`MAX_GAP_BINS`] bins bridged, each range
/// ending at its last bin where most of its bins are above the share.
#[must_use]
pub fn dominated_ranges(frequency_hz: &[f64], disturbance: &[f64], reference: &[f64]) -> Vec<[f64; 2]> {
    let n = frequency_hz.len().min(disturbance.len()).min(reference.len());
    let dominated: Vec<bool> = (0..n)
        .map(|k| {
            let d = disturbance[k];
            d.is_finite() && d > 0.0 && reference[k] >= DOMINANT_SHARE * d
        })
        .collect();
    let mut ranges = Vec::new();
    let mut k = 0;
    while k < n {
        if !dominated[k] {
            k += 1;
            continue;
        }
        // Extend over gaps of up to MAX_GAP_BINS; the range ends at the last bin where most of
        // its bins so far are above the share (scattered bins after a solid run do not sink it).
        let start = k;
        let (mut end, mut count, mut best) = (k, 1, (k, 1));
        while let Some(gap) = (1..=MAX_GAP_BINS + 1).find(|g| end + g < n && dominated[end + g]) {
            end += gap;
            count += 1;
            if 2 * count > end - start + 1 {
                best = (end, count);
            }
        }
        let (last, held) = best;
        if held >= MIN_RANGE_BINS {
            ranges.push([frequency_hz[start], frequency_hz[last]]);
        }
        k = last + 1;
    }
    ranges
}

impl ReferencePsd {
    /// Its density at `f_hz`: the mean density of the band holding it, `None` outside the bands.
    #[must_use]
    pub fn at(&self, f_hz: f64) -> Option<f64> {
        let b = crate::spectral::bands::band_holding(&self.edges_hz, f_hz)?;
        self.psd.get(b).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_density_is_read_in_the_band_holding_the_frequency() {
        let r = ReferencePsd {
            edges_hz: vec![1.0, 2.0, 4.0],
            psd: vec![10.0, 20.0],
        };
        assert_eq!(r.at(0.5), None);
        assert_eq!(r.at(1.0), Some(10.0));
        assert_eq!(r.at(1.99), Some(10.0));
        assert_eq!(r.at(2.0), Some(20.0));
        assert_eq!(r.at(4.0), Some(20.0));
        assert_eq!(r.at(4.01), None);
        assert_eq!(ReferencePsd::default().at(1.0), None);
    }

    #[test]
    fn ranges_hold_runs_of_bins_where_the_reference_is_half_or_more() {
        let f: Vec<f64> = (1..=20).map(f64::from).collect();
        let mut disturbance = vec![4.0; 20];
        let mut reference = vec![1.0; 20];
        // 12..=20 Hz dominated (a share of exactly half counts), with a three-bin dip at 15-17 Hz
        // bridged; two bins at 2 and 5 Hz are scatter.
        for k in 11..20 {
            reference[k] = 2.0;
        }
        for k in 14..17 {
            reference[k] = 1.9;
        }
        reference[1] = 3.0;
        reference[4] = 3.0;
        assert_eq!(dominated_ranges(&f, &disturbance, &reference), vec![[12.0, 20.0]]);
        // Bins above the share scattered among more below it are no range.
        let sparse: Vec<f64> = (0..20).map(|k| if k % 3 == 0 { 3.0 } else { 1.0 }).collect();
        assert!(dominated_ranges(&f, &disturbance, &sparse).is_empty());
        // ... nor do they hide a solid run after them: scattered bins at 1 and 5 Hz bridged to
        // 9-12 Hz fail as one range (6 of 12 bins), 5-12 Hz does not (5 of 8).
        let mut late = vec![1.0; 20];
        for k in [0, 4, 8, 9, 10, 11] {
            late[k] = 3.0;
        }
        assert_eq!(dominated_ranges(&f, &disturbance, &late), vec![[5.0, 12.0]]);
        // ... or one before them: 1-4 Hz, then every fourth bin to the top.
        let early: Vec<f64> = (0..20)
            .map(|k| if k < 4 || k % 4 == 3 { 3.0 } else { 1.0 })
            .collect();
        // (1-8 Hz: 5 of its 8 bins; the scattered rest is no range.)
        assert_eq!(dominated_ranges(&f, &disturbance, &early), vec![[1.0, 8.0]]);
        // Four bins below break the run: 12-14 Hz stays, two bins at 19-20 Hz are too few.
        reference[17] = 1.0;
        assert_eq!(dominated_ranges(&f, &disturbance, &reference), vec![[12.0, 14.0]]);
        // A disturbance that is NaN, zero or negative is never the reference's.
        disturbance[11] = f64::NAN;
        disturbance[12] = 0.0;
        disturbance[13] = -1.0;
        assert!(dominated_ranges(&f, &disturbance, &reference).is_empty());
        assert!(dominated_ranges(&[], &[], &[]).is_empty());
        assert!(dominated_ranges(&f, &[4.0; 20], &[1.0; 20]).is_empty());
    }
}
