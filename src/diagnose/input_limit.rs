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
//! raises it; neither turns the phase. No effect of the catalogue changes the gain across the
//! band without a phase of its own: a lag, a resonance, a clock drift or a skew turn the phase,
//! a vibration tone is not coherent with the input, and a memoryless nonlinearity's linear part
//! is one gain at every frequency for Gaussian motion (Bussgang). So when the order-0 fit over
//! the search band finds an even gain change (the identifier's `gain_changes_across_band`, its
//! rise beyond its own deviation and moving `K` by more than `K`'s deviation) **and** the usable
//! band ends below the band's top, the loss of coherence at the top is the inputs': with
//! `band_hz: "auto"` the diagnosis's band ends at the usable band's top, and the report says so
//! ([`InputLimit`]). A band the user gives is kept as given, and the report says where inside it
//! the inputs are not the motion. The band's bottom is kept: the outputs' own low-frequency
//! noise (a gyro's `1/f`) lowers the coherence there too, and it is the block's.
//!
//! Units: Hz; the gain change is relative (`-0.9`: the gain falls by 90 % across the band).

use serde::{Deserialize, Serialize};

use crate::ident::band::{native_bins, usable_band};
use crate::ident::identify::BlockIdentification;
use crate::ident::warnings::IdentWarning;

/// Where the inputs from the angles are not the motion, at the top of the band the diagnosis was
/// asked to search.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputLimit {
    /// The band asked for, Hz (the auto band's search limits, or the user's band).
    pub searched_hz: [f64; 2],
    /// The usable band's top inside it, Hz: the last bin whose coherence says the inputs are
    /// the motion's.
    pub usable_top_hz: f64,
    /// `[first, last]` bin frequency above the usable band's top, up to the band's top, Hz: the
    /// outputs' coherence with the inputs below the usable band's threshold there.
    pub untrusted_hz: [f64; 2],
    /// The gain's relative change across the searched band with no phase of its own (the even
    /// gain of the order-0 fit), and its standard deviation.
    pub gain_change: f64,
    /// Standard deviation of `gain_change`.
    pub gain_change_std: f64,
    /// Whether the diagnosis's band was ended below `untrusted_hz` (the auto band); `false`: the
    /// user's band was kept as given.
    pub band_ended: bool,
}

/// The input limit of `b`, identified (order 0) over `searched_hz`; `given`: the band is the
/// user's (kept as given). `None` when the order-0 fit shows no even gain change, when the
/// usable band reaches the band's top, or when no band is usable at all (nothing then tells the
/// inputs' loss from the block's).
#[must_use]
pub fn input_limit(b: &BlockIdentification, searched_hz: [f64; 2], given: bool) -> Option<InputLimit> {
    let (gain_change, gain_change_std) = b.warnings.iter().find_map(|w| match w {
        IdentWarning::GainChangesAcrossBand { rise, rise_std, .. } => Some((*rise, *rise_std)),
        _ => None,
    })?;
    let top = usable_band(&b.spectra, searched_hz)?[1];
    let f = &b.spectra.frequency_hz;
    let above: Vec<f64> = native_bins(&b.spectra, searched_hz)
        .into_iter()
        .map(|k| f[k])
        .filter(|&x| x > top)
        .collect();
    let (&first, &last) = (above.first()?, above.last()?);
    Some(InputLimit {
        searched_hz,
        usable_top_hz: top,
        untrusted_hz: [first, last],
        gain_change,
        gain_change_std,
        band_ended: !given,
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
             with no phase of its own, the mark of the angles' noise or band limit (the reference's), not of the block"
        );
        if self.band_ended {
            format!(
                "{block_name} block: the diagnosis searched {:.2}-{:.2} Hz, not up to {:.1} Hz: above, {why}; a \
                 comparison there says nothing about the block (give band_hz to search there anyway)",
                self.searched_hz[0], self.usable_top_hz, self.searched_hz[1]
            )
        } else {
            format!(
                "{block_name} block: in {lo:.2}-{hi:.2} Hz of the given band {why}; findings there may be the \
                 reference's (band_hz \"auto\" leaves that part out)"
            )
        }
    }
}
