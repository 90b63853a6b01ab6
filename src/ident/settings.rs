//! Identifier settings (contract section 3): every field optional, defaults echoed into every
//! output.
//!
//! `estimate` is `"h1"` (the default) or `"causal_wiener"` ([`Estimate`]); `lambda` is three
//! numbers or `"auto"`; `order` is an integer 0..=4 or `"auto"`, or one of
//! these per block (`{"gyro": 0, "accel": "auto"}`, [`BlockOrders`]). Validation
//! against a run ([`Settings::validate`]) refuses: a band outside `(0, Nyquist]` or empty, a
//! weight `A` that is not symmetric positive definite, a `lambda` that makes `I - A^-1 Lambda`
//! singular, a negative `lambda` or one that shrinks the gain by more than [`MAX_SHRINK`], an order above 4, a segment longer than the run or a record holding fewer than
//! [`MIN_EQUIVALENT_AVERAGES`] of it, a block the run does not have. A segment left out of the settings file is the program's:
//! [`Settings::for_run`] shortens it for a short record ([`welch_for_record`]).

use std::fmt;
use std::path::Path;

use nalgebra::Matrix3;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use super::band::BandSetting;
pub use super::block_orders::BlockOrders;
use crate::block::Block;
use crate::spectral::WelchSettings;
pub use validation::{MAX_SHRINK, SettingsError, max_shrink};

#[path = "settings_validation.rs"]
mod validation;

/// Highest structural order.
pub const MAX_ORDER: usize = 4;

/// Fewest equivalent averages the identifier accepts (8 Hann segments at half overlap give 7.63).
/// The 3-input `H1` estimate leaves the disturbance spectrum `nu = n_eq - 3` degrees of freedom per
/// bin (`n_eq` Welch's equivalent number of averages, which falls with the overlap: 8 segments
/// give 4.4 at 0.75, 2.0 at 0.9), and the fit's weights are its inverse, whose mean is
/// `nu / (nu - 2)` times the truth: infinite at `n_eq <= 5` (at `n_eq <= 3` the estimate fits the
/// output exactly and the disturbance is zero), 1.8x at 7.5.
pub const MIN_EQUIVALENT_AVERAGES: f64 = 7.5;

/// What a segment left to the program leaves the record: 12 segments (two halves of six, so the
/// order choice can be checked on held-out data, admissibility rule 7) and 11 equivalent averages
/// (12 Hann segments at half overlap give 11.42). Fewer is warned (`few_segments`).
pub const AUTO_MIN_SEGMENTS: usize = 12;

/// See [`AUTO_MIN_SEGMENTS`].
pub const AUTO_MIN_EQUIVALENT_AVERAGES: f64 = 11.0;

/// Shortest segment the program picks (256 samples at 250 Hz are 1 s: bins 1 Hz apart, the band
/// then starts near 1 Hz); a record too short for it is refused unless a shorter segment is given.
pub const AUTO_MIN_SEGMENT_LEN: usize = 256;

/// Welch's equivalent number of averages of `welch` over `n_samples`
/// ([`crate::ident::spectra::equivalent_averages`], the figure the fit's weights use).
#[must_use]
pub fn equivalent_averages_of(welch: &WelchSettings, n_samples: usize) -> f64 {
    let window = welch.window.coefficients(welch.segment_len);
    super::spectra::equivalent_averages(&window, welch.step(), welch.n_segments(n_samples))
}

/// Whether `segments` Welch segments of `averages` equivalent averages are what a segment left to
/// the program must leave a record ([`AUTO_MIN_SEGMENTS`], [`AUTO_MIN_EQUIVALENT_AVERAGES`]);
/// fewer is warned (`few_segments`).
#[must_use]
pub fn leaves_enough(segments: usize, averages: f64) -> bool {
    segments >= AUTO_MIN_SEGMENTS && averages >= AUTO_MIN_EQUIVALENT_AVERAGES
}

fn enough_for_auto(welch: &WelchSettings, n_samples: usize) -> bool {
    leaves_enough(
        welch.n_segments(n_samples),
        equivalent_averages_of(welch, n_samples),
    )
}

/// Whether `welch` leaves a record of `n_samples` the identifier's minimum
/// ([`MIN_EQUIVALENT_AVERAGES`]).
fn enough_to_identify(welch: &WelchSettings, n_samples: usize) -> bool {
    equivalent_averages_of(welch, n_samples) >= MIN_EQUIVALENT_AVERAGES
}

/// `welch` for a record of `n_samples`: unchanged when its segment was given; left to the
/// program, the segment is halved from its default until the record holds [`AUTO_MIN_SEGMENTS`]
/// and [`AUTO_MIN_EQUIVALENT_AVERAGES`], not below [`AUTO_MIN_SEGMENT_LEN`]. At the default
/// overlap, records of at least `6.5 x 4096` samples (93 s at 286 Hz, 53 s at 500 Hz, 27 s at
/// 1 kHz) keep 4096.
#[must_use]
pub fn welch_for_record(welch: WelchSettings, n_samples: usize) -> WelchSettings {
    let mut w = welch;
    if !w.segment_auto {
        return w;
    }
    while w.segment_len / 2 >= AUTO_MIN_SEGMENT_LEN
        && w.segment_len.is_multiple_of(4)
        && !enough_for_auto(&w, n_samples)
    {
        w.segment_len /= 2;
    }
    w
}

/// The Lagrange multipliers of the regularising constraint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LambdaSetting {
    /// Set by hand, one per output channel.
    Values([f64; 3]),
    /// Solved from the regularising constraint.
    Auto,
}

/// The frequency-response estimate that Lambda regularises and the structural model is fitted to
/// ([`crate::ident::wiener`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimate {
    /// `H1 = S_xu S_uu^-1` per bin: the estimate that reproduces the measured cross-spectrum
    /// (the regularising constraint) exactly, whose covariance the fit's weights are. Each bin
    /// depends on that bin's spectra only, so nothing outside the band moves the fit (the default).
    #[default]
    H1,
    /// The paper's causal Wiener-Kolmogorov filter `W0 = [S_xu D_u^-H]_+ D_u^-1`: causal, but
    /// each bin depends on the spectra at every frequency, so a defect above the band (a
    /// reference's band limit) moves the estimate inside it.
    CausalWiener,
}

impl Estimate {
    /// Both, default first.
    pub const ALL: [Self; 2] = [Self::H1, Self::CausalWiener];
}

impl fmt::Display for Estimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::H1 => "H1 (measured cross-spectrum)",
            Self::CausalWiener => "causal Wiener W0 (paper)",
        })
    }
}

/// The structural order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrderSetting {
    /// A fixed order (0 = `K e^(-tau s)`).
    Fixed(usize),
    /// Chosen by the order-selection criterion.
    Auto,
}

/// Settings of one identification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Welch estimation of the spectral matrices.
    pub welch: WelchSettings,
    /// Analysis band: `"auto"` (the usable band found from the data, [`crate::ident::band`]) or
    /// `[low, high]`, Hz.
    pub band_hz: BandSetting,
    /// Weight matrix A (symmetric positive definite).
    #[serde(rename = "weight_A")]
    pub weight_a: [[f64; 3]; 3],
    /// The frequency-response estimate Lambda regularises and the structural fit uses:
    /// `"h1"` (the default) or `"causal_wiener"` (the paper's `W0`).
    pub estimate: Estimate,
    /// Lagrange multipliers.
    pub lambda: LambdaSetting,
    /// Structural order: one for both blocks, or one per block ([`BlockOrders`]).
    pub order: BlockOrders,
    /// Blocks to identify; empty (the default) means every block the run has.
    pub blocks: Vec<Block>,
    /// Whether the blocks are calibrated (K near identity): the self-check then warns about a
    /// gain far from it ([`crate::ident::selfcheck`]). `false` for a raw, uncalibrated block.
    pub calibrated: bool,
    /// The stretch of the record to analyse, `[t1, t2]` in the run's time column (s), or the
    /// whole record (`null`, the default). The observer still runs over the whole record (no
    /// edge effects at the span's ends); the spectra, the identification and the diagnosis use
    /// the span only. Absent from a model file when not set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub span_s: Option<[f64; 2]>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            welch: WelchSettings::default(),
            band_hz: BandSetting::Auto,
            weight_a: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            estimate: Estimate::H1,
            lambda: LambdaSetting::Values([0.0; 3]),
            order: BlockOrders::both(OrderSetting::Auto),
            blocks: Vec::new(),
            calibrated: true,
            span_s: None,
        }
    }
}

/// Where a JSON document that is not an object starts (1-based line and column of its first
/// character), `None` for an object or an empty document. A struct deserialises from an array
/// too, so an input file of `[]` would otherwise be read as all defaults.
#[must_use]
pub fn not_an_object(bytes: &[u8]) -> Option<(usize, usize)> {
    let at = bytes.iter().position(|b| !b.is_ascii_whitespace())?;
    let before = &bytes[..at];
    (bytes[at] != b'{').then(|| {
        let line = before.split(|&b| b == b'\n').count();
        (line, 1 + before.iter().rev().take_while(|&&b| b != b'\n').count())
    })
}

/// A JSON input file's problem: the line and column `serde_json` reports and what is wrong,
/// prefixed by the JSON path (`serde_path_to_error`'s; `"."` is the document itself, `"?"` no
/// field, and neither is shown).
#[must_use]
pub fn json_problem(path: &str, inner: &serde_json::Error) -> (usize, usize, String) {
    let what = inner
        .to_string()
        .split(" at line ")
        .next()
        .unwrap_or_default()
        .to_owned();
    // `?`: serde_path_to_error's path when the error lies in no field (an unclosed object).
    let detail = if path == "." || path == "?" {
        what
    } else {
        format!("{path}: {what}")
    };
    (inner.line(), inner.column(), detail)
}

impl Settings {
    /// Reads settings from a JSON file's bytes; `file` names it in errors.
    ///
    /// # Errors
    /// [`SettingsError::Parse`] with the line and column of the first problem.
    pub fn from_json(bytes: &[u8], file: &Path) -> Result<Self, SettingsError> {
        let parse_error = |path: String, inner: &serde_json::Error| {
            let (line, column, detail) = json_problem(&path, inner);
            SettingsError::Parse {
                file: file.display().to_string(),
                line,
                column,
                detail,
            }
        };
        // A BOM (some editors save one) is skipped, as in a sidecar.
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        // A struct also deserialises from a JSON array (`[]` was taken as the defaults).
        if let Some((line, column)) = not_an_object(bytes) {
            return Err(SettingsError::Parse {
                file: file.display().to_string(),
                line,
                column,
                detail: "the settings must be a JSON object ({...})".to_owned(),
            });
        }
        let mut de = serde_json::Deserializer::from_slice(bytes);
        let settings: Self = serde_path_to_error::deserialize(&mut de)
            .map_err(|e| parse_error(e.path().to_string(), e.inner()))?;
        de.end().map_err(|e| parse_error(".".into(), &e))?;
        Ok(settings)
    }

    /// `A` as a matrix.
    #[must_use]
    pub fn weight(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| self.weight_a[i][j])
    }

    /// The blocks to identify in a run having `present`: the settings' list, or all present.
    #[must_use]
    pub fn blocks_for(&self, present: &[Block]) -> Vec<Block> {
        if self.blocks.is_empty() {
            present.to_vec()
        } else {
            self.blocks.clone()
        }
    }

    /// These settings as used on `run`: the blocks filled in from the run when empty
    /// ([`Self::blocks_for`]), a segment left to the program fitted to the samples of the span
    /// ([`welch_for_record`]; the whole record when the span does not fit it, which
    /// [`Self::validate`] then refuses). Every output echoes these.
    #[must_use]
    pub fn for_run(&self, run: &crate::run::Run) -> Settings {
        let n = self.span_range(&run.time_s).map_or(run.len(), |r| r.len());
        self.for_record(n, &run.blocks())
    }

    /// [`Self::for_run`], checked ([`Self::validate`]) against the samples of the span it
    /// analyses: what the pipeline runs with, or why it refuses.
    ///
    /// # Errors
    /// [`SettingsError::Span`] when the span is not inside the record; otherwise the first rule
    /// of [`Self::validate`] the settings as used break on the span.
    pub fn used_on(&self, run: &crate::run::Run) -> Result<Settings, SettingsError> {
        let span = self.span_range(&run.time_s)?;
        let present = run.blocks();
        let used = self.for_record(span.len(), &present);
        used.validate(span.len(), run.sample_rate_hz, &present)?;
        Ok(used)
    }

    /// Whether `self` and `other`, each as used on its run, were the same request: equal, or
    /// differing only in the segment the program fitted to each record.
    #[must_use]
    pub fn same_request(&self, other: &Settings) -> bool {
        let asked = |s: &Settings| {
            let mut s = s.clone();
            if s.welch.segment_auto {
                s.welch.segment_len = crate::spectral::DEFAULT_SEGMENT_LEN;
            }
            s
        };
        asked(self) == asked(other)
    }

    /// [`Self::for_run`] for a record of `n_samples` having the blocks `present`.
    #[must_use]
    pub fn for_record(&self, n_samples: usize, present: &[Block]) -> Settings {
        Settings {
            blocks: self.blocks_for(present),
            welch: welch_for_record(self.welch, n_samples),
            ..self.clone()
        }
    }

    /// The samples of `span_s` in a record with times `time_s` (all of them without a span).
    ///
    /// # Errors
    /// [`SettingsError::Span`] when the span is not finite, not ordered, or not inside the record.
    pub fn span_range(&self, time_s: &[f64]) -> Result<std::ops::Range<usize>, SettingsError> {
        let Some([from, to]) = self.span_s else {
            return Ok(0..time_s.len());
        };
        let (start, end) = (
            time_s.first().copied().unwrap_or(0.0),
            time_s.last().copied().unwrap_or(0.0),
        );
        if !(from.is_finite() && to.is_finite() && from < to && from >= start && to <= end) {
            return Err(SettingsError::Span { from, to, start, end });
        }
        let first = time_s.partition_point(|&t| t < from);
        let last = time_s.partition_point(|&t| t <= to);
        Ok(first..last)
    }
}

/// `values` or the word `"auto"` (`None`); `what` names the accepted forms in the error.
pub(crate) fn values_or_auto<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
    what: &str,
) -> Result<Option<T>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Raw<T> {
        Values(T),
        Word(String),
    }
    match Raw::<T>::deserialize(d).map_err(|_| de::Error::custom(format!("{what} or \"auto\"")))? {
        Raw::Values(v) => Ok(Some(v)),
        Raw::Word(w) if w == "auto" => Ok(None),
        Raw::Word(w) => Err(de::Error::custom(format!("{what} or \"auto\", not \"{w}\""))),
    }
}

/// Serialises `values`, or the word `"auto"` for `None`.
pub(crate) fn serialize_values_or_auto<S: Serializer, T: Serialize>(
    values: Option<&T>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match values {
        Some(v) => v.serialize(s),
        None => s.serialize_str("auto"),
    }
}

impl Serialize for LambdaSetting {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let values = match self {
            LambdaSetting::Values(v) => Some(v),
            LambdaSetting::Auto => None,
        };
        serialize_values_or_auto(values, s)
    }
}

impl<'de> Deserialize<'de> for LambdaSetting {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(values_or_auto(d, "lambda must be three numbers")?
            .map_or(LambdaSetting::Auto, LambdaSetting::Values))
    }
}

impl Serialize for OrderSetting {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            OrderSetting::Fixed(n) => s.serialize_u64(*n as u64),
            OrderSetting::Auto => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for OrderSetting {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = OrderSetting;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "an order 0..={MAX_ORDER} or \"auto\"")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<OrderSetting, E> {
                usize::try_from(v)
                    .ok()
                    .filter(|n| *n <= MAX_ORDER)
                    .map(OrderSetting::Fixed)
                    .ok_or_else(|| E::custom(format!("order {v} is above {MAX_ORDER}")))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<OrderSetting, E> {
                u64::try_from(v)
                    .map_err(|_| E::custom(format!("order {v} is negative")))
                    .and_then(|u| self.visit_u64(u))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<OrderSetting, E> {
                if v == "auto" {
                    Ok(OrderSetting::Auto)
                } else {
                    Err(E::custom(format!(
                        "order must be 0..={MAX_ORDER} or \"auto\", not \"{v}\""
                    )))
                }
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
#[path = "settings_tests.rs"]
mod tests;
