//! A block's output channel that never moves: one value over every sample analysed (a dead or
//! disconnected sensor axis, a channel the logger never wrote, a stuck register). Nothing of the
//! block's response is in it, and the estimate cannot be formed without it: the channel's row of
//! the noise weights is infinite and its spectral density zero. Before this check such a run
//! failed deep in the fit ("row weight of output 2 at bin 0 is not finite", exit status 1, as if
//! the program were at fault) and `inspect` passed it. Now the block is refused with the channels
//! named ([`IdentError::DeadOutput`]), the run's other blocks are identified, and the gyro's
//! outputs are not the observer's witness of the angle noise (a flat channel would read every
//! motion of its axis as angle noise).
//!
//! Contract: the columns as the loader gives them (finite); an empty column is not dead (the
//! span's own checks refuse it).

use std::ops::Range;

use super::IdentError;
use super::signals::{BlockSignals, channel_names};

/// Most of a channel's samples that may differ from their predecessor for it to count as dead:
/// one in a hundred. A moving sensor's output changes nearly every sample (its noise alone does,
/// at any quantisation a certification uses); a dead one holds its value, and the few samples
/// of a spike or two (two changes each) do not make it move (one spike of 0.5 in a channel of
/// zeros passed an "every sample equal" test: the gyro was identified with `K[gz][wz]` 0.0015
/// and the accelerometer used the flat gyro as its witness).
const MOVING_SHARE: f64 = 0.01;

/// The value `column` holds for its longest run of equal samples, when it changes from one sample
/// to the next at no more than [`MOVING_SHARE`] of its samples (a dead channel, spikes and all);
/// `None` when it moves, or is empty. One pass, no copy.
#[must_use]
pub fn held_value(column: &[f64]) -> Option<f64> {
    let first = *column.first()?;
    let (mut changes, mut run, mut longest, mut held, mut value) = (0_usize, 1_usize, 0_usize, first, first);
    for pair in column.windows(2) {
        if (pair[1] - pair[0]).abs() > 0.0 {
            changes += 1;
            if run > longest {
                (longest, held) = (run, value);
            }
            (run, value) = (1, pair[1]);
        } else {
            run += 1;
        }
    }
    if run > longest {
        held = value;
    }
    (changes as f64 <= MOVING_SHARE * column.len() as f64).then_some(held)
}

/// Whether `column` moves ([`held_value`] finds no held value; an empty column counts as moving:
/// nothing to say).
#[must_use]
pub fn moves(column: &[f64]) -> bool {
    held_value(column).is_none()
}

/// The refusal of `signals`' block when an output channel is dead over `span` ([`held_value`]),
/// naming each such channel with the value it holds; `None` when every channel moves.
#[must_use]
pub fn dead_output(signals: &BlockSignals, span: &Range<usize>) -> Option<IdentError> {
    let names = channel_names(signals.block).1;
    let channels: Vec<(&'static str, f64)> = signals
        .output
        .iter()
        .zip(names)
        .filter_map(|(c, name)| held_value(c.get(span.clone())?).map(|v| (name, v)))
        .collect();
    (!channels.is_empty()).then(|| IdentError::DeadOutput {
        block: signals.block.name(),
        channels,
        others: true,
    })
}

/// The channels of [`IdentError::DeadOutput`] in words: `output gz (always 0) never moves`,
/// `outputs gy (always 0.0123) and gz (always 0) never move`.
#[must_use]
pub fn channel_words(channels: &[(&'static str, f64)]) -> String {
    let (noun, verb) = if channels.len() == 1 {
        ("output", "moves")
    } else {
        ("outputs", "move")
    };
    let each: Vec<String> = channels
        .iter()
        .map(|(name, value)| format!("{name} (always {value})"))
        .collect();
    let list = match each.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => each.concat(),
    };
    format!("{noun} {list} never {verb}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::block::Block;

    fn signals(output: [Vec<f64>; 3]) -> BlockSignals {
        BlockSignals {
            block: Block::Gyro,
            input: [vec![0.1, 0.2, 0.3], vec![0.3, 0.1, 0.2], vec![0.2, 0.3, 0.1]],
            output,
        }
    }

    #[test]
    fn a_flat_channel_is_named_with_its_value_and_a_moving_one_is_not() {
        let moving = vec![0.1, 0.2, 0.1];
        // One sample off by the smallest step still moves.
        let barely = vec![0.5, 0.5, f64::from_bits(0.5_f64.to_bits() + 1)];
        assert!(
            dead_output(
                &signals([moving.clone(), barely.clone(), moving.clone()]),
                &(0..3)
            )
            .is_none()
        );
        let Some(IdentError::DeadOutput {
            block,
            channels,
            others,
        }) = dead_output(&signals([moving.clone(), vec![0.0123; 3], vec![0.0; 3]]), &(0..3))
        else {
            panic!("a flat channel must refuse the block");
        };
        assert_eq!((block, others), ("gyro", true));
        assert_eq!(channels.len(), 2);
        assert_eq!(channels[0].0, "gy");
        assert_eq!(channels[0].1.to_bits(), 0.0123_f64.to_bits());
        assert_eq!(channels[1].0, "gz");
        assert_eq!(
            channel_words(&channels),
            "outputs gy (always 0.0123) and gz (always 0) never move"
        );
        assert!(moves(&[]), "nothing to say of an empty column");
        // A dead channel with a spike in it is dead; one that changes at 2 % of its samples moves.
        let mut spiked = vec![0.0; 1000];
        spiked[500] = 0.5;
        assert_eq!(held_value(&spiked).map(f64::to_bits), Some(0.0_f64.to_bits()));
        let steps: Vec<f64> = (0..1000).map(|i| f64::from(i / 50)).collect();
        assert!(moves(&steps), "20 changes in 1000 samples");
        let rare: Vec<f64> = (0..1000).map(|i| f64::from(i / 200)).collect();
        assert_eq!(
            held_value(&rare).map(f64::to_bits),
            Some(0.0_f64.to_bits()),
            "the longest run's value"
        );
        // Over a span: flat inside it, moving outside.
        let mut partly = moving.clone();
        partly.extend([0.3; 3]);
        let s = signals([partly.clone(), partly.clone(), partly]);
        assert!(dead_output(&s, &(0..3)).is_none());
        assert!(dead_output(&s, &(3..6)).is_some());
        assert_eq!(channel_words(&channels[1..]), "output gz (always 0) never moves");
    }

    #[test]
    fn the_refusal_names_the_channels_and_is_the_user_s_input() {
        let e = dead_output(&signals([vec![1.0; 3], vec![2.0; 3], vec![3.0; 3]]), &(0..3)).expect("all flat");
        let words = e.to_string();
        assert!(
            words.starts_with(
                "gyro block: outputs gx (always 1), gy (always 2) and gz (always 3) never move over"
            ),
            "{words}"
        );
        assert!(words.contains("leave this block out"), "{words}");
        assert!(!e.clone().alone().to_string().contains("leave this block out"));
        assert!(e.is_refusal() && e.is_input_error());
    }
}
