//! How the identifier fits the real recordings (`tests/data/real`, BROAD, CC BY 4.0; README
//! there) when they are short or the fit is redone: the Welch segment fitted to a 30-60 s stretch
//! (or given by the user, and too few of it said or refused), higher orders whose lag the delay
//! gives back not admissible (admissibility rule 4, poles and zeros), and a retune starting from
//! the previous fit. The defaults on the whole runs and the self-check's warnings:
//! `identify_real.rs`.

use std::path::PathBuf;

use crate::common::real as real_common;
use imu_attest::ident::identify::{BlockIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::ident::structural::admissible::Rejection;
use imu_attest::ident::warnings::IdentWarning;
use imu_attest::run::{LoadOptions, Run, load_bytes};
use imu_attest::spectral::WelchSettings;
use real_common::{gyro, kinds, real};

/// Why the fitted order-2 candidate was not admissible (`None`: it was).
/// Order 2's rejection in the fit to the estimate as measured (before any fit over an even gain:
/// the candidates the admissibility rules judged on the recording itself).
fn rejection_of_order_2(b: &BlockIdentification) -> Option<Rejection> {
    let first = b.first_fit.as_ref().unwrap_or(&b.structural);
    let two = first.candidates.iter().find(|c| c.order == 2);
    two.expect("order 2 fitted").rejected.clone()
}

fn stretch(span_s: [f64; 2]) -> Settings {
    Settings {
        span_s: Some(span_s),
        ..Settings::default()
    }
}

/// Short stretches of the real runs, as a lab's 30-60 s recording would be, with default settings:
/// the segment is fitted to the record, the order is 0 and the delay right. Before, 30 s held 3
/// segments of 4096 (an internal error: the 3-input estimate fitted the output exactly and left a
/// disturbance of zero), and 60 s held 7, on which order 2 was chosen with a delay of
/// -2.3 +- 4.8 ms and nothing said.
#[test]
fn short_stretches_get_a_segment_that_fits_and_the_known_delay() {
    for (name, span, segment) in [
        ("broad07_fast_rotation", [21.51, 51.51], 1024),
        ("broad07_fast_rotation", [51.5, 111.5], 2048),
        ("broad25_tapping", [39.6, 99.6], 2048),
        ("broad25_tapping", [99.6, 129.6], 1024),
        ("broad11_slow_translation", [60.0, 90.0], 1024),
    ] {
        let b = gyro(&real(name), &stretch(span));
        let s = &b.structural;
        eprintln!(
            "{name} {span:?}: segment {}, order {}, tau {:.3} +- {:.3} ms, {:?}",
            b.spectra.segment_len,
            s.order,
            s.tau_s * 1e3,
            s.tau_std_s * 1e3,
            kinds(&b)
        );
        assert_eq!(b.spectra.segment_len, segment, "{name} {span:?}");
        assert!(b.spectra.n_averages >= 12, "{name} {span:?}");
        assert_eq!(s.order, 0, "{name} {span:?}: {:?}", s.candidates);
        assert!(
            (3.9e-3..4.5e-3).contains(&s.tau_s),
            "{name} {span:?}: {}",
            s.tau_s
        );
        assert!(!kinds(&b).contains(&"few_segments".to_owned()));
    }
}

/// Admissibility rule 4: on this minute of the fast run, order 2 fits better than the delay alone
/// and predicts the other half better too, with a pair near 50 Hz whose lag (3.6 ms) its negative
/// delay (-3.7 +- 4.5 ms) gives back: the reference's band limit, not the gyro. Not admissible.
#[test]
fn poles_whose_lag_the_delay_gives_back_are_not_admissible() {
    let b = gyro(&real("broad07_fast_rotation"), &stretch([51.5, 111.5]));
    let Some(Rejection::DelayTradedForPoles {
        tau_s,
        tau_std_s,
        pole_lag_s,
    }) = rejection_of_order_2(&b)
    else {
        panic!("{:?}", rejection_of_order_2(&b))
    };
    assert!(tau_s < 0.0 && 2.0 * tau_std_s >= pole_lag_s && pole_lag_s > 0.0);
    // Its delay is not negative beyond 3 sigma: rule 4 alone admitted it.
    assert!(tau_s + 3.0 * tau_std_s > 0.0);
    assert_eq!(b.structural.order, 0);
}

/// The rows of a real run from `from_s` to `to_s` after its first sample, as a lab's short
/// recording would hold them (a file of its own, not a span of the whole run).
fn piece(name: &str, from_s: f64, to_s: f64) -> Run {
    use std::io::Read;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    let mut text = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(&path).expect("the real run"))
        .read_to_string(&mut text)
        .expect("gzip");
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().expect("header"));
    let rows: Vec<(f64, &str)> = lines
        .map(|l| {
            let t = l.split(',').next().and_then(|c| c.parse().ok());
            (t.expect("a time in the first column"), l)
        })
        .collect();
    let t0 = rows[0].0;
    for (t, l) in rows {
        if (t0 + from_s..t0 + to_s).contains(&t) {
            out.push_str(l);
            out.push('\n');
        }
    }
    load_bytes(
        &PathBuf::from(format!("{name}_piece.csv")),
        out.as_bytes(),
        &LoadOptions::default(),
    )
    .expect("the piece loads")
}

/// Admissibility rule 4, zeros: on these 20-40 s pieces of the real runs, order 2 fits better
/// than the delay alone and predicts the other half better too, with a pair near 35 Hz, a delay
/// of -6 to -8 ms (+- 2-3 ms) and a numerator whose zeros (right half plane) add about 4.8 ms of
/// lag: the whole phase is a 4.1-4.2 ms delay's, and the gain rises across the band (the
/// reference's band limit). `auto` chose it on each, and only the warning said so; now the delay
/// alone is chosen, with the known delay.
#[test]
fn zeros_whose_lag_the_delay_gives_back_are_not_admissible() {
    for (name, from_s, to_s) in [
        ("broad25_tapping", 10.0, 40.0),
        ("broad25_tapping", 40.0, 70.0),
        ("broad25_tapping", 70.0, 90.0),
        ("broad07_fast_rotation", 20.0, 60.0),
    ] {
        let b = gyro(&piece(name, from_s, to_s), &Settings::default());
        let rejected = rejection_of_order_2(&b);
        eprintln!("{name} {from_s}-{to_s} s: order 2 {rejected:?}");
        // broad07's piece: since the gyro witness's delay is found by a coherence-weighted
        // correlation (`stand::colour`), its order-2 fit puts the lag in its poles (rule 4's
        // first part: a delay of -4.6 ms beside a pole lag of 4.5 ms) instead of its zeros.
        if let Some(Rejection::DelayTradedForPoles {
            tau_s, pole_lag_s, ..
        }) = rejected
            && name == "broad07_fast_rotation"
        {
            assert!(tau_s < 0.0 && pole_lag_s > 0.0, "{tau_s} {pole_lag_s}");
            assert_eq!(b.structural.order, 0, "{:?}", b.structural.candidates);
            assert!(
                (3.9e-3..4.5e-3).contains(&b.structural.tau_s),
                "{}",
                b.structural.tau_s
            );
            continue;
        }
        let Some(Rejection::DelayTradedForZeros {
            tau_s,
            tau_std_s,
            zero_lag_s,
            zero_lag_std_s,
        }) = rejected
        else {
            panic!("{name} {from_s}-{to_s} s: {rejected:?}")
        };
        assert!(
            tau_s < 0.0 && zero_lag_s > 2.0 * zero_lag_std_s,
            "{tau_s} {zero_lag_s}"
        );
        // Neither earlier part of rule 4 refuses it.
        assert!(tau_s + 3.0 * tau_std_s > 0.0, "{tau_s} {tau_std_s}");
        assert_eq!(b.structural.order, 0, "{:?}", b.structural.candidates);
        assert!(
            (3.9e-3..4.5e-3).contains(&b.structural.tau_s),
            "{}",
            b.structural.tau_s
        );
        assert!(!kinds(&b).contains(&"delay_absorbed_by_poles".to_owned()));
    }
}

/// A segment given by the user is kept, and too few of it is said (`few_segments`) or, under
/// eight, refused with what to give; the program's own segment on the same stretch says nothing.
#[test]
fn a_given_segment_with_few_segments_is_warned_or_refused() {
    let run = real("broad25_tapping");
    let given = |segment_len| Settings {
        welch: WelchSettings {
            segment_len,
            segment_auto: false,
            ..WelchSettings::default()
        },
        ..stretch([99.6, 139.6])
    };
    // 40 s: 11 428 samples, 10 segments of 2048.
    let b = gyro(&run, &given(2048));
    let few = b.warnings.iter().find_map(|w| match w {
        IdentWarning::FewSegments {
            segments,
            segment_len,
            ..
        } => Some((*segments, *segment_len)),
        _ => None,
    });
    assert_eq!(few, Some((10, 2048)), "{:?}", kinds(&b));
    let auto = gyro(&run, &stretch([99.6, 139.6]));
    assert_eq!(auto.spectra.segment_len, 1024);
    assert!(!kinds(&auto).contains(&"few_segments".to_owned()));
    let err = identify_run(&run, &given(4096)).expect_err("4 segments of 4096");
    let msg = err.to_string();
    assert!(err.is_input_error(), "{msg}");
    assert!(
        msg.contains("4 segments of 4096") && msg.contains("segment of 2048 samples"),
        "{msg}"
    );
}

/// A retune (the app's): the block identified again from its own fit start, whose fit over the
/// even gain it starts from. The same settings reuse every fit exactly (the same model, not
/// provisional); a changed Lambda refines them (provisional until a cold fit, as any retune), and
/// the fit is still over the even gain with `K` near the cold fit's.
#[test]
fn a_retune_starts_the_fit_over_the_even_gain_from_the_previous_one() {
    use imu_attest::ident::identify::identify_block_from;
    use imu_attest::ident::settings::LambdaSetting;
    let b = gyro(&real("broad07_fast_rotation"), &Settings::default());
    let start = b.fit_start();
    assert!(start.over_even_gain.is_some() && b.first_fit.is_some());
    assert!(std::sync::Arc::ptr_eq(
        &start.fit,
        b.first_fit.as_ref().expect("first fit")
    ));
    let again = identify_block_from(
        b.block,
        b.spectra.clone(),
        b.factorisation.clone(),
        &Settings::default(),
        Some(&start),
    )
    .expect("identified again");
    assert_eq!(again.structural.k, b.structural.k);
    assert_eq!(again.structural.even_gain, b.structural.even_gain);
    assert!(again.structural.fitted.from_scratch());
    let settings = Settings {
        lambda: LambdaSetting::Values([1e-4; 3]),
        ..Settings::default()
    };
    let cold = gyro(&real("broad07_fast_rotation"), &settings);
    let warm = identify_block_from(
        b.block,
        b.spectra.clone(),
        b.factorisation.clone(),
        &settings,
        Some(&start),
    )
    .expect("retuned");
    assert!(warm.structural.even_gain.is_some() && cold.structural.even_gain.is_some());
    assert!(!warm.structural.fitted.from_scratch() && cold.structural.fitted.from_scratch());
    for i in 0..3 {
        for j in 0..3 {
            let d = (warm.structural.k[i][j] - cold.structural.k[i][j]).abs();
            assert!(d < 0.1 * cold.structural.k_std[i][j], "K[{i}][{j}]: {d}");
        }
    }
}
