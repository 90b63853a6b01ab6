//! Findings whose evidence lies where the angles are mostly their noise.
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
//! on the angle-noise model, and one named without confirmation (no band below of
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
//! findings 127 -> 127. Only where the angles have a noisy range: a block whose coherence ends
//! low while the angles' SNR stays above pi to the top (its own sensor noise above little
//! motion, say) is not asked to confirm anything; and where that coherence leaves fewer than
//! [`MIN_BELOW_BINS`] below, its smooth findings are named unconfirmed, said as a warning.
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

/// Where the angles are mostly their noise, up to the band's top.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoisyAngles {
    /// The low edge of the first of the noise model's bands from which up the angles' SNR
    /// (median of the axes) stays below [`MIN_ANGLE_SNR`], Hz.
    pub from_hz: f64,
    /// The SNR's median over the bands from `from_hz` to the band's top.
    pub snr: f64,
    /// The last bin below the range where the block's outputs are not coherent with its inputs
    /// up to the band's top (`ident::band::untrusted_to_top`, as the input limit's
    /// `usable_top_hz`), where it lies below `from_hz`, Hz: the band below ends there
    /// ([`NoisyAngles::below_top_hz`]). Absent where there is no such range or it lies at or above
    /// `from_hz`.
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
pub fn noisy_angles_range(snr: &[([f64; 2], [f64; 3])], searched_hz: [f64; 2]) -> Option<NoisyAngles> {
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
    Some(NoisyAngles {
        // Noisy from the first band inside: from the search's bottom.
        from_hz: if first == 0 { searched_hz[0] } else { noisy[0].0 },
        snr: super::tone::median(&mut values),
        usable_top_hz: None,
        set_aside: Vec::new(),
        unconfirmed: Vec::new(),
    })
}

/// Whether a candidate of `effect` must be confirmed below the noisy range: not a tone (a line,
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
    /// The range with the block's own usable top: `usable_top_hz` (where its outputs are last
    /// coherent with its inputs below a range that reaches the band's top) kept where it lies
    /// below `from_hz`.
    #[must_use]
    pub fn with_usable_top(self, usable_top_hz: Option<f64>) -> Self {
        Self {
            usable_top_hz: usable_top_hz.filter(|f| *f < self.from_hz),
            ..self
        }
    }

    /// The top of the band below, where a smooth finding must be confirmed: the lower of where
    /// the angles are mostly their noise and where the block's outputs are last coherent with
    /// its inputs (module docs).
    #[must_use]
    pub fn below_top_hz(&self) -> f64 {
        self.usable_top_hz.map_or(self.from_hz, |f| f.min(self.from_hz))
    }

    /// Whether the words are a warning (a finding named without confirmation) rather than a note.
    #[must_use]
    pub fn is_warning(&self) -> bool {
        !self.unconfirmed.is_empty()
    }

    /// The range in the lab's words, for the command line, the app and the certificate; `None`
    /// where nothing was set aside and every smooth finding was confirmed.
    #[must_use]
    pub fn words(&self, block_name: &str) -> Option<String> {
        let range = format!(
            "{block_name} block: from {:.1} Hz the angles are mostly their noise (their signal-to-noise ratio by the noise \
             model, median of the axes, {:.2} there, below {MIN_ANGLE_SNR:.2}), and the inputs computed from them hold the \
             motion only as well as that model is known",
            self.from_hz, self.snr
        );
        let range = match self.usable_top_hz {
            Some(f) => format!(
                "{range}; this block's outputs are coherent with its inputs only up to {f:.1} Hz, and the band below, \
                 where a smooth finding must be confirmed, ends there"
            ),
            None => range,
        };
        let ids = |effects: &[Effect]| effects.iter().map(|e| e.id()).collect::<Vec<_>>().join(", ");
        let mut said = Vec::new();
        if !self.set_aside.is_empty() {
            said.push(format!(
                "the search found {} significant over the band, but not on the band below (where the inputs are the \
                 motion): not named, as resting on the angle-noise model",
                ids(&self.set_aside)
            ));
        }
        if !self.unconfirmed.is_empty() {
            said.push(format!(
                "{} named without that confirmation (too little of the band lies below, or named after a resonance or a \
                 clock drift the model below cannot follow): it may rest on the angle-noise model",
                ids(&self.unconfirmed)
            ));
        }
        (!said.is_empty()).then(|| format!("{range}; {}", said.join("; ")))
    }
}

#[cfg(test)]
mod tests {
    use super::{MIN_ANGLE_SNR, NoisyAngles, noisy_angles_range};

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
        let mut said = noisy_angles_range(&bands(falling), searched).expect("a range");
        assert_eq!(said.words("gyro"), None);
        said.set_aside = vec![crate::effect::Effect::SensorLag];
        let w = said.words("gyro").expect("words");
        assert!(
            w.starts_with("gyro block: from ") && w.contains("sensor_lag") && w.contains("not named"),
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
        let range = noisy_angles_range(&bands(falling), searched).expect("a range");
        let from = range.from_hz;
        assert!(from > 4.0, "{from}");
        let own = range.clone().with_usable_top(Some(4.0));
        assert_eq!((own.usable_top_hz, own.below_top_hz()), (Some(4.0), 4.0));
        let mut own_words = own;
        own_words.set_aside = vec![crate::effect::Effect::SensorLag];
        let w = own_words.words("accel").expect("words");
        assert!(
            w.contains("coherent with its inputs only up to 4.0 Hz") && w.contains("not named"),
            "{w}"
        );
        for at_or_above in [from, from + 1.0] {
            let kept = range.clone().with_usable_top(Some(at_or_above));
            assert_eq!(kept.usable_top_hz, None);
            assert_eq!(kept.below_top_hz().to_bits(), from.to_bits());
        }
        assert_eq!(
            range.with_usable_top(None).below_top_hz().to_bits(),
            from.to_bits()
        );
        // Noisy from the search's bottom: the range starts there.
        let all = noisy_angles_range(&bands(|_| [0.5; 3]), [0.3, 40.0]).expect("a range");
        assert_eq!(
            all,
            NoisyAngles {
                from_hz: 0.3,
                snr: 0.5,
                usable_top_hz: None,
                set_aside: Vec::new(),
                unconfirmed: Vec::new(),
            }
        );
    }
}
