#![expect(clippy::float_cmp, reason = "bin frequencies are exact multiples of 1 Hz")]

use std::path::Path;

use nalgebra::Matrix3;
use num_complex::Complex64;

use super::*;
use crate::ident::settings::Settings;

const BINS: usize = 513;
const RATE: f64 = 1024.0; // 1 Hz per bin with fft_len 1024

/// Spectra of `x = u + n` with `S_uu = I` and white-per-bin output noise `noise(f)`: each
/// output's multiple coherence is exactly `1 / (1 + noise(f))`.
fn spectra(noise: impl Fn(f64) -> f64) -> BlockSpectra {
    let fft_len = 2 * (BINS - 1);
    let frequency_hz: Vec<f64> = (0..BINS).map(|k| k as f64 * RATE / fft_len as f64).collect();
    let one = Matrix3::<Complex64>::identity();
    BlockSpectra {
        aligned_samples: 0,
        centroid_hz: Vec::new(),
        centroid_offset_hz: Vec::new(),
        gyro_witnessed: false,
        left_out_noise: None,
        s_uu: vec![one; BINS],
        s_xu: vec![one; BINS],
        s_xx: frequency_hz
            .iter()
            .map(|&f| one * Complex64::from(1.0 + noise(f)))
            .collect(),
        frequency_hz,
        n_averages: 40,
        equivalent_averages: 38.0,
        bin_correlation: 1.0,
        stretches: Vec::new(),
        finer_stretches: None,
        stationarity_cache: crate::ident::stretches::StationarityCache::default(),
        held_out_cache: crate::ident::holdout::HeldOutCache::default(),
        usable_band_cache: crate::ident::band_cache::BandCache::default(),
        sample_rate_hz: RATE,
        fft_len,
        segment_len: fft_len,
    }
}

/// Coherence `c` as output noise.
fn noise_for(c: f64) -> f64 {
    1.0 / c - 1.0
}

#[test]
fn multiple_coherence_matches_the_closed_form() {
    let sp = spectra(|f| if f < 10.0 { noise_for(0.99) } else { noise_for(0.3) });
    for (k, expected) in [(5, 0.99), (20, 0.3)] {
        for c in multiple_coherence(&sp, k) {
            assert!((c - expected).abs() < 1e-12, "bin {k}: {c}");
        }
    }
}

#[test]
fn the_band_ends_where_the_coherence_falls() {
    // Coherent up to 12 Hz, then noise: the band is [first bin >= 0.1 Hz, 12 Hz].
    let sp = spectra(|f| {
        if f <= 12.0 {
            noise_for(0.98)
        } else {
            noise_for(0.4)
        }
    });
    let band = usable_band(&sp, [0.1, 40.0]).unwrap();
    assert_eq!(band, [1.0, 12.0]);
    // The most coherent stretch is kept when there are two: 2-5 Hz (4 bins, too short) and
    // 15-35 Hz.
    let sp = spectra(|f| {
        if (2.0..=5.0).contains(&f) || (15.0..=35.0).contains(&f) {
            noise_for(0.95)
        } else {
            noise_for(0.5)
        }
    });
    assert_eq!(usable_band(&sp, [0.1, 40.0]).unwrap(), [15.0, 35.0]);
}

#[test]
fn a_line_a_few_bins_wide_does_not_split_the_band() {
    // A tone over 4 bins (20-23 Hz) leaves the band whole; a dip of 6 bins splits it.
    let tone = spectra(|f| {
        if (20.0..=23.0).contains(&f) {
            noise_for(0.2)
        } else {
            noise_for(0.97)
        }
    });
    assert_eq!(usable_band(&tone, [0.1, 40.0]).unwrap(), [1.0, 40.0]);
    let dip = spectra(|f| {
        if (20.0..=25.0).contains(&f) {
            noise_for(0.2)
        } else {
            noise_for(0.97)
        }
    });
    let band = usable_band(&dip, [0.1, 40.0]).unwrap();
    assert!(band[1] < 21.0 || band[0] > 24.0, "{band:?}");
}

#[test]
fn no_coherent_stretch_gives_none_and_the_best_coherence() {
    let sp = spectra(|_| noise_for(0.6));
    assert_eq!(usable_band(&sp, [0.1, 40.0]), None);
    assert!((best_coherence(&sp, [0.1, 40.0]) - 0.6).abs() < 1e-12);
    // Fewer than MIN_BAND_BINS coherent bins: none either.
    let short = spectra(|f| {
        if (3.0..=7.0).contains(&f) {
            noise_for(0.99)
        } else {
            noise_for(0.3)
        }
    });
    assert_eq!(usable_band(&short, [0.1, 40.0]), None);
}

#[test]
fn untrusted_ranges_of_a_given_band() {
    let sp = spectra(|f| {
        if f <= 12.0 {
            noise_for(0.98)
        } else {
            noise_for(0.4)
        }
    });
    let ranges = untrusted_ranges(&sp, [1.0, 40.0]);
    assert_eq!(ranges.len(), 1, "{ranges:?}");
    assert_eq!(ranges[0], [13.0, 40.0]);
    assert!(untrusted_ranges(&sp, [1.0, 12.0]).is_empty());
    assert_eq!(untrusted_to_top(&sp, [1.0, 40.0]), Some([13.0, 40.0]));
    assert_eq!(
        untrusted_to_top(&sp, [1.0, 40.0]).map(|r| last_bin_below(&sp, [1.0, 40.0], r[0])),
        Some(Some(12.0))
    );
    assert_eq!(last_bin_below(&sp, [1.0, 40.0], 1.0), None);
    assert_eq!(untrusted_to_top(&sp, [1.0, 12.0]), None);
    // A dip inside the band whose top is trusted: no range to the top.
    let dip = spectra(|f| noise_for(if (10.0..=20.0).contains(&f) { 0.4 } else { 0.98 }));
    assert_eq!(untrusted_ranges(&dip, [1.0, 40.0]).len(), 1);
    assert_eq!(untrusted_to_top(&dip, [1.0, 40.0]), None);
}

#[test]
fn the_setting_reads_auto_or_two_numbers() {
    let parse = |t: &str| Settings::from_json(t.as_bytes(), Path::new("s.json"));
    assert_eq!(parse("{}").unwrap().band_hz, BandSetting::Auto);
    assert_eq!(
        parse(r#"{"band_hz": "auto"}"#).unwrap().band_hz,
        BandSetting::Auto
    );
    assert_eq!(
        parse(r#"{"band_hz": [0.5, 20]}"#).unwrap().band_hz,
        BandSetting::Fixed([0.5, 20.0])
    );
    let e = parse(r#"{"band_hz": "wide"}"#).unwrap_err().to_string();
    assert!(e.contains("band_hz") && e.contains("auto"), "{e}");
    assert_eq!(auto_limits(500.0), [0.1, 40.0]);
    assert_eq!(auto_limits(50.0), [0.1, 20.0]);
}

/// The auto band is found once per spectra (a retune asks again): the cached answer is the
/// search's, with and without a usable band, and a given band is kept as given.
#[test]
fn the_auto_band_is_the_searchs_own_when_asked_again() {
    use crate::block::Block;
    use crate::ident::identify::resolve_band;
    let sp = spectra(|f| {
        if (15.0..=35.0).contains(&f) {
            noise_for(0.97)
        } else {
            noise_for(0.5)
        }
    });
    let limits = auto_limits(RATE);
    let found = usable_band(&sp, limits).unwrap();
    for _ in 0..2 {
        assert_eq!(resolve_band(&sp, Block::Gyro, BandSetting::Auto).unwrap(), found);
    }
    assert_eq!(
        resolve_band(&sp, Block::Gyro, BandSetting::Fixed([2.0, 9.0])).unwrap(),
        [2.0, 9.0]
    );
    let none = spectra(|_| noise_for(0.6));
    for _ in 0..2 {
        assert!(matches!(
            resolve_band(&none, Block::Accel, BandSetting::Auto),
            Err(crate::ident::IdentError::NoUsableBand { .. })
        ));
    }
}
