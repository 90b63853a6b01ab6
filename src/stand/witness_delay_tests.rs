use super::*;
use crate::rng::Rng;
use crate::sim::regime::Regime;
use crate::sim::stand::StandImperfections;
use crate::sim::{SimConfig, simulate};

/// [`align_weight`]'s level is the one unrelated signals pass once in a hundred windows: squared
/// coherencies of independent complex Gaussian pairs over `M` bins (brute force, seeded) exceed
/// it in 1 % of 20000 windows (binomial deviation 0.07 %), for `M` of 4, 8 and 16; it gives 0 at
/// and below that level and 1 at full coherence.
#[test]
fn the_alignment_weight_passes_unrelated_signals_once_in_a_hundred() {
    let mut rng = Rng::new(31);
    for m in [4_usize, 8, 16] {
        let trials = 20_000;
        let mut passed = 0;
        for _ in 0..trials {
            let (mut cross, mut pa, mut pb) = (Complex64::default(), 0.0, 0.0);
            for _ in 0..m {
                let a = Complex64::new(rng.normal(), rng.normal());
                let b = Complex64::new(rng.normal(), rng.normal());
                cross += a * b.conj();
                pa += a.norm_sqr();
                pb += b.norm_sqr();
            }
            if align_weight(cross.norm_sqr() / (pa * pb), m as f64) > 0.0 {
                passed += 1;
            }
        }
        let share = f64::from(passed) / f64::from(trials);
        assert!((0.007..0.013).contains(&share), "M = {m}: {share}");
        let c0 = 1.0 - ALIGN_FALSE_ALARM.powf(1.0 / (m as f64 - 1.0));
        assert!(align_weight(c0, m as f64).abs() < 1e-12 && align_weight(0.5 * c0, m as f64) == 0.0);
        assert!((align_weight(1.0, m as f64) - 1.0).abs() < 1e-12);
    }
    assert!(align_weight(0.9, 1.0) == 0.0, "one bin tells nothing");
}

/// On a steady gyro (the simulator's, on a stand with real imperfections) the two halves of a
/// minute give delays whose difference is within its stated deviation (each half's bound,
/// [`align`]): over eight seeds the normalised differences have an rms between 0.5 and 1.6 (a
/// bound far too narrow would read a drift from noise, [`drift`]'s five deviations aside).
#[test]
fn the_delay_s_deviation_is_its_scatter_on_a_steady_gyro() {
    let rate = 500.0;
    let z: Vec<f64> = (1..=8)
        .map(|seed| {
            let mut c = SimConfig::new(Regime::Cruise);
            (c.seed, c.duration_s, c.rate_hz, c.stand) = (seed, 60.0, rate, StandImperfections::real());
            let r = simulate(&c).unwrap();
            let gyro = r.gyro.as_ref().unwrap();
            let half = r.angles[0].len() / 2;
            let [(d0, s0), (d1, s1)] = [0..half, half..2 * half].map(|range| {
                let a = r.angles.each_ref().map(|x| &x[range.clone()]);
                let w = gyro.each_ref().map(|x| &x[range.clone()]);
                let mut fft = RecordFft::new(fast_len(half), rate);
                let y = angle_spectra(a, &mut fft);
                first_delay(a, w, &y, &mut fft)
            });
            assert!(
                s0 > 0.0 && s0 < 1e-3 && s1 > 0.0 && s1 < 1e-3,
                "seed {seed}: {s0} {s1}"
            );
            (d1 - d0) / s0.hypot(s1)
        })
        .collect();
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    assert!((0.5..1.6).contains(&rms), "rms {rms}: {z:?}");
}
