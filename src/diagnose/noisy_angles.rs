//! Findings whose evidence lies where the inputs may not be the motion: the angles mostly their
//! noise, or the block's outputs no longer coherent with its inputs.
//!
//! The observer undoes the angle noise's attenuation of the inputs with its noise model `N` (the
//! colour of [`crate::stand::colour`]); an error `e N` of that model leaves the regression's gain
//! off by about `e / SNR`, with `SNR` the angles' density over the model's, less one
//! ([`crate::stand::observer::ObserverEstimate::angle_snr`]). The model is a median over the
//! record's stretches of windows of `B` independent bins in all, so `e` has a variance of about
//! `(pi / 2) / B`; the gain's statistical variance over the same bins is
//! `(1 - gamma^2) / (2 B gamma^2) = 1 / (2 B SNR)` where the input noise sets the coherence. The
//! model's error is at most the comparison's statistical error where `SNR >= pi`
//! ([`MIN_ANGLE_SNR`]), on records of any length. The bound covers the model's statistical error
//! only (not its bias: the gyro's own noise taken for the angles'; not a white model read near
//! Nyquist), and the bins' count is the same on both sides only roughly; the measurement backs
//! pi (below).
//!
//! Below pi a smooth error of the model is a smooth change of the gain the size of the noise,
//! which the search fits as a lag, a reference lag or a skew (`tau` takes a lag's phase, its
//! droop is left): a clean 300 s cruise run with 0.2 mrad of coloured angle noise gave the gyro a
//! `sensor_lag` of criterion gain 535 over 0.1-40 Hz, 4 over 0.1-12 Hz, none over 0.1-9 Hz, its
//! angles' SNR (median of the axes) below pi from 9.9 Hz (that lag is one the band below still
//! confirms: the check below removes most such findings, not all). Ending the band there (tried, 29 Nov)
//! removed most such findings but lost true ones far larger than the model's error (a mount
//! resonance at 21-31 Hz named at criterion gains of thousands, a gyro tone at 33 Hz) and handed
//! a resonance's rise to a false `g_sensitivity`. So the band is kept, and a finding must be
//! confirmed where the inputs are the motion: the search keeps, beside its model over the band,
//! the same model over the band below the noisy range ([`Below`]), and a candidate of a smooth
//! effect (every effect but a tone or a resonance, peaks seen where they are, and a clock drift,
//! fitted on the whole band's re-timing: [`asked_below`]) is named only if the same effect
//! is significant there too, by the search's own rule (BIC on that band's degrees of freedom
//! plus the same look-elsewhere cost).
//! One that is not is set aside, and the report says so ([`NoisyAngles::set_aside`]): it rests
//! on the angle-noise model (or on inputs that may not be the motion, below), and one named without confirmation (no band below of
//! [`MIN_BELOW_BINS`], or after a resonance or clock drift the model below cannot follow) is said
//! too ([`NoisyAngles::unconfirmed`]). The test is of significance only, not of agreement with
//! the band's size; an effect whose evidence grows with frequency (a skew as `f`, a lever arm as
//! `f^2`) is confirmed where it is weakest, so a small true one may be set aside (said).
//!
//! The band below ends lower where the block's own outputs stop being coherent with its inputs
//! up to the band's top below the angles' range ([`NoisyAngles::usable_top_hz`], below the
//! untrusted range of `crate::ident::band::untrusted_to_top`): the angles' SNR is the median
//! axis's, and a block's inputs are not the angles themselves (the accelerometer's specific
//! force takes gravity through roll and pitch only, and the lever arm through the angles'
//! second derivatives). On a 120 Hz reference interpolated onto 500 Hz samples with 0.2 mrad of
//! coloured noise (cruise, 120 s), the angles' range began at 9.7-10.8 Hz and the
//! accelerometer's coherence ended at 3.4-4.0 Hz; confirmed below 9.7 Hz, a false `sensor_lag`
//! and `lever_arm_error` were named on three of four clean seeds the rules had not been measured
//! on (10-12; the input limit, which ends the band there on other seeds, had not: the gain's
//! fall moved `K` less than its deviation). Confirmed below the coherence's end they were set
//! aside, and so was a true lag of 3.5-4.7 ms on that reference (four seeds; its droop below
//! 4 Hz is within `K`'s deviation), named on the same reference with 0.05 mrad of noise. On 209
//! campaign runs: clean runs with a finding 9 -> 4 of 45 with coloured angle noise, true
//! findings 127 -> 127.
//!
//! The block's coherence asks the same where the angles have no noisy range
//! ([`confirmation_range`]; `angles` then absent): a block whose outputs stop being coherent
//! with its inputs up to the band's top while the angles' SNR stays above pi there may have
//! inputs that are mostly the angles' noise (its own, not the median axis's), or its own noise
//! may hide the motion; the comparison there cannot tell which, and a smooth finding is
//! confirmed below. Where that coherence leaves fewer than [`MIN_BELOW_BINS`] below, its smooth
//! findings are named unconfirmed, said as a warning.
//!
//! The median over the axes, as the usable band's coherence: two axes that carry the motion keep
//! the range for the outputs they drive. Units: Hz; the ratio is of densities.

use serde::{Deserialize, Serialize};

use super::state::State;
use crate::effect::Effect;

/// Smallest signal-to-noise ratio of the angles (median of the axes) at which the noise model's
/// own error leaves the inputs' gain off by at most the comparison's statistical error (module
/// docs).
pub const MIN_ANGLE_SNR: f64 = std::f64::consts::PI;

/// The angles' noisy range: where their signal-to-noise ratio stays below [`MIN_ANGLE_SNR`] up
/// to the band's top.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AngleRange {
    /// The low edge of the first of the noise model's bands from which up the angles' SNR
    /// (median of the axes) stays below [`MIN_ANGLE_SNR`], Hz.
    pub from_hz: f64,
    /// The SNR's median over the bands from `from_hz` to the band's top.
    pub snr: f64,
}

/// Where the inputs may not be the motion up to the band's top: the angles mostly their noise,
/// or the block's outputs no longer coherent with its inputs (module docs); a smooth finding is
/// confirmed below.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoisyAngles {
    /// The angles' noisy range; absent where their SNR stays above [`MIN_ANGLE_SNR`] to the
    /// band's top and only the block's coherence ends below it (`usable_top_hz` then present).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub angles: Option<AngleRange>,
    /// The last bin below the range where the block's outputs are not coherent with its inputs
    /// up to the band's top (`ident::band::untrusted_to_top`, as the input limit's
    /// `usable_top_hz`), where it lies below the angles' `from_hz` (or there is no such range),
    /// Hz: the band below ends there ([`NoisyAngles::below_top_hz`]). Absent where there is no
    /// such range or it lies at or above `from_hz`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub usable_top_hz: Option<f64>,
    /// The smooth effects the search found significant over the band, which the band below did
    /// not confirm: not named (module docs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub set_aside: Vec<Effect>,
    /// The smooth effects named without confirmation: no band below long enough to fit
    /// ([`MIN_BELOW_BINS`]), or named after a resonance or a clock drift, which the model below
    /// cannot follow.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unconfirmed: Vec<Effect>,
}

/// Where, inside `searched_hz`, the angles' signal-to-noise ratio `snr` (the observer's bands,
/// ascending: [`crate::stand::observer::ObserverEstimate::angle_snr`]) stays below
/// [`MIN_ANGLE_SNR`] (median of the axes) from one band up to the band's top; a band counts when
/// its centre (geometric) lies inside the search. `None` when the top band is clean enough, or
/// no band lies in the search.
#[must_use]
pub fn noisy_angles_range(snr: &[([f64; 2], [f64; 3])], searched_hz: [f64; 2]) -> Option<AngleRange> {
    let inside: Vec<(f64, f64)> = snr
        .iter()
        .filter(|([lo, hi], _)| (searched_hz[0]..=searched_hz[1]).contains(&(lo * hi).sqrt()))
        .map(|([lo, _], v)| (*lo, super::tone::median(&mut v.clone())))
        .collect();
    let first = inside
        .iter()
        .rposition(|(_, m)| *m >= MIN_ANGLE_SNR)
        .map_or(0, |k| k + 1);
    let noisy = inside.get(first..).filter(|r| !r.is_empty())?;
    let mut values: Vec<f64> = noisy.iter().map(|(_, m)| *m).collect();
    Some(AngleRange {
        // Noisy from the first band inside: from the search's bottom.
        from_hz: if first == 0 { searched_hz[0] } else { noisy[0].0 },
        snr: super::tone::median(&mut values),
    })
}

/// Where the band below must end for a block (module docs): at the angles' noisy range
/// `angles`, or lower at `usable_top_hz`, the block's last coherent bin below an untrusted range
/// that reaches the band's top (the caller's: with `angles`, the band's bottom where no bin below
/// is coherent, and the smooth findings are said unconfirmed; without, `None` then, as a block
/// coherent nowhere in a band it was given is not asked); `None` where neither is (nothing to
/// confirm).
#[must_use]
pub fn confirmation_range(angles: Option<AngleRange>, usable_top_hz: Option<f64>) -> Option<NoisyAngles> {
    let usable_top_hz = usable_top_hz.filter(|f| angles.is_none_or(|a| *f < a.from_hz));
    (angles.is_some() || usable_top_hz.is_some()).then(|| NoisyAngles {
        angles,
        usable_top_hz,
        set_aside: Vec::new(),
        unconfirmed: Vec::new(),
    })
}

/// Whether a candidate of `effect` must be confirmed on the band below: not a tone (a line,
/// seen where it is), a resonance (a peak: its frequency may lie above the band below, which
/// then cannot hold it; a campaign on 29 Nov set aside true mount resonances at 25-31 Hz above
/// ranges from 9.7 and 19.3 Hz, and a false `g_sensitivity` took their rise; the search's reach
/// test keeps a resonance off the band's edges and below a damping of 0.5, so it is no smooth
/// error of the model), or a clock drift (its re-timing is fitted on the whole band).
#[must_use]
pub fn asked_below(effect: Effect) -> bool {
    !matches!(
        effect,
        Effect::VibrationTone | Effect::PlatformResonance | Effect::ClockDrift
    )
}

/// Fewest native Welch bins of the band below ([`NoisyAngles::below_top_hz`]; the usable band's least,
/// `ident::band::MIN_BAND_BINS`): fewer confirm nothing, and the findings are said unconfirmed.
pub const MIN_BELOW_BINS: usize = crate::ident::band::MIN_BAND_BINS;

/// The search's model over the band below ([`NoisyAngles::below_top_hz`]), kept beside its model
/// over the band.
#[derive(Clone, Debug)]
pub struct Below {
    /// The model with the findings named so far, fitted on the band below.
    pub state: State,
    /// The band below, Hz.
    pub band_hz: [f64; 2],
    /// Its real degrees of freedom (all three channels): BIC's `n` there.
    pub dof: f64,
}

impl NoisyAngles {
    /// The top of the band below, where a smooth finding must be confirmed: the lower of where
    /// the angles are mostly their noise and where the block's outputs are last coherent with
    /// its inputs (module docs); `None` where neither is known (a report file holding neither).
    #[must_use]
    pub fn below_top_hz(&self) -> Option<f64> {
        match (self.angles, self.usable_top_hz) {
            (Some(a), Some(f)) => Some(f.min(a.from_hz)),
            (Some(a), None) => Some(a.from_hz),
            (None, f) => f,
        }
    }

    /// Whether the words are a warning (a finding named without confirmation) rather than a note.
    #[must_use]
    pub fn is_warning(&self) -> bool {
        !self.unconfirmed.is_empty()
    }

    /// The range in the lab's words, for the command line, the app and the certificate; `None`
    /// where nothing was set aside and every smooth finding was confirmed (or, read from a file,
    /// neither range is given).
    #[must_use]
    pub fn words(&self, block_name: &str) -> Option<String> {
        let (range, resting) = match (self.angles, self.usable_top_hz) {
            (Some(a), top) => {
                let range = format!(
                    "{block_name} block: from {:.1} Hz the angles are mostly their noise (their signal-to-noise ratio by the \
                     noise model, median of the axes, {:.2} there, below {MIN_ANGLE_SNR:.2}), and the inputs computed from \
                     them hold the motion only as well as that model is known",
                    a.from_hz, a.snr
                );
                let range = match top {
                    Some(f) => format!(
                        "{range}; this block's outputs are coherent with its inputs only up to {f:.1} Hz, and the band \
                         below, where a smooth finding must be confirmed, ends there"
                    ),
                    None => range,
                };
                (range, "the angle-noise model")
            }
            (None, Some(f)) => {
                let why = if block_name == "accel" {
                    "the specific force takes gravity through roll and pitch only, and the lever arm through the angles' \
                     second derivatives"
                } else {
                    "the rates are the angles' derivatives, and the median axis does not speak for every axis"
                };
                (
                    format!(
                        "{block_name} block: its outputs are coherent with its inputs only up to {f:.1} Hz; above, the \
                         angles' signal-to-noise ratio stays above {MIN_ANGLE_SNR:.2}, but the inputs computed from them \
                         may still hold their noise more than the motion ({why}), or the block's own noise may hide it, \
                         so a smooth finding must be confirmed below {f:.1} Hz"
                    ),
                    "inputs that may not be the motion",
                )
            }
            (None, None) => return None,
        };
        let ids = |effects: &[Effect]| effects.iter().map(|e| e.id()).collect::<Vec<_>>().join(", ");
        let mut said = Vec::new();
        if !self.set_aside.is_empty() {
            said.push(format!(
                "the search found {} significant over the band, but not on the band below (where the inputs are the \
                 motion): not named, as resting on {resting}",
                ids(&self.set_aside)
            ));
        }
        if !self.unconfirmed.is_empty() {
            said.push(format!(
                "{} named without that confirmation (too little of the band lies below, or named after a resonance or a \
                 clock drift the model below cannot follow): it may rest on {resting}",
                ids(&self.unconfirmed)
            ));
        }
        (!said.is_empty()).then(|| format!("{range}; {}", said.join("; ")))
    }
}

#[cfg(test)]
mod tests {
    use super::{AngleRange, MIN_ANGLE_SNR, NoisyAngles, confirmation_range, noisy_angles_range};

    /// Bands a twentieth of a decade wide from 0.1 Hz, each axis's SNR from `snr(f)`.
    fn bands(snr: impl Fn(f64) -> [f64; 3]) -> Vec<([f64; 2], [f64; 3])> {
        let r = 10.0_f64.powf(0.05);
        (0..70)
            .map(|j| {
                let lo = 0.1 * r.powi(j);
                ([lo, lo * r], snr((lo * lo * r).sqrt()))
            })
            .collect()
    }

    #[test]
    fn the_range_starts_where_the_median_axis_stays_below_pi_up_to_the_top() {
        let searched = [0.1, 40.0];
        // Clean everywhere, or below pi only above the search: nothing.
        assert_eq!(noisy_angles_range(&bands(|_| [50.0; 3]), searched), None);
        assert_eq!(
            noisy_angles_range(&bands(|f| [if f > 45.0 { 0.1 } else { 50.0 }; 3]), searched),
            None
        );
        // A band straddling the search's top counts by its centre: below pi only above 40.5 Hz
        // (the band from 39.8 Hz, centred at 42.2 Hz) is outside.
        assert_eq!(
            noisy_angles_range(&bands(|f| [if f > 40.5 { 0.1 } else { 50.0 }; 3]), searched),
            None
        );
        // A dip inside the band with a clean top is not a range (a line, a notch of the motion).
        let dip = |f: f64| [if (5.0..8.0).contains(&f) { 0.5 } else { 50.0 }; 3];
        assert_eq!(noisy_angles_range(&bands(dip), searched), None);
        // One axis noisy everywhere (a still axis): the median keeps the band; two: it does not.
        assert_eq!(noisy_angles_range(&bands(|_| [0.0, 50.0, 50.0]), searched), None);
        assert_eq!(
            noisy_angles_range(&bands(|_| [0.0, 0.0, 50.0]), searched).map(|r| r.from_hz),
            Some(0.1)
        );
        // Two axes falling as 1/f^4 (the median axis 1000 / f^4), the third clean: the range
        // starts at the low edge of the first band whose centre lies above (1000 / pi)^(1/4) Hz.
        let falling = |f: f64| {
            let v = 1000.0 / f.powi(4);
            [v, 0.5 * v, 1e6]
        };
        let range = noisy_angles_range(&bands(falling), searched).expect("a range");
        let crossing = (1000.0 / MIN_ANGLE_SNR).powf(0.25);
        let half_band = 10.0_f64.powf(0.025);
        assert!(
            crossing / half_band <= range.from_hz && range.from_hz < crossing * half_band,
            "{range:?} vs {crossing}"
        );
        assert!(range.snr < MIN_ANGLE_SNR && range.snr > 0.0, "{range:?}");
        // The words: none where nothing was set aside and every smooth finding was confirmed.
        let angles = noisy_angles_range(&bands(falling), searched);
        let mut said = confirmation_range(angles, None).expect("a range");
        assert_eq!(said.below_top_hz(), angles.map(|a| a.from_hz));
        assert_eq!(said.words("gyro"), None);
        said.set_aside = vec![crate::effect::Effect::SensorLag];
        let w = said.words("gyro").expect("words");
        assert!(
            w.starts_with("gyro block: from ")
                && w.contains("sensor_lag")
                && w.contains("not named, as resting on the angle-noise model"),
            "{w}"
        );
        assert!(!said.is_warning());
        said.unconfirmed = vec![crate::effect::Effect::AxisTimeSkew];
        let w = said.words("gyro").expect("words");
        assert!(
            w.contains("axis_time_skew named without that confirmation"),
            "{w}"
        );
        assert!(said.is_warning());
        // The block's outputs coherent only up to below the range: the band below ends there,
        // and the words say so; at or above it, nothing changes.
        let from = range.from_hz;
        assert!(from > 4.0, "{from}");
        let own = confirmation_range(angles, Some(4.0)).expect("a range");
        assert_eq!((own.usable_top_hz, own.below_top_hz()), (Some(4.0), Some(4.0)));
        let mut own_words = own;
        own_words.set_aside = vec![crate::effect::Effect::SensorLag];
        let w = own_words.words("accel").expect("words");
        assert!(
            w.contains("coherent with its inputs only up to 4.0 Hz") && w.contains("not named"),
            "{w}"
        );
        for at_or_above in [from, from + 1.0] {
            let kept = confirmation_range(angles, Some(at_or_above)).expect("a range");
            assert_eq!(kept.usable_top_hz, None);
            assert_eq!(kept.below_top_hz().map(f64::to_bits), Some(from.to_bits()));
        }
    }

    /// Without a noisy range of the angles, the block's coherence's end alone asks the
    /// confirmation, in words that do not call the angles noise; with neither, nothing is asked.
    #[test]
    fn the_blocks_coherence_alone_ends_the_band_below() {
        assert_eq!(confirmation_range(None, None), None);
        let mut own = confirmation_range(None, Some(3.5)).expect("a range");
        assert_eq!((own.angles, own.below_top_hz()), (None, Some(3.5)));
        assert_eq!(own.words("accel"), None);
        own.set_aside = vec![
            crate::effect::Effect::SensorLag,
            crate::effect::Effect::LeverArmError,
        ];
        let w = own.words("accel").expect("words");
        assert!(
            w.starts_with("accel block: its outputs are coherent with its inputs only up to 3.5 Hz")
                && w.contains("sensor_lag, lever_arm_error significant over the band")
                && w.contains("as resting on inputs that may not be the motion")
                && !w.contains("signal-to-noise ratio by the noise model")
                && w.contains("gravity through roll and pitch"),
            "{w}"
        );
        // Read back from a report: the angles' fields absent, no nulls written.
        let json = serde_json::to_string(&own).expect("serialised");
        assert!(!json.contains("from_hz") && !json.contains("null"), "{json}");
        let back: NoisyAngles = serde_json::from_str(&json).expect("read back");
        assert_eq!(back, own);
        // With the angles' range, its fields sit where they always did (flattened).
        let with = confirmation_range(
            Some(AngleRange {
                from_hz: 9.7,
                snr: 1.2,
            }),
            Some(3.5),
        )
        .expect("a range");
        let value = serde_json::to_value(&with).expect("serialised");
        assert_eq!(value["from_hz"], 9.7);
        assert_eq!(value["usable_top_hz"], 3.5);
        let back: NoisyAngles = serde_json::from_value(value).expect("read back");
        assert_eq!(back, with);
    }

    #[test]
    fn the_search_bottom_starts_a_range_noisy_everywhere() {
        let bands = bands(|_| [0.5; 3]);
        // Noisy from the search's bottom: the range starts there.
        let all = noisy_angles_range(&bands, [0.3, 40.0]).expect("a range");
        assert_eq!(
            all,
            AngleRange {
                from_hz: 0.3,
                snr: 0.5
            }
        );
    }
}
