//! The identifier's settings parser on arbitrary bytes; what parses is validated against a few
//! run shapes and must round-trip through JSON.
#![no_main]

use std::path::Path;

use imu_attest::ident::band::BandSetting;
use imu_attest::ident::settings::Settings;
use imu_attest::run::Block;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match Settings::from_json(data, Path::new("fuzz.json")) {
        Ok(s) => {
            for (n, rate) in [(0, 500.0), (30_000, 500.0), (1 << 20, 1.0)] {
                if s.validate(n, rate, &[Block::Gyro, Block::Accel]).is_ok()
                    && let BandSetting::Fixed([low, high]) = s.band_hz
                {
                    assert!(low > 0.0 && low < high && high <= rate / 2.0);
                }
            }
            let text = serde_json::to_string(&s).expect("settings serialise");
            let again = Settings::from_json(text.as_bytes(), Path::new("again.json")).expect("round trip");
            assert_eq!(again, s);
        }
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains("fuzz.json") && !message.contains('\n'), "{message}");
        }
    }
});
