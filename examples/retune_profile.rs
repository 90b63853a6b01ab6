//! Repeats the app's retune (a change of Lambda, the fit from the previous one) many times on one
//! run, for a profiler: `cargo build --release --example retune_profile &&
//! perf record -g target/release/examples/retune_profile RUN.csv 400`.
//! Prints the median wall time of a retune (on stderr, as the other examples report).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use imu_attest::ident::session::{Session, Start};
use imu_attest::ident::settings::{LambdaSetting, Settings};
use imu_attest::run::{LoadOptions, load};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: retune_profile RUN.csv [COUNT] [LAMBDA_STEP]")?,
    );
    let count: usize = args.next().map_or(Ok(200), |s| s.parse())?.max(1);
    // The Lambda step between retunes: `bench`'s is 0.005 (its nine retunes 0.005 apart); the
    // steps cycle over nine values so that every retune moves Lambda by about as much.
    let step: f64 = args.next().map_or(Ok(1e-4), |s| s.parse())?;
    let run = load(&path, &LoadOptions::default())?;
    let settings = Settings::default().for_run(&run);
    let mut session = Session::new(Arc::new(run));
    session.identify(&settings, Start::Cold, &mut |_| {})?;
    let mut times = Vec::with_capacity(count);
    for i in 1..=count {
        let l = 0.005 + step * (i % 9) as f64 + 1e-9 * i as f64;
        let s = Settings {
            lambda: LambdaSetting::Values([l, 0.5 * l, 0.25 * l]),
            ..settings.clone()
        };
        let start = Instant::now();
        std::hint::black_box(session.identify(&s, Start::Warm, &mut |_| {})?);
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    eprintln!("retune median {:.2} ms over {count}", 1e3 * times[count / 2]);
    Ok(())
}
