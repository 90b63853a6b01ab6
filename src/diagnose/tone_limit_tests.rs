use super::*;

fn limit() -> ToneLimit {
    ToneLimit {
        chi2_needed: 70.0,
        frequency_hz: vec![1.0, 2.0, 3.0, 4.0],
        amplitude: vec![[1.0, 2.0, 3.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [9.0, 1.0, 1.0]],
        input_lines_hz: Vec::new(),
    }
}

/// The limit is read at the nearest point inside the searched range and nowhere outside it (a
/// frequency above the search's top has no limit: nothing was searched there).
#[test]
fn the_limit_is_read_inside_the_searched_range_only() {
    let l = limit();
    assert_eq!(l.at(2.4), Some([1.0, 1.0, 1.0]));
    assert_eq!(l.at(2.6), Some([2.0, 2.0, 2.0]));
    assert_eq!(l.at(4.0), Some([9.0, 1.0, 1.0]));
    assert_eq!(l.at(0.99), None);
    assert_eq!(l.at(4.01), None);
    let empty = ToneLimit {
        frequency_hz: Vec::new(),
        amplitude: Vec::new(),
        ..l
    };
    assert_eq!(empty.at(2.0), None);
}

/// The words give the median over points and outputs (the upper median of the 12 values: 2.0),
/// the largest with its frequency and its ratio to the median, the unit and the top searched.
#[test]
fn the_words_give_the_median_the_largest_and_the_top() {
    let w = limit().words(Block::Accel);
    assert!(w.contains("2.00e0 m/s^2 (the median over 1.00-4.00 Hz"), "{w}");
    assert!(w.contains("9.00e0 m/s^2 at 4.0 Hz (4 times the median)"), "{w}");
    assert!(
        w.contains("chi2 70.0 needed") && w.contains("above 4.0 Hz"),
        "{w}"
    );
    assert!(w.contains("none stated below 1.00 Hz"), "{w}");
    assert!(!w.contains("inputs' own lines"), "{w}");
    // The inputs' own lines, where no tone is named, are listed.
    let with_lines = ToneLimit {
        input_lines_hz: vec![2.3, 7.2],
        ..limit()
    };
    let w = with_lines.words(Block::Accel);
    assert!(
        w.contains("none named at the inputs' own lines (2.30, 7.20 Hz: e.g. a stand programme's sines"),
        "{w}"
    );
    assert!(limit().words(Block::Gyro).contains("rad/s"));
}
