//! The real recordings in `tests/data/real` (BROAD, CC BY 4.0; README there), the figure the
//! tests judge their gain by, and their gyro block identified with the kinds of its warnings.

use std::path::PathBuf;

use imu_attest::ident::identify::{BlockIdentification, identify_run};
use imu_attest::ident::settings::Settings;
use imu_attest::run::{LoadOptions, Run, load};

/// The recording `name` (`tests/data/real/{name}.csv.gz` and its sidecar), loaded as a user would.
pub fn real(name: &str) -> Run {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/real")
        .join(format!("{name}.csv.gz"));
    load(&path, &LoadOptions::default()).expect("the real run loads")
}

/// `||K - I||_F / ||I||_F`: the gain's distance from identity, relative.
pub fn k_error(k: &[[f64; 3]; 3]) -> f64 {
    (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| (k[i][j] - f64::from(u8::from(i == j))).powi(2))
        .sum::<f64>()
        .sqrt()
        / 3f64.sqrt()
}

/// `run` with its gyro written `samples` rows late (each sample `samples` rows later, the first
/// rows taking the record's last: rest at both ends, so no step of motion is made).
pub fn gyro_late(mut run: Run, samples: usize) -> Run {
    for c in run.gyro.as_mut().expect("a gyro").iter_mut() {
        c.rotate_right(samples);
    }
    run
}

/// The gyro block of `run` identified with `settings` (the real runs have no other block).
pub fn gyro(run: &Run, settings: &Settings) -> BlockIdentification {
    let mut id = identify_run(run, settings).expect("identified");
    assert_eq!(id.blocks.len(), 1, "the real runs have the gyro block only");
    id.blocks.remove(0)
}

/// The `kind` of each of `b`'s warnings, as its JSON names it.
pub fn kinds(b: &BlockIdentification) -> Vec<String> {
    b.warnings
        .iter()
        .map(|w| {
            serde_json::to_value(w).expect("serialisable")["kind"]
                .as_str()
                .expect("a kind")
                .to_owned()
        })
        .collect()
}
