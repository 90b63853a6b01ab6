//! Welch settings: segment length, overlap, window and detrend, with their validation.

use super::{Detrend, SpectralError, Window};
use serde::{Deserialize, Serialize};

/// The smallest segment length accepted, samples.
pub const MIN_SEGMENT_LEN: usize = 8;

/// The segment length when none is given, samples.
pub const DEFAULT_SEGMENT_LEN: usize = 4096;

/// How a run is cut into segments and what is done to each. Every field is optional in JSON; an
/// unknown one is refused (a misspelt `segment_len` would otherwise be silently ignored).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "WelchSettingsFile")]
pub struct WelchSettings {
    /// Samples per segment `N`: even and at least [`MIN_SEGMENT_LEN`]. Default
    /// [`DEFAULT_SEGMENT_LEN`].
    pub segment_len: usize,
    /// `segment_len` is left to the program (the default: `segment_len` absent from the settings
    /// file, or `"segment_auto": true` beside it): it is then the longest segment tried, and a
    /// user of these settings may shorten it for a record too short to hold enough segments (the
    /// identifier does: [`crate::ident::settings::Settings::for_run`]). Written out only when
    /// true, beside the segment used, so an echo read back chooses the same segment.
    #[serde(skip_serializing_if = "is_false")]
    pub segment_auto: bool,
    /// Fraction of a segment shared with the next one, in `[0, 1)`. Default 0.5.
    #[serde(default = "default_overlap")]
    pub overlap: f64,
    /// Taper applied after detrending. Default Hann.
    pub window: Window,
    /// What is removed from each segment before windowing. Default the mean.
    pub detrend: Detrend,
    /// FFT length (scipy's `nfft`): each windowed segment is zero-padded to it. Even and at least
    /// `segment_len`; absent (`None`), it equals `segment_len`. Padding samples the same estimate
    /// on a finer grid: with `fft_len >= 2 segment_len` the grid holds the estimate's whole
    /// correlation without aliasing. The identifier takes it up to a whole number of segments
    /// (`ident::spectra::grid_len`), so the native bins lie on its grid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fft_len: Option<usize>,
}

/// [`WelchSettings`] as a settings file gives them: every field optional, unknown ones refused.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WelchSettingsFile {
    #[serde(default)]
    segment_len: Option<usize>,
    #[serde(default)]
    segment_auto: Option<bool>,
    #[serde(default = "default_overlap")]
    overlap: f64,
    #[serde(default)]
    window: Window,
    #[serde(default)]
    detrend: Detrend,
    #[serde(default)]
    fft_len: Option<usize>,
}

impl From<WelchSettingsFile> for WelchSettings {
    fn from(f: WelchSettingsFile) -> Self {
        Self {
            segment_len: f.segment_len.unwrap_or(DEFAULT_SEGMENT_LEN),
            segment_auto: f.segment_auto.unwrap_or(f.segment_len.is_none()),
            overlap: f.overlap,
            window: f.window,
            detrend: f.detrend,
            fft_len: f.fft_len,
        }
    }
}

#[expect(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_false(b: &bool) -> bool {
    !*b
}

fn default_overlap() -> f64 {
    0.5
}

impl Default for WelchSettings {
    fn default() -> Self {
        Self {
            segment_len: DEFAULT_SEGMENT_LEN,
            segment_auto: true,
            overlap: default_overlap(),
            window: Window::default(),
            detrend: Detrend::default(),
            fft_len: None,
        }
    }
}

impl WelchSettings {
    /// The FFT length actually used: `fft_len`, or `segment_len` when absent.
    #[must_use]
    pub fn nfft(&self) -> usize {
        self.fft_len.unwrap_or(self.segment_len)
    }

    /// Samples shared by consecutive segments: `round(overlap * segment_len)` (scipy's
    /// `noverlap`, which scipy takes as an integer; ties round away from zero).
    #[must_use]
    pub fn noverlap(&self) -> usize {
        (self.overlap * self.segment_len as f64).round() as usize
    }

    /// Samples from the start of one segment to the start of the next: `segment_len - noverlap`.
    /// Zero for settings that [`validate`](Self::validate) rejects.
    #[must_use]
    pub fn step(&self) -> usize {
        self.segment_len.saturating_sub(self.noverlap())
    }

    /// Number of whole segments in a run of `n_samples` (a trailing partial segment is dropped);
    /// zero for settings that [`validate`](Self::validate) rejects or a run shorter than a segment.
    #[must_use]
    pub fn n_segments(&self, n_samples: usize) -> usize {
        let step = self.step();
        if step == 0 || n_samples < self.segment_len {
            return 0;
        }
        (n_samples - self.segment_len) / step + 1
    }

    /// Checks the settings against a run of `n_samples` samples per channel.
    ///
    /// # Errors
    /// - [`SpectralError::BadSegmentLen`] if `segment_len` is odd or below [`MIN_SEGMENT_LEN`];
    /// - [`SpectralError::BadOverlap`] if `overlap` is not a finite number in `[0, 1)`, or is so
    ///   close to 1 that `round(overlap * segment_len) == segment_len`;
    /// - [`SpectralError::BadFftLen`] if `fft_len` is odd or shorter than `segment_len`;
    /// - [`SpectralError::TooFewSamples`] if `n_samples < segment_len`.
    pub fn validate(&self, n_samples: usize) -> Result<(), SpectralError> {
        let segment_len = self.segment_len;
        if segment_len < MIN_SEGMENT_LEN || !segment_len.is_multiple_of(2) {
            return Err(SpectralError::BadSegmentLen { segment_len });
        }
        let overlap = self.overlap;
        if !(0.0..1.0).contains(&overlap) || self.step() == 0 {
            return Err(SpectralError::BadOverlap { overlap, segment_len });
        }
        if let Some(fft_len) = self.fft_len
            && (fft_len < segment_len || !fft_len.is_multiple_of(2))
        {
            return Err(SpectralError::BadFftLen { fft_len, segment_len });
        }
        if n_samples < segment_len {
            return Err(SpectralError::TooFewSamples {
                n_samples,
                segment_len,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{Detrend, SpectralError, WelchSettings, Window};

    fn with(segment_len: usize, overlap: f64) -> WelchSettings {
        WelchSettings {
            segment_len,
            overlap,
            ..WelchSettings::default()
        }
    }

    #[test]
    fn defaults_and_partial_json() {
        let s: WelchSettings = serde_json::from_str("{}").unwrap();
        assert_eq!(s, WelchSettings::default());
        assert_eq!(
            (s.segment_len, s.overlap, s.window, s.detrend),
            (4096, 0.5, Window::Hann, Detrend::Mean)
        );
        let s: WelchSettings =
            serde_json::from_str(r#"{"segment_len": 256, "window": "hamming", "detrend": "linear"}"#)
                .unwrap();
        assert_eq!(
            (s.segment_len, s.overlap, s.window, s.detrend),
            (256, 0.5, Window::Hamming, Detrend::Linear)
        );
        let round_trip: WelchSettings = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(round_trip, s);
        assert!(!s.segment_auto, "a given segment is the user's");
        let given = serde_json::to_value(s).unwrap();
        assert!(given.get("segment_auto").is_none(), "{given}");
        // Left out, the segment is the program's, and the echo says so beside the segment.
        let auto: WelchSettings = serde_json::from_str(r#"{"overlap": 0.25}"#).unwrap();
        assert!(auto.segment_auto && auto.segment_len == 4096);
        let echoed = serde_json::to_value(auto).unwrap();
        assert_eq!(
            (&echoed["segment_len"], &echoed["segment_auto"]),
            (&4096.into(), &true.into())
        );
        let back: WelchSettings = serde_json::from_value(echoed).unwrap();
        assert_eq!(back, auto);
        // "segment_auto" beside a segment: the longest the program tries.
        let up_to: WelchSettings =
            serde_json::from_str(r#"{"segment_len": 1024, "segment_auto": true}"#).unwrap();
        assert!(up_to.segment_auto && up_to.segment_len == 1024);
        let typo = serde_json::from_str::<WelchSettings>(r#"{"segment": 1024}"#).unwrap_err();
        assert!(typo.to_string().contains("unknown field"), "{typo}");
    }

    #[test]
    fn segment_counting_matches_scipy() {
        // scipy: nseg = (n - noverlap) // (nperseg - noverlap)
        assert_eq!(with(64, 0.5).n_segments(1000), (1000 - 32) / 32);
        assert_eq!(with(64, 0.0).n_segments(1000), 15);
        assert_eq!(with(100, 0.75).noverlap(), 75);
        assert_eq!(with(10, 0.25).noverlap(), 3, "2.5 rounds away from zero");
        assert_eq!(with(64, 0.5).n_segments(63), 0);
        assert_eq!(with(64, 0.5).n_segments(64), 1);
    }

    #[test]
    fn every_bad_setting_is_refused_with_its_numbers() {
        for n in [0, 6, 7, 9, 4097] {
            assert_eq!(
                with(n, 0.5).validate(10_000),
                Err(SpectralError::BadSegmentLen { segment_len: n })
            );
        }
        for overlap in [-0.1, 1.0, 1.5, f64::NAN, f64::INFINITY, 0.95] {
            let err = with(8, overlap).validate(10_000).unwrap_err();
            assert!(
                matches!(err, SpectralError::BadOverlap { segment_len: 8, .. }),
                "{overlap}: {err}"
            );
        }
        let err = with(256, 0.5).validate(255).unwrap_err();
        assert_eq!(
            err,
            SpectralError::TooFewSamples {
                n_samples: 255,
                segment_len: 256
            }
        );
        let msg = err.to_string();
        assert!(msg.contains("255") && msg.contains("256"), "{msg}");
        assert_eq!(with(8, 0.9).validate(8), Ok(()));
        assert_eq!(with(8, 0.0).validate(8), Ok(()));
    }
}
