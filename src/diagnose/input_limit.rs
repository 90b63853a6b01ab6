//! Where the diagnosis's inputs are not the motion.
//!
//! The diagnosis searches the whole band asked for ([`super::prepare`]): a missing effect lowers
//! the coherence of the outputs with the inputs, so the identifier's usable band (where that
//! coherence is high, [`crate::ident::band`]) would hide the very misfit it looks for. But the
//! coherence also falls where the inputs computed from the angles are the angles' noise or are
//! cut by the reference's band limit, and there the comparison of model and measurement says
//! nothing about the block: on a real run with an optical reference (120 Hz, its noise above the
//! hand motion from about 11 Hz), the paper's model fitted over 0.1-40 Hz read `K` 0.88 / 1.00 /
//! 0.85 (against 1.00 within 0.5 % over the usable band), and every cell of the disagreement map
//! was a misfit.
//!
//! The two causes are told apart by the gain. Input noise attenuates the regression's gain where
//! it dominates (errors in variables); a reference smoothed or interpolated from a slower rate
//! raises it; neither turns the phase. A block's own dynamics bend the gain too (below its
//! corner a first-order lag is a delay, which `tau` takes, and an even droop `-(f/f_c)^2 / 2`),
//! but with a phase that the identifier's order selection sees: fitted again over the even gain
//! (`ident::even_gain`), a lag still needs its pole. No other catalogue effect changes the gain
//! across the band (a tone is not coherent with the input; a memoryless nonlinearity's linear
//! part is one gain at every frequency for Gaussian motion, Bussgang). So the inputs' loss is
//! taken to be the angles' when three things hold: the order-0 fit over the band finds the gain
//! falling evenly (the identifier's `gain_changes_across_band`, its rise negative, beyond its own
//! deviation and moving `K` by more than `K`'s deviation: input noise attenuates; a resonance
//! above the band, or a smoothed reference, raises the gain instead), the identifier with its
//! order selection on keeps order 0 over the band (no dynamics of the block's own: `dynamics`
//! below), and the outputs' coherence
//! with the inputs is below the usable band's threshold from some bin up to the band's top
//! ([`crate::ident::band::untrusted_to_top`]). With `band_hz: "auto"` the diagnosis's band then
//! ends below that range, and the report says so ([`InputLimit`]); too few bins below it leave the
//! band as it was, and that is said too. A band the user gives is kept as given, and the report
//! says where inside it the inputs are not the motion. The band's bottom is kept: the outputs'
//! own low-frequency noise (a gyro's `1/f`) lowers the coherence there too, and it is the
//! block's.
//!
//! What an ended band cannot test is said with it: a lag's corner, a resonance or a tone above
//! it (no line is searched above an ended band: the residual there is the model driven by the
//! angles' noise, `super::workflow`); a clock drift is tested on less of its phase.
//!
//! Units: Hz; the gain change is relative (`-0.9`: the gain falls by 90 % across the band).

use serde::{Deserialize, Serialize};

use crate::ident::band::{last_bin_below, untrusted_to_top};
use crate::ident::identify::BlockIdentification;
use crate::ident::warnings::IdentWarning;

/// Where the inputs from the angles are not the motion, at the top of the band the diagnosis was
/// asked to search.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputLimit {
    /// The band asked for, Hz (the auto band's search limits, or the user's band).
    pub searched_hz: [f64; 2],
    /// The last bin below the untrusted range, Hz.
    pub usable_top_hz: f64,
    /// `[first, last]` bin frequency of the range that reaches the band's top with the outputs'
    /// coherence with the inputs below the usable band's threshold, Hz.
    pub untrusted_hz: [f64; 2],
    /// The gain's relative change across the searched band with no phase of its own (the even
    /// gain of the order-0 fit).
    pub gain_change: f64,
    /// Standard deviation of `gain_change`.
    pub gain_change_std: f64,
    /// Whether the diagnosis's band was ended at `usable_top_hz`; `false`: the band asked for was
    /// searched (the user's, or too few bins below the range).
    pub band_ended: bool,
    /// Whether the band was the user's (kept as given).
    #[serde(default)]
    pub given: bool,
}

/// The gain's fall across the band with no phase of its own that the order-0 fit of `b` found
/// (`gain_changes_across_band` with a negative rise, a row of `K` moved by more than `K`'s
/// relative deviation: the warning's `rows_moved`), and its standard deviation; `None` when it
/// found none, or a rise. The warning is said also where only one element moves beyond its own
/// deviation (a precise row beside poor cross-couplings); that does not end the diagnosis's band
/// (on a slow, noisy reference the accelerometer's band then ended at 4 Hz where its noisy range
/// was marked, and 3 of 209 campaign runs' findings changed).
#[must_use]
pub fn falling_gain(b: &BlockIdentification) -> Option<(f64, f64)> {
    b.warnings.iter().find_map(|w| match w {
        IdentWarning::GainChangesAcrossBand {
            rise,
            rise_std,
            rows_moved: true,
            ..
        } if *rise < 0.0 => Some((*rise, *rise_std)),
        _ => None,
    })
}

/// The input limit of `b`, identified (order 0) over `searched_hz`; `given`: the band is the
/// user's (kept as given); `dynamics`: the identifier, its order selection on, chose poles over
/// that band (the gain's change may be the block's own: nothing is said). `None` as well when the
/// order-0 fit shows no even gain change, or no untrusted range reaches the band's top, or
/// nothing below it is trusted.
#[must_use]
pub fn input_limit(
    b: &BlockIdentification,
    searched_hz: [f64; 2],
    given: bool,
    dynamics: bool,
) -> Option<InputLimit> {
    if dynamics {
        return None;
    }
    let (gain_change, gain_change_std) = falling_gain(b)?;
    let untrusted = untrusted_to_top(&b.spectra, searched_hz)?;
    let usable_top_hz = last_bin_below(&b.spectra, searched_hz, untrusted[0])?;
    Some(InputLimit {
        searched_hz,
        usable_top_hz,
        untrusted_hz: untrusted,
        gain_change,
        gain_change_std,
        band_ended: !given,
        given,
    })
}

impl InputLimit {
    /// The diagnosis's band: the searched band, ended at the usable band's top when
    /// `band_ended`.
    #[must_use]
    pub fn band_hz(&self) -> [f64; 2] {
        if self.band_ended {
            [self.searched_hz[0], self.usable_top_hz]
        } else {
            self.searched_hz
        }
    }

    /// Whether the line is a warning (the band searched reaches where the inputs are not the
    /// motion) rather than a note (it was ended below).
    #[must_use]
    pub fn is_warning(&self) -> bool {
        !self.band_ended
    }

    /// The limit in the lab's words, for the command line, the app and the certificate.
    #[must_use]
    pub fn words(&self, block_name: &str) -> String {
        let [lo, hi] = self.untrusted_hz;
        let gain = if self.gain_change >= 0.0 {
            format!("rises by {:.0} %", 100.0 * self.gain_change)
        } else if self.gain_change > -1.0 {
            format!("falls by {:.0} %", -100.0 * self.gain_change)
        } else {
            "falls away".to_owned()
        };
        let why = format!(
            "the outputs are not coherent with the inputs from the angles, and across the band the gain {gain} \
             with no phase of its own, the mark of the angles' noise where the motion is weak (the reference's)"
        );
        if self.band_ended {
            format!(
                "{block_name} block: the diagnosis searched {:.2}-{:.2} Hz, not up to {:.1} Hz: above, {why}, and the \
                 identifier, its order selection on, gives the block no dynamics of its own; a comparison there \
                 says nothing about the block: a lag, resonance or tone above {:.1} Hz cannot be tested on this \
                 run, and a clock drift only on less of its phase (give band_hz to search there anyway)",
                self.searched_hz[0], self.usable_top_hz, self.searched_hz[1], self.usable_top_hz
            )
        } else if self.given {
            format!(
                "{block_name} block: in {lo:.2}-{hi:.2} Hz of the given band {why}; findings there may be the \
                 reference's (band_hz \"auto\" leaves that part out where the block has no dynamics of its own)"
            )
        } else {
            format!(
                "{block_name} block: in {lo:.2}-{hi:.2} Hz {why}, but too few bins lie below it for a diagnosis: \
                 the whole band was searched, and findings there may be the reference's"
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::InputLimit;

    fn limit(band_ended: bool, given: bool) -> InputLimit {
        InputLimit {
            searched_hz: [0.1, 40.0],
            usable_top_hz: 11.16,
            untrusted_hz: [11.23, 39.97],
            gain_change: -0.93,
            gain_change_std: 0.01,
            band_ended,
            given,
        }
    }

    #[test]
    #[expect(
        clippy::float_cmp,
        reason = "the bands are copied, not computed: equal exactly"
    )]
    fn each_case_has_its_words_and_its_band() {
        let ended = limit(true, false);
        assert_eq!(ended.band_hz(), [0.1, 11.16]);
        assert!(!ended.is_warning());
        let w = ended.words("gyro");
        assert!(
            w.starts_with("gyro block: the diagnosis searched 0.10-11.16 Hz, not up to 40.0 Hz"),
            "{w}"
        );
        assert!(
            w.contains("falls by 93 %") && w.contains("cannot be tested"),
            "{w}"
        );
        let given = limit(false, true);
        assert_eq!(given.band_hz(), [0.1, 40.0]);
        assert!(given.is_warning());
        let w = given.words("gyro");
        assert!(
            w.contains("in 11.23-39.97 Hz of the given band") && w.contains("\"auto\""),
            "{w}"
        );
        // The auto band too short below the range: searched whole, and not called the user's.
        let whole = limit(false, false);
        assert_eq!(whole.band_hz(), [0.1, 40.0]);
        assert!(whole.is_warning());
        let w = whole.words("gyro");
        assert!(
            w.contains("the whole band was searched") && !w.contains("given band"),
            "{w}"
        );
        let away = InputLimit {
            gain_change: -1.4,
            ..limit(true, false)
        };
        assert!(away.words("accel").contains("the gain falls away"));
    }
}
