//! The real recordings in `tests/data/real` (BROAD, CC BY 4.0; README there) and the figure the
//! tests judge their gain by.

use std::path::PathBuf;

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
