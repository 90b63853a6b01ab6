//! Significant candidates the search did not name, and why.
//!
//! A candidate that pays the criterion (its `chi2` gain above BIC plus the look-elsewhere cost)
//! is still not a finding when it fails one of the search's other rules (README, "The missing-
//! effect workflow", items 5-6): it must be within reach of the data (a resonance inside the
//! band, not at an edge, damped at most 0.5), a fit with it must be found, and it must close the
//! gap and open it nowhere (the three channels' residual power shrinks, no channel's gap grows
//! beyond the refit's numerical noise). Until 29 Nov such a candidate stayed in the first round's
//! list only, and a run whose strongest evidence the rules refused read `no_missing_effect` with
//! nothing said: a true mount resonance beside strong coloured angle noise (cruise, seed 21,
//! 120 s) gained 1011 and was refused for opening one channel's gap by 0.013 dB while closing the
//! worst's by 0.84 dB. Each refusal is now kept (the last round's, per effect, for effects never
//! named: a resonance refused on one axis and named on another is not kept) and said: a warning
//! where it may hide the block's strongest effect ([`is_warning`]), a note otherwise. Effects the
//! band below did not confirm are said by [`super::noisy_angles`], not here. (The real
//! recordings: notes of a first-order lag that would make the residual power grow, the optical
//! reference's band limit.)
//!
//! Gaps are in dB (band power of the residual over the measured output's, per channel); a gain
//! is in `chi2` units. The gaps are floored at -300 dB, never NaN; a candidate with no fit is
//! [`Reason::FitFailed`].

use serde::{Deserialize, Serialize};

use super::rules::MAX_RESONANCE_DAMPING;
use crate::effect::Effect;

/// One significant candidate not named.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NotNamed {
    /// The catalogue entry (its id in JSON).
    pub effect: Effect,
    /// Its criterion gain in the round it was refused (positive: significant).
    pub criterion_gain: f64,
    /// Why it is not a finding.
    pub reason: Reason,
}

/// Why a significant candidate is not a finding.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Reason {
    /// A resonance within 3 % of a band edge or damped above 0.5: beyond what the data can show.
    OutOfReach {
        /// The mode's fitted frequency, Hz.
        frequency_hz: f64,
        /// Its fitted damping ratio.
        damping: f64,
    },
    /// No fit with the effect was found (no solvable point of its parameters).
    FitFailed,
    /// The residual power of the three channels together does not shrink.
    TotalGrows {
        /// Before, dB.
        before_db: f64,
        /// With the effect, dB.
        after_db: f64,
    },
    /// One channel's gap grows (the total shrinks): the effect trades one channel's bins for
    /// another's, or its refit moves the shared gain and delay against that channel.
    OpensGap {
        /// The output channel whose gap grows most (`gx`, ..., `az`).
        channel: String,
        /// Its gap before, dB.
        before_db: f64,
        /// With the effect, dB.
        after_db: f64,
        /// The worst channel's gap before, dB.
        worst_before_db: f64,
        /// With the effect, dB.
        worst_after_db: f64,
    },
    /// A stand-side effect found on one block that makes the other block's fit worse: both see
    /// the same angles, so it is not the stand's.
    OtherBlockDisagrees {
        /// The other block (`gyro`, `accel`).
        block: String,
        /// The other block's `chi2` gain with it (negative: worse).
        delta_chi2: f64,
    },
}

impl Reason {
    /// Whether the candidate was set aside by a tolerance of the rules (a gap opened, the total
    /// residual power not shrinking), which an engineer may overrule by accepting it; a mode out
    /// of reach or a failed fit would not be added to a model either ([`super::extend`]).
    #[must_use]
    pub fn may_be_accepted(&self) -> bool {
        matches!(self, Self::OpensGap { .. } | Self::TotalGrows { .. })
    }
}

/// Records a refusal in `kept` (with its round): the first (strongest) of an effect in a round
/// stands for it; a later round's replaces an earlier one's (it was tried against the fuller
/// model).
pub(super) fn record(kept: &mut Vec<(usize, NotNamed)>, round: usize, entry: NotNamed) {
    match kept.iter_mut().find(|(_, r)| r.effect == entry.effect) {
        Some((at, r)) if *at < round => (*at, *r) = (round, entry),
        Some(_) => {}
        None => kept.push((round, entry)),
    }
}

/// Whether a refusal may hide an effect stronger than the findings: a gap opened (the total
/// shrinking), which rests on a tolerance (the refit's numerical noise) that a true effect whose
/// refit moves the shared gain and delay a little against another channel fails; or, where
/// something was named, a lightly damped mode (damping at most [`MAX_RESONANCE_DAMPING`]) at the
/// band's edge, a peak the band cuts, of which the findings may be partial fits. (Where nothing
/// was named, a mode at the edge is a note: the fit parks one there for any misfit beyond the
/// band.) The other refusals are the data's: a fit that explains less of the outputs' power than
/// before (its gain rests on the noise weights), a mode damped beyond a peak (a gentle roll-off).
fn may_hide(reason: &Reason, anything_named: bool) -> bool {
    match reason {
        Reason::OpensGap { .. } => true,
        Reason::OutOfReach { damping, .. } => anything_named && *damping <= MAX_RESONANCE_DAMPING,
        Reason::FitFailed | Reason::TotalGrows { .. } | Reason::OtherBlockDisagrees { .. } => false,
    }
}

/// Whether the refusals are a warning: one that may hide an effect (a gap opened; a lightly
/// damped mode at the band's edge beside findings) refused evidence stronger than every finding
/// named on the block (`weakest_named_gain` is `None` when nothing was named). On two runs with
/// a true 30 Hz mount resonance (turbulent cruise, 0.1 mrad coloured angle noise) the band found
/// ends at 28.6 Hz, the mode fits at its edge (gain 10 000-11 400, damping 0.07-0.08) and a
/// g-sensitivity and a lag were named in its place; searched over 0.1-40 Hz, the mode is named.
#[must_use]
pub fn is_warning(not_named: &[NotNamed], weakest_named_gain: Option<f64>) -> bool {
    not_named.iter().any(|r| {
        may_hide(&r.reason, weakest_named_gain.is_some())
            && weakest_named_gain.is_none_or(|weakest| r.criterion_gain > weakest)
    })
}

/// The refusals in the lab's words, for the command line, the app and the certificate; `None`
/// when there are none. `band_hz` is the band searched.
#[must_use]
pub fn words(not_named: &[NotNamed], block_name: &str, band_hz: [f64; 2]) -> Option<String> {
    if not_named.is_empty() {
        return None;
    }
    let each: Vec<String> = not_named
        .iter()
        .map(|r| {
            let why = match &r.reason {
                Reason::OutOfReach { frequency_hz, damping } if *damping > MAX_RESONANCE_DAMPING => format!(
                    "fitted at {frequency_hz:.2} Hz, damping {damping:.2}: damped beyond a peak, the data cannot tell \
                     it from a gentle roll-off"
                ),
                Reason::OutOfReach { frequency_hz, damping } => format!(
                    "fitted at {frequency_hz:.2} Hz, damping {damping:.2}, at the edge of the band searched \
                     ({:.2}-{:.2} Hz), where a mode cannot be told from a misfit beyond the band: a peak there \
                     is cut, and the findings named may be partial fits of it (band_hz wider tests it)",
                    band_hz[0], band_hz[1]
                ),
                Reason::FitFailed => "no fit with it was found".to_owned(),
                Reason::OtherBlockDisagrees { block, delta_chi2 } => format!(
                    "the same band limit makes the {block} block's fit worse (chi2 {delta_chi2:+.1}), and both \
                     blocks see the same angles: not the stand's (a misfit of this form on this block alone)"
                ),
                Reason::TotalGrows { before_db, after_db } => format!(
                    "the three channels' residual power would not shrink ({before_db:.3} -> {after_db:.3} dB): its chi2 \
                     gain rests on the noise weights, not on explaining the outputs"
                ),
                Reason::OpensGap {
                    channel,
                    before_db,
                    after_db,
                    worst_before_db,
                    worst_after_db,
                } => format!(
                    "it would open {channel}'s gap ({before_db:.3} -> {after_db:.3} dB) while the worst channel's goes \
                     {worst_before_db:.2} -> {worst_after_db:.2} dB, and a finding must open the gap nowhere"
                ),
            };
            format!("{} (gain {:.1}): {why}", r.effect.id(), r.criterion_gain)
        })
        .collect();
    Some(format!(
        "{block_name} block: significant but not named (the search's rules, README \"The missing-effect workflow\"): {}",
        each.join("; ")
    ))
}

#[cfg(test)]
mod tests {
    use super::{NotNamed, Reason, is_warning, record, words};
    use crate::effect::Effect;

    fn opens(gain: f64) -> NotNamed {
        NotNamed {
            effect: Effect::PlatformResonance,
            criterion_gain: gain,
            reason: Reason::OpensGap {
                channel: "gy".to_owned(),
                before_db: -6.4546,
                after_db: -6.4419,
                worst_before_db: -2.90,
                worst_after_db: -3.75,
            },
        }
    }

    #[test]
    fn a_later_round_replaces_and_a_weaker_one_of_the_same_round_does_not() {
        let mut kept = Vec::new();
        record(&mut kept, 0, opens(1011.0));
        record(&mut kept, 0, opens(3.0));
        assert_eq!(kept.len(), 1);
        assert!((kept[0].1.criterion_gain - 1011.0).abs() < 1e-12);
        record(&mut kept, 2, opens(891.0));
        assert_eq!(kept[0].0, 2);
        assert!((kept[0].1.criterion_gain - 891.0).abs() < 1e-12);
        let lag = NotNamed {
            effect: Effect::SensorLag,
            criterion_gain: 7.9,
            reason: Reason::FitFailed,
        };
        record(&mut kept, 1, lag);
        assert_eq!(kept.len(), 2);
    }

    #[test]
    fn what_may_hide_an_effect_stronger_than_the_findings_is_a_warning() {
        let refused = [opens(1011.0)];
        assert!(is_warning(&refused, None));
        assert!(is_warning(&refused, Some(500.0)));
        assert!(!is_warning(&refused, Some(2000.0)));
        assert!(!is_warning(&[], None));
        let grows = NotNamed {
            effect: Effect::SensorLag,
            criterion_gain: 204.7,
            reason: Reason::TotalGrows {
                before_db: -23.145,
                after_db: -23.072,
            },
        };
        assert!(!is_warning(&[grows], Some(31.3)));
        let edge = |damping| NotNamed {
            effect: Effect::PlatformResonance,
            criterion_gain: 10_011.0,
            reason: Reason::OutOfReach {
                frequency_hz: 28.08,
                damping,
            },
        };
        assert!(is_warning(&[edge(0.08)], Some(1354.0)));
        assert!(!is_warning(&[edge(0.81)], Some(1354.0)));
        assert!(!is_warning(&[edge(0.08)], Some(20_000.0)));
        // Nothing named: a mode parked at the edge is a note.
        assert!(!is_warning(&[edge(0.08)], None));
    }

    #[test]
    fn the_words_name_the_effect_the_channel_and_the_rule() {
        assert_eq!(words(&[], "gyro", [0.1, 40.0]), None);
        let said = words(&[opens(1011.0)], "gyro", [0.1, 40.0]).unwrap_or_default();
        assert!(
            said.starts_with("gyro block: significant but not named"),
            "{said}"
        );
        assert!(said.contains("platform_resonance (gain 1011.0)"), "{said}");
        assert!(said.contains("open gy's gap (-6.455 -> -6.442 dB)"), "{said}");
        assert!(said.contains("-2.90 -> -3.75 dB"), "{said}");
        let edge = |frequency_hz, damping| NotNamed {
            effect: Effect::PlatformResonance,
            criterion_gain: 40.0,
            reason: Reason::OutOfReach {
                frequency_hz,
                damping,
            },
        };
        let said = words(&[edge(39.99, 0.81)], "accel", [0.1, 40.0]).unwrap_or_default();
        assert!(
            said.contains("39.99 Hz, damping 0.81: damped beyond a peak"),
            "{said}"
        );
        let said = words(&[edge(28.08, 0.08)], "gyro", [0.1, 28.9]).unwrap_or_default();
        assert!(
            said.contains("at the edge of the band searched (0.10-28.90 Hz)"),
            "{said}"
        );
    }

    #[test]
    fn a_band_limit_the_other_block_refuses_is_said_and_no_warning() {
        let refused = NotNamed {
            effect: Effect::ReferenceBandLimit,
            criterion_gain: 2.2,
            reason: Reason::OtherBlockDisagrees {
                block: "gyro".to_owned(),
                delta_chi2: -812.4,
            },
        };
        let said = words(std::slice::from_ref(&refused), "accel", [0.1, 40.0]).unwrap_or_default();
        assert!(
            said.contains("reference_band_limit (gain 2.2): the same band limit makes the gyro block's fit worse (chi2 -812.4)"),
            "{said}"
        );
        assert!(!is_warning(std::slice::from_ref(&refused), None));
        assert!(!refused.reason.may_be_accepted());
    }
}
