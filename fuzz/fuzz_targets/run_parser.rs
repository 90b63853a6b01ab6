//! The run loader on arbitrary bytes (plain or gzipped CSV). The first byte picks the size of the
//! blocks the file is read in, so that lines cross block boundaries; the rest is the file.
#![no_main]

use std::path::Path;

use imu_attest::run::{LoadOptions, load_bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, file)) = data.split_first() else {
        return;
    };
    let options = LoadOptions {
        chunk_bytes: [1, 7, 64, 4096][usize::from(pick % 4)],
        memory_limit_bytes: Some(1 << 30),
        ..LoadOptions::default()
    };
    match load_bytes(Path::new("fuzz.csv"), file, &options) {
        Ok(run) => {
            let n = run.len();
            assert!(n >= imu_attest::run::MIN_SAMPLES);
            assert!(run.sample_rate_hz.is_finite() && run.sample_rate_hz > 0.0);
            assert!(run.time_s.windows(2).all(|w| w[1] > w[0]));
            for c in run.angles.iter().chain(run.gyro.iter().flatten()).chain(run.accel.iter().flatten()) {
                assert_eq!(c.len(), n);
                assert!(c.iter().all(|v| v.is_finite()));
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains("fuzz.csv") && !message.contains('\n'), "{message}");
        }
    }
});
