//! The session's causal stage: computed only for the causal estimate, added to the cached
//! factorisation when the estimate changes, warm-started in the app's way after a Welch change and
//! polished to what `identify` gives; an unused warm causal stage does not make an `H1` fit
//! provisional.

use std::sync::Arc;

use super::{Session, Start};
use crate::ident::identify::{RunIdentification, identify_run};
use crate::ident::settings::{Estimate, Settings};
use crate::run::{LoadOptions, Run, load};
use crate::spectral::WelchSettings;

fn cruise() -> Arc<Run> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sample_runs/cruise.csv.gz");
    Arc::new(load(&path, &LoadOptions::default()).expect("the bundled sample"))
}

fn settings(estimate: Estimate, overlap: f64) -> Settings {
    Settings {
        estimate,
        welch: WelchSettings {
            overlap,
            ..Settings::default().welch
        },
        ..Settings::default()
    }
}

/// Each block's factorisation, by block order.
fn factorisations(id: &RunIdentification) -> Vec<Arc<crate::ident::factorisation::Factorisation>> {
    id.blocks.iter().map(|b| b.factorisation.clone()).collect()
}

#[test]
fn the_causal_stage_is_added_when_asked_warm_started_after_a_welch_change_and_polished() {
    let run = cruise();
    let mut session = Session::new(run.clone());
    let quiet = &mut |_| {};
    let h1 = session
        .identify(&settings(Estimate::H1, 0.5), Start::Cold, quiet)
        .unwrap();
    assert!(
        h1.blocks.iter().all(|b| b.factorisation.causal.is_none()),
        "H1: no causal stage"
    );

    // The causal estimate on the same spectra: the stage is added, nothing else refactored.
    let causal = session
        .identify(&settings(Estimate::CausalWiener, 0.5), Start::Cold, quiet)
        .unwrap();
    for (a, b) in h1.blocks.iter().zip(&causal.blocks) {
        assert!(Arc::ptr_eq(&a.spectra, &b.spectra));
        assert!(Arc::ptr_eq(
            &a.factorisation.noise_factor,
            &b.factorisation.noise_factor
        ));
        let stage = b.factorisation.causal.as_ref().expect("the causal stage");
        assert!(stage.from_scratch && stage.input_refinement >= 2);
    }
    assert!(!causal.provisional());

    // A Welch change under H1, polished: a cold disturbance factor and no causal stage.
    let h1_moved = settings(Estimate::H1, 0.6);
    assert!(
        session
            .identify(&h1_moved, Start::Warm, quiet)
            .unwrap()
            .provisional()
    );
    let h1_polished = session.polish().expect("something to polish").unwrap();
    assert!(!h1_polished.provisional());
    assert!(
        h1_polished
            .blocks
            .iter()
            .all(|b| b.factorisation.causal.is_none())
    );

    // Back to the causal estimate as the app does it: the stage starts from the one of the
    // spectra before the Welch change (provisional), then is redone from scratch.
    let causal_moved = settings(Estimate::CausalWiener, 0.6);
    let warm = session.identify(&causal_moved, Start::Warm, quiet).unwrap();
    for (a, b) in h1_polished.blocks.iter().zip(&warm.blocks) {
        assert!(Arc::ptr_eq(
            &a.factorisation.noise_factor,
            &b.factorisation.noise_factor
        ));
        let stage = b.factorisation.causal.as_ref().expect("the causal stage");
        assert!(!stage.from_scratch, "started from the previous spectra's");
    }
    assert!(warm.provisional());
    let polished = session.polish().expect("something to polish").unwrap();
    assert!(!polished.provisional());
    let reference = identify_run(&run, &causal_moved).unwrap();
    for (shown, cold) in polished.blocks.iter().zip(&reference.blocks) {
        assert_eq!(*shown.structural, *cold.structural, "{}", shown.block);
        let stage = |b: &super::BlockIdentification| b.factorisation.causal.clone().expect("stage");
        assert_eq!(stage(shown).causal_wiener, stage(cold).causal_wiener);
    }

    // An H1 fit on a factorisation that keeps an unused warm causal stage: the warm causal fit's
    // factorisation (cold disturbance factor, warm stage) is kept as it is, and a cold H1 request
    // is answered from it without refactorising.
    let mut session = Session::new(run);
    session
        .identify(&settings(Estimate::CausalWiener, 0.5), Start::Cold, quiet)
        .unwrap();
    session.identify(&h1_moved, Start::Warm, quiet).unwrap();
    session.polish().expect("something to polish").unwrap();
    let mixed = session.identify(&causal_moved, Start::Warm, quiet).unwrap();
    assert!(mixed.blocks.iter().all(|b| {
        b.factorisation.noise_from_scratch && b.factorisation.causal.as_ref().is_some_and(|c| !c.from_scratch)
    }));
    let h1_cold = session.identify(&h1_moved, Start::Cold, quiet).unwrap();
    for (a, b) in factorisations(&mixed).iter().zip(factorisations(&h1_cold).iter()) {
        assert!(
            Arc::ptr_eq(a, b),
            "the unused warm stage forced no refactorisation"
        );
    }
    assert!(!h1_cold.provisional());
}
