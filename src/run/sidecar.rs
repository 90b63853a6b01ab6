//! The optional JSON sidecar of a run (contract section 2): `cruise.csv` -> `cruise.json`.
//!
//! Every field is optional; fields this version does not know are ignored, not an error. Wrong
//! JSON or a wrong type is [`LoadError::Sidecar`] with `serde_json`'s line and column; a right type
//! with an impossible value (g not positive, a lever arm that is not three finite numbers, a
//! negative angle noise) is [`LoadError::SidecarValue`]. Units: m/s^2, m, rad.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::LoadError;

/// Standard gravity, m/s^2: the default of [`Sidecar::g_mps2`].
pub const STANDARD_G_MPS2: f64 = 9.806_65;

/// The sidecar's schema id this version writes and expects.
pub const SIDECAR_FORMAT: &str = "stand-run/1";

/// What the sidecar says about a run, with the defaults filled in where it is silent or absent.
#[derive(Clone, Debug, PartialEq)]
pub struct Sidecar {
    /// A sidecar file was found and read.
    pub found: bool,
    /// Its `format` field, when given (`"stand-run/1"`).
    pub format: Option<String>,
    /// Flight regime; the file stem when the sidecar does not say.
    pub regime: String,
    /// Gravity, m/s^2 (default [`STANDARD_G_MPS2`]).
    pub g_mps2: f64,
    /// Accelerometer block's sensing point relative to the centre of rotation, platform axes, m.
    pub accel_lever_arm_m: [f64; 3],
    /// Gyro block's sensing point relative to the centre of rotation, platform axes, m.
    pub gyro_lever_arm_m: [f64; 3],
    /// Standard deviation of one angle sample's measurement noise, rad; `None`: estimate it.
    pub angle_noise_rad: Option<f64>,
    /// Free text.
    pub notes: Option<String>,
}

impl Sidecar {
    /// The defaults used when there is no sidecar: regime `regime`, g standard, lever arms zero.
    #[must_use]
    pub fn defaults(regime: &str) -> Self {
        Self {
            found: false,
            format: None,
            regime: regime.to_owned(),
            g_mps2: STANDARD_G_MPS2,
            accel_lever_arm_m: [0.0; 3],
            gyro_lever_arm_m: [0.0; 3],
            angle_noise_rad: None,
            notes: None,
        }
    }
}

/// The fields the program reads ([`RawSidecar`]'s); any other but the simulator's own
/// ([`crate::sim::EXTRA_SIDECAR_FIELDS`], which only tests read) is ignored with a notice naming
/// it.
pub const SIDECAR_FIELDS: [&str; 7] = [
    "format",
    "regime",
    "g_mps2",
    "accel_lever_arm_m",
    "gyro_lever_arm_m",
    "angle_noise_rad",
    "notes",
];

/// A notice per top-level field of `bytes` (a JSON object) the program does not read, with the
/// known name it most likely meant (one that contains it, or is contained in it, or within two
/// edits): a misspelt `accel_lever_arm` left the lever arm zero, and the accelerometer refused,
/// with no word about the field.
fn unknown_fields(bytes: &[u8]) -> Vec<String> {
    let Ok(serde_json::Value::Object(fields)) = serde_json::from_slice::<serde_json::Value>(bytes) else {
        return Vec::new();
    };
    fields
        .keys()
        .filter(|k| {
            let k = k.as_str();
            !SIDECAR_FIELDS.contains(&k) && !crate::sim::EXTRA_SIDECAR_FIELDS.contains(&k)
        })
        .map(|k| {
            let lower = k.to_ascii_lowercase();
            let meant = SIDECAR_FIELDS.iter().find(|known| {
                lower.len() >= 3 && (known.contains(lower.as_str()) || lower.contains(*known))
                    || edits(&lower, known) <= 2
            });
            match meant {
                Some(known) => format!(
                    "sidecar field '{k}' is not one the program reads, ignored: did you mean \
                     '{known}'?"
                ),
                None => format!("sidecar field '{k}' is not one the program reads, ignored"),
            }
        })
        .collect()
}

/// The Levenshtein distance of `a` and `b` (bytes).
fn edits(a: &str, b: &str) -> usize {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The sidecar's fields as written; unknown fields are skipped by serde (and noticed,
/// [`unknown_fields`]).
#[derive(Deserialize)]
struct RawSidecar {
    format: Option<String>,
    regime: Option<String>,
    g_mps2: Option<f64>,
    accel_lever_arm_m: Option<Vec<f64>>,
    gyro_lever_arm_m: Option<Vec<f64>>,
    angle_noise_rad: Option<f64>,
    notes: Option<String>,
}

/// The sidecar path of a run: `cruise.csv` and `cruise.csv.gz` (any case of the extensions) give
/// `cruise.json` in the same folder; a name without those extensions gets `.json` in place of its
/// last extension.
#[must_use]
pub fn sidecar_path(csv_path: &Path) -> PathBuf {
    csv_path.with_file_name(format!("{}.json", run_stem(csv_path)))
}

/// The run's file stem: the file name without `.csv`, `.csv.gz` or `.gz` (or its last extension).
#[must_use]
pub fn run_stem(csv_path: &Path) -> String {
    let name = csv_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    for ext in [".csv.gz", ".csv", ".gz"] {
        if lower.len() > ext.len() && lower.ends_with(ext) {
            return name[..name.len() - ext.len()].to_owned();
        }
    }
    match name.rfind('.') {
        Some(dot) if dot > 0 => name[..dot].to_owned(),
        _ => name,
    }
}

/// Reads the sidecar of `csv_path`, or the defaults (with a notice) when there is none.
///
/// # Errors
/// [`LoadError::Io`] when the sidecar exists but cannot be read (a directory gives
/// [`LoadError::NotAFile`]), [`LoadError::Sidecar`] for bad JSON or a wrong field type,
/// [`LoadError::SidecarValue`] for an impossible value.
pub(super) fn read_sidecar(csv_path: &Path, notices: &mut Vec<String>) -> Result<Sidecar, LoadError> {
    let path = sidecar_path(csv_path);
    let stem = run_stem(csv_path);
    let bytes = match std::fs::read(&path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let shown = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            notices.push(format!(
                "no sidecar {shown}: regime = file stem '{stem}', lever arms zero, g = {STANDARD_G_MPS2} m/s^2"
            ));
            return Ok(Sidecar::defaults(&stem));
        }
        Err(_) if path.is_dir() => return Err(LoadError::NotAFile { path }),
        Err(source) => return Err(LoadError::Io { path, source }),
    };
    parse_sidecar(&path, &bytes, &stem, notices)
}

/// Parses sidecar bytes; `stem` is the regime when the sidecar gives none.
///
/// # Errors
/// [`LoadError::Sidecar`] for bad JSON (or a UTF-8 error) or a wrong field type, with `serde_json`'s
/// line and column; [`LoadError::SidecarValue`] for an impossible value.
pub fn parse_sidecar(
    path: &Path,
    bytes: &[u8],
    stem: &str,
    notices: &mut Vec<String>,
) -> Result<Sidecar, LoadError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    // A struct also deserialises from an array: `[]` was read as a sidecar of defaults.
    if let Some((line, column)) = crate::ident::settings::not_an_object(bytes) {
        return Err(LoadError::Sidecar {
            path: path.to_owned(),
            line,
            column,
            detail: "the sidecar must be a JSON object ({...})".to_owned(),
        });
    }
    // The field's name with the problem (`g_mps2: invalid type: ...`), as the settings' errors.
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let raw: RawSidecar = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| (e.path().to_string(), e.into_inner()))
        .and_then(|raw| de.end().map(|()| raw).map_err(|e| (".".to_owned(), e)))
        .map_err(|(field, e)| {
            let (line, column, detail) = crate::ident::settings::json_problem(&field, &e);
            LoadError::Sidecar {
                path: path.to_owned(),
                line,
                column,
                detail,
            }
        })?;
    let value_error = |field, detail: String| LoadError::SidecarValue {
        path: path.to_owned(),
        field,
        detail,
    };
    notices.extend(unknown_fields(bytes));
    let mut sidecar = Sidecar::defaults(stem);
    sidecar.found = true;
    if let Some(format) = raw.format {
        if format != SIDECAR_FORMAT {
            notices.push(format!(
                "sidecar format '{format}' is not '{SIDECAR_FORMAT}': read as {SIDECAR_FORMAT}"
            ));
        }
        sidecar.format = Some(format);
    }
    if let Some(regime) = raw.regime {
        if regime.trim().is_empty() {
            return Err(value_error("regime", "must not be empty".to_owned()));
        }
        sidecar.regime = regime;
    }
    if let Some(g) = raw.g_mps2 {
        if !(g.is_finite() && g > 0.0) {
            return Err(value_error(
                "g_mps2",
                format!("must be a positive finite number, got {g}"),
            ));
        }
        sidecar.g_mps2 = g;
    }
    if let Some(arm) = raw.accel_lever_arm_m {
        sidecar.accel_lever_arm_m = lever_arm(&arm).map_err(|d| value_error("accel_lever_arm_m", d))?;
    }
    if let Some(arm) = raw.gyro_lever_arm_m {
        sidecar.gyro_lever_arm_m = lever_arm(&arm).map_err(|d| value_error("gyro_lever_arm_m", d))?;
    }
    if let Some(noise) = raw.angle_noise_rad {
        if !(noise.is_finite() && noise >= 0.0) {
            return Err(value_error(
                "angle_noise_rad",
                format!("must be a finite number >= 0, got {noise}"),
            ));
        }
        sidecar.angle_noise_rad = Some(noise);
    }
    sidecar.notes = raw.notes;
    Ok(sidecar)
}

/// Three finite numbers, or what is wrong with them.
fn lever_arm(values: &[f64]) -> Result<[f64; 3], String> {
    let arm: [f64; 3] = values
        .try_into()
        .map_err(|_| format!("must be 3 numbers [x, y, z] in metres, got {}", values.len()))?;
    if arm.iter().all(|v| v.is_finite()) {
        Ok(arm)
    } else {
        Err(format!("must be 3 finite numbers, got {arm:?}"))
    }
}
