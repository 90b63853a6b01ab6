//! `imu-attest simulate --regime NAME [--duration S] [--rate HZ] [--seed N]
//! [--effect ID[:block][@scale]]... [--blocks gyro,accel] [--stand real] [--angle-latency S]
//! [--angle-band-hz HZ] [--angle-filter-hz HZ] [--angle-rate-hz HZ] [--coloured-angle-noise RAD] [--coloured-angle-corner-hz HZ]
//! [--sensor-noise default|white] [--random-walk K] [--sensor-filter-hz HZ] [--fault glitch|hold|clip|wrap|slip[:CHANNEL]]...
//! [--tone-hz F] [--tone-gate from:T|pulsed:ON,OFF] [--sine roll|yaw|pitch:HZ:DEG]...
//! --out RUN.csv`

use std::path::Path;

use super::{Args, CliError};
use crate::run::sidecar_path;
use crate::sim::effect::{Block, EffectSpec};
use crate::sim::fault::FaultSpec;
use crate::sim::regime::Regime;
use crate::sim::stand::StandImperfections;
use crate::sim::truth::ToneGate;
use crate::sim::write::write_run_with_progress;
use crate::sim::{SimConfig, simulate};

/// The option `name` as a positive, finite number of Hz (`None` when absent).
fn positive_hz(args: &Args, name: &str) -> Result<Option<f64>, CliError> {
    args.get(name)
        .map(|text| {
            text.parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or_else(|| CliError::Input(format!("--{name}: '{text}' is not a positive number of Hz")))
        })
        .transpose()
}

pub(super) fn run(args: &Args) -> Result<(), CliError> {
    let regime: Regime = args
        .required("regime")?
        .parse()
        .map_err(|e| CliError::Input(format!("--regime: {e}")))?;
    let mut config = SimConfig::new(regime);
    config.duration_s = args.parsed_or("duration", config.duration_s)?;
    config.rate_hz = args.parsed_or("rate", config.rate_hz)?;
    config.seed = args.parsed_or("seed", config.seed)?;
    for spec in args.all("effect") {
        config.effects.push(
            spec.parse::<EffectSpec>()
                .map_err(|e| CliError::Input(format!("--effect {spec}: {e}")))?,
        );
    }
    for spec in args.all("sine") {
        config.sines.push(
            spec.parse()
                .map_err(|e| CliError::Input(format!("--sine {spec}: {e}")))?,
        );
    }
    for spec in args.all("fault") {
        config.faults.push(
            spec.parse::<FaultSpec>()
                .map_err(|e| CliError::Input(format!("--fault {spec}: {e}")))?,
        );
    }
    if let Some(list) = args.get("blocks") {
        config.blocks = list
            .split(',')
            .map(|name| {
                Block::BOTH.into_iter().find(|b| b.name() == name).ok_or_else(|| {
                    CliError::Input(format!("--blocks: unknown block '{name}' (known: gyro, accel)"))
                })
            })
            .collect::<Result<_, _>>()?;
    }
    if args.get("stand") == Some("real") {
        config.stand = StandImperfections::real();
    } else if let Some(other) = args.get("stand") {
        return Err(CliError::Input(format!(
            "--stand: unknown stand '{other}' (known: real; or give --angle-latency, --angle-band-hz, --angle-filter-hz, --angle-rate-hz, --coloured-angle-noise)"
        )));
    }
    config.stand.latency_s = args.parsed_or("angle-latency", config.stand.latency_s)?;
    if let Some(fb) = positive_hz(args, "angle-band-hz")? {
        config.stand.band_limit_hz = Some(fb);
    }
    if let Some(fc) = positive_hz(args, "angle-filter-hz")? {
        config.stand.filter_hz = Some(fc);
    }
    config.sensor_filter_hz = positive_hz(args, "sensor-filter-hz")?;
    if let Some(fr) = args.get("angle-rate-hz") {
        let fr: f64 = fr
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0 && *v < config.rate_hz)
            .ok_or_else(|| {
                CliError::Input(format!(
                    "--angle-rate-hz: '{fr}' is not a number of Hz between 0 and the run's rate ({} Hz)",
                    config.rate_hz
                ))
            })?;
        config.stand.reference_rate_hz = Some(fr);
    }
    config.stand.coloured_noise_rad =
        args.parsed_or("coloured-angle-noise", config.stand.coloured_noise_rad)?;
    if config.stand.coloured_corner_hz <= 0.0 {
        config.stand.coloured_corner_hz = StandImperfections::real().coloured_corner_hz;
    }
    config.stand.coloured_corner_hz =
        args.parsed_or("coloured-angle-corner-hz", config.stand.coloured_corner_hz)?;
    let stand = config.stand;
    if !(stand.latency_s.is_finite()
        && stand.latency_s.abs() < 1.0
        && stand.coloured_noise_rad.is_finite()
        && stand.coloured_noise_rad >= 0.0
        && stand.coloured_corner_hz.is_finite()
        && stand.coloured_corner_hz > 0.0)
    {
        return Err(CliError::Input(
            "stand imperfections: latency must be finite and below 1 s, coloured noise >= 0 rad, corner > 0 Hz"
                .into(),
        ));
    }
    match args.get("sensor-noise") {
        None | Some("default") => {}
        Some("white") => config.sensor_noise.white_only = true,
        Some(other) => {
            return Err(CliError::Input(format!(
                "--sensor-noise: unknown noise '{other}' (known: default, white)"
            )));
        }
    }
    config.sensor_noise.random_walk = args.parsed_or("random-walk", 0.0)?;
    if !(config.sensor_noise.random_walk.is_finite() && config.sensor_noise.random_walk >= 0.0) {
        return Err(CliError::Input(
            "--random-walk: the walk's strength must be a number >= 0 (output units per s per sqrt(s))"
                .into(),
        ));
    }
    config.tone.frequency_hz = args
        .get("tone-hz")
        .map(|_| args.parsed_or("tone-hz", 0.0))
        .transpose()?;
    if let Some(gate) = args.get("tone-gate") {
        config.tone.gate = parse_gate(gate)?;
    }
    let out = args.required("out")?;
    args.reject_unknown()?;
    if !args.positional.is_empty() {
        return Err(CliError::Input(format!(
            "simulate takes no positional argument, got '{}'",
            args.positional[0]
        )));
    }
    let out = Path::new(out);
    // `--out x.json` would be its own sidecar: the sidecar would replace the run.
    if sidecar_path(out) == out {
        return Err(CliError::Input(format!(
            "--out {}: the run and its sidecar would be the same file (name the run .csv or .csv.gz)",
            out.display()
        )));
    }
    let spinner = super::progress::spinner("simulating");
    let run = simulate(&config).map_err(|e| CliError::Input(e.to_string()));
    spinner.finish_and_clear();
    let run = run?;
    let bar = super::progress::bar(
        run.time_s.len() as u64,
        "writing {msg} {wide_bar} {pos}/{len} rows {eta}",
    );
    bar.set_message(super::progress::display_name(out));
    let written = write_run_with_progress(&run, out, &mut |done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    written.map_err(|e| CliError::Input(e.to_string()))
}

/// `--tone-gate from:T` or `pulsed:ON,OFF` (seconds).
fn parse_gate(text: &str) -> Result<ToneGate, CliError> {
    let bad = || {
        CliError::Input(format!(
            "--tone-gate: '{text}' is not from:T or pulsed:ON,OFF (seconds, e.g. from:60 or pulsed:2,3)"
        ))
    };
    let number = |v: &str| v.trim().parse::<f64>().map_err(|_| bad());
    match text.split_once(':') {
        Some(("from", t)) => Ok(ToneGate::From { start_s: number(t)? }),
        Some(("pulsed", times)) => {
            let (on, off) = times.split_once(',').ok_or_else(bad)?;
            Ok(ToneGate::Pulsed {
                on_s: number(on)?,
                off_s: number(off)?,
            })
        }
        _ => Err(bad()),
    }
}
