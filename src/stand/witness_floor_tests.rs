use num_complex::Complex64;

use super::*;
use crate::fourier::fast_len;
use crate::rng::Rng;

/// White rates of known variance read their variance as the floor, on each axis.
#[test]
fn white_rates_read_their_variance() {
    let (n, rate) = (60_000, 500.0);
    let mut rng = Rng::new(11);
    let sd = [0.01, 0.02, 0.005];
    let rates = sd.map(|s| (0..n).map(|_| s * rng.normal()).collect::<Vec<f64>>());
    let mut fft = RecordFft::new(fast_len(n), rate);
    let floor = WitnessFloor::of_rates(&rates, &mut fft, 3.0 * n as f64 / 8.0).expect("a floor");
    for (level, s) in floor.rate_level.iter().zip(sd) {
        let rel = level / (s * s) - 1.0;
        // The median over ~4500 correlated bins: a few percent.
        assert!(rel.abs() < 0.05, "level {level} against {}", s * s);
    }
}

/// The angle units follow the trapezoid integration: `1 / (2 pi f)` at low frequency, 0 at Nyquist.
#[test]
fn angle_units_follow_the_trapezoid_rule() {
    let floor = WitnessFloor {
        rate_level: [1.0, 4.0, 0.0],
        sample_rate_hz: 1000.0,
        top_hz: 40.0,
    };
    let at_one = floor.in_angle_units(1.0);
    let want = 1.0 / (2.0 * PI).powi(2);
    assert!((at_one[0] / want - 1.0).abs() < 1e-5, "{at_one:?}");
    assert!((at_one[1] / (4.0 * want) - 1.0).abs() < 1e-5);
    assert!(at_one[2].abs() < f64::MIN_POSITIVE, "{at_one:?}");
    // Brute force: the trapezoid rule's gain at 200 Hz, |(1 + z^-1) / (1 - z^-1)| / (2 fs).
    let z = Complex64::from_polar(1.0, -2.0 * PI * 200.0 / 1000.0);
    let gain = ((Complex64::from(1.0) + z) / (Complex64::from(1.0) - z)).norm() / 2000.0;
    assert!((floor.in_angle_units(200.0)[0] / (gain * gain) - 1.0).abs() < 1e-9);
    assert!(floor.in_angle_units(499.999_999)[0] < 1e-18);
}

/// A record with no bins near Nyquist (or none at all) has no floor.
#[test]
fn no_floor_without_the_top_bins() {
    let mut fft = RecordFft::new(4, 100.0);
    let rates = [vec![1.0, -1.0], vec![0.5, 0.5], vec![0.0, 0.0]];
    assert_eq!(WitnessFloor::of_rates(&rates, &mut fft, 0.75), None);
}
