//! A 60-second simulated approach run, written by the binary's `simulate` (for the command-line
//! tests that need a run with a known hidden effect).

use std::path::Path;

/// Writes the run of `seed` with `effect` (an `--effect` spec) to `out`; panics if `simulate`
/// fails.
pub fn approach_run(out: &Path, seed: &str, effect: Option<&str>) {
    let mut args = vec![
        "simulate",
        "--regime",
        "approach",
        "--duration",
        "60",
        "--seed",
        seed,
    ];
    if let Some(e) = effect {
        args.extend(["--effect", e]);
    }
    let out = out.to_str().expect("a UTF-8 path");
    args.extend(["--out", out]);
    let o = crate::binary::imu_attest(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
