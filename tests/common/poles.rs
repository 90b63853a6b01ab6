//! The `poles_or_even_gain` warning of a block, read as a test checks it: a model with poles kept
//! over the delay-only fit's even gain, said with the even gain's delay.

use imu_attest::ident::identify::BlockIdentification;
use imu_attest::ident::warnings::IdentWarning;

/// What a `poles_or_even_gain` warning says.
#[derive(Debug)]
pub struct PolesSaid {
    pub order: usize,
    pub tau_s: f64,
    pub tau_std_s: f64,
    pub even_tau_s: f64,
    pub even_tau_std_s: f64,
    pub margin: f64,
    pub words: String,
}

/// The block's `poles_or_even_gain` warning, if it has one.
pub fn poles_said(b: &BlockIdentification) -> Option<PolesSaid> {
    b.warnings.iter().find_map(|w| match w {
        IdentWarning::PolesOrEvenGain {
            order,
            tau_s,
            tau_std_s,
            even_tau_s,
            even_tau_std_s,
            margin,
            ..
        } => Some(PolesSaid {
            order: *order,
            tau_s: *tau_s,
            tau_std_s: *tau_std_s,
            even_tau_s: *even_tau_s,
            even_tau_std_s: *even_tau_std_s,
            margin: *margin,
            words: w.to_string(),
        }),
        _ => None,
    })
}

/// Checks what every such warning must say of its block: the chosen model's order and delay,
/// the poles' lag traded for delay (the even gain's delay later by over three deviations), kept
/// because the poles won, the even gain's delay with a deviation, and words giving the even gain's delay and the advice to fix the order
/// to 0. Returns the warning.
pub fn assert_poles_said(b: &BlockIdentification) -> PolesSaid {
    let s = &b.structural;
    assert!(
        s.order > 0,
        "order {}: the case this test stands for is gone",
        s.order
    );
    let said = poles_said(b).expect("poles kept over the even gain are said");
    assert_eq!(said.order, s.order);
    assert!(
        (said.tau_s - s.tau_s).abs() < 1e-12,
        "the chosen model's delay: {} {}",
        said.tau_s,
        s.tau_s
    );
    assert!(
        said.even_tau_s - said.tau_s > 3.0 * said.tau_std_s,
        "the poles' lag traded: {said:?}"
    );
    assert!(said.margin > 0.0, "kept because the poles won: {said:?}");
    assert!(
        said.even_tau_std_s.is_finite() && said.even_tau_std_s > 0.0,
        "the even gain's delay with its deviation: {said:?}"
    );
    assert!(
        said.words.contains(&format!("{:.3} ms", said.even_tau_s * 1e3))
            && said.words.contains("fix the order to 0"),
        "{}",
        said.words
    );
    said
}
