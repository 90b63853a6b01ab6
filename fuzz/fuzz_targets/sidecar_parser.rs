//! The sidecar parser on arbitrary bytes.
#![no_main]

use std::path::Path;

use imu_attest::run::parse_sidecar;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut notices = Vec::new();
    match parse_sidecar(Path::new("fuzz.json"), data, "fuzz", &mut notices) {
        Ok(s) => {
            assert!(s.g_mps2.is_finite() && s.g_mps2 > 0.0);
            assert!(s.accel_lever_arm_m.iter().chain(&s.gyro_lever_arm_m).all(|v| v.is_finite()));
            assert!(s.angle_noise_rad.is_none_or(|v| v.is_finite() && v >= 0.0));
        }
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains("fuzz.json") && !message.contains('\n'), "{message}");
        }
    }
});
