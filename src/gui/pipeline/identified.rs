//! The identification stage's snapshot for the UI: the core's per-block results, the model file
//! they make (what Export writes), and the Bode, coherence and disturbance curves precomputed so
//! the plots only borrow them.
//!
//! Curves use `x = log10 f` (Hz). Confidence bands are `|W_u| ± 2 W_u_std` (about 95 %) in dB (the
//! lower edge at most [`BAND_FLOOR_DB`] below the estimate, where the band contains zero), and
//! `± asin(2 W_u_std / |W_u|)` in phase (± 180° where the band contains zero). Phases are shown
//! wrapped to (-180°, 180°]: unwrapping the noisy phase of a weak cross-axis element would let
//! it drift by whole turns.

use std::sync::Arc;

use egui_plot::PlotPoint;
use num_complex::Complex64;

use crate::block::Block;
use crate::diagnose::Prepared;
use crate::diagnose::extend::apply_effects;
use crate::effect::Effect;
use crate::ident::band::{AUTO_LIMITS_HZ, multiple_coherence, native_bins};
use crate::ident::identify::{BlockIdentification, RunIdentification};
use crate::ident::settings::Settings;
use crate::model::{BlockModel, Model};
use crate::noise::reference::AccelGeometry;
use crate::noise::share::{ReferenceShare, reference_share};
use crate::run::Run;

/// Number of standard deviations of the confidence bands.
pub const BAND_SIGMAS: f64 = 2.0;

/// Deepest the lower edge of a magnitude band goes below the estimate, dB.
pub const BAND_FLOOR_DB: f64 = 40.0;

/// One element `W_u[i][j]` on a Bode plot.
#[derive(Debug, Default)]
pub struct BodeElement {
    /// `log10 f` of the band bins.
    pub log_f: Vec<f64>,
    /// `20 log10 |W|`, dB.
    pub magnitude_db: Vec<PlotPoint>,
    /// Confidence band, dB (lower, upper).
    pub magnitude_band_db: (Vec<f64>, Vec<f64>),
    /// Phase, degrees, in (-180, 180].
    pub phase_deg: Vec<PlotPoint>,
    /// Confidence band, degrees (lower, upper).
    pub phase_band_deg: (Vec<f64>, Vec<f64>),
    /// The fitted structural model, dB.
    pub model_magnitude_db: Vec<PlotPoint>,
    /// The fitted structural model's phase, degrees.
    pub model_phase_deg: Vec<PlotPoint>,
    /// The deviation from the static gain ([`deviation`]): ppm on the diagonal, mrad off it.
    pub deviation: Vec<PlotPoint>,
    /// Its confidence band (lower, upper).
    pub deviation_band: (Vec<f64>, Vec<f64>),
    /// The fitted model's deviation from its own `K`.
    pub model_deviation: Vec<PlotPoint>,
    /// `"ppm"` (a scale-factor element) or `"mrad"` (a cross-axis element).
    pub deviation_unit: &'static str,
}

/// The deviation of `W_ij` at angular frequency `omega` (rad/s) from the static gain `k`: the
/// in-phase part once the model's delay `tau_s` is taken out, `Re(W e^(j omega tau)) - k`, in ppm
/// on the diagonal (a scale-factor error) and in mrad off it (a misalignment), so that errors of
/// a few hundred ppm, invisible on a dB scale, show.
#[must_use]
pub fn deviation(w: Complex64, omega: f64, tau_s: f64, k: f64, diagonal: bool) -> f64 {
    let scale = if diagonal { 1e6 } else { 1e3 };
    ((w * Complex64::from_polar(1.0, omega * tau_s)).re - k) * scale
}

/// A block's curves.
#[derive(Debug)]
pub struct BlockBode {
    /// The block.
    pub block: Block,
    /// Input names (columns).
    pub inputs: [String; 3],
    /// Output names (rows).
    pub outputs: [String; 3],
    /// `W_u` elements, row-major (`3 i + j`).
    pub elements: Vec<BodeElement>,
    /// Multiple coherence of each output with the three inputs, `(log10 f, coherence)`.
    pub coherence: [Vec<PlotPoint>; 3],
    /// `10 log10 |S_psi,ij|` per element, row-major, dB re 1 unit^2/Hz.
    pub noise_psd_db: Vec<Vec<PlotPoint>>,
    /// The analysis band used, Hz (marked on the plots).
    pub band_hz: [f64; 2],
    /// The reference's angle error through the model in each output's disturbance,
    /// `(log10 f, 10 log10 S)` per output, dB re 1 unit^2/Hz (`crate::noise::share`).
    pub reference_psd_db: [Vec<PlotPoint>; 3],
    /// Per output, where that is at least half the disturbance, Hz.
    pub reference_dominated_hz: [Vec<[f64; 2]>; 3],
    /// That in words, shown above the disturbance PSD matrix.
    pub reference_explanation: String,
}

/// The starting points of accepted effects' fits and the effects (`crate::diagnose::extend`).
pub type Extension<'a> = (&'a [Prepared], &'a [(Block, Effect)]);

/// A run's identification under one set of settings.
#[derive(Debug)]
pub struct Identification {
    /// The settings as used (blocks resolved).
    pub settings: Settings,
    /// The core's results (shared with the worker's session).
    pub core: Arc<RunIdentification>,
    /// The model file (contract section 4): `Model::from_identification`, what `identify` writes.
    pub model: Model,
    /// Curves, one entry per block of `core`.
    pub bode: Vec<BlockBode>,
    /// The effects accepted into `model`.
    pub accepted: Vec<(Block, Effect)>,
}

impl Identification {
    /// Builds the snapshot from the core's results.
    #[must_use]
    pub fn new(run: &Run, settings: Settings, core: Arc<RunIdentification>) -> Self {
        let model = Model::from_identification(run, &settings, &core);
        Self::extended(settings, core, model, None, AccelGeometry::of(run))
    }

    /// [`Identification::new`] from its model file (`Model::from_identification` of `core`), the
    /// model extended by accepted effects, from the diagnosis's
    /// starting point of the same run and settings (`crate::diagnose::extend`); `geometry` is
    /// the run's, for the reference's share of the disturbance.
    #[must_use]
    pub fn extended(
        settings: Settings,
        core: Arc<RunIdentification>,
        mut model: Model,
        extension: Option<Extension<'_>>,
        geometry: AccelGeometry,
    ) -> Self {
        if let Some((prepared, accepted)) = extension {
            apply_effects(&mut model, prepared, accepted);
        }
        let bode = core
            .blocks
            .iter()
            .filter_map(|b| {
                let m = model.blocks.get(b.block.name())?;
                Some(bode(b, m, &reference_share(b.block, m, &core.motion, geometry)))
            })
            .collect();
        Self {
            settings,
            core,
            model,
            bode,
            accepted: extension.map(|(_, a)| a.to_vec()).unwrap_or_default(),
        }
    }

    /// Every block's identification, in the order of the settings.
    #[must_use]
    pub fn blocks(&self) -> &[BlockIdentification] {
        &self.core.blocks
    }

    /// Whether a structural fit or a factorisation was started from an earlier one rather than
    /// computed from scratch: the worker then redoes them from scratch when idle and sends the
    /// result again (what `imu-attest identify` gives for these settings).
    #[must_use]
    pub fn provisional(&self) -> bool {
        self.core.provisional()
    }

    /// The model of `block`, if identified.
    #[must_use]
    pub fn block_model(&self, block: Block) -> Option<&BlockModel> {
        self.model.blocks.get(block.name())
    }
}

fn db20(x: f64) -> f64 {
    20.0 * x.max(1e-300).log10()
}

/// The magnitude band `(|w| - s, |w| + s)` in dB, the lower edge at most [`BAND_FLOOR_DB`] below
/// `|w|`.
fn band_db(w: f64, s: f64) -> (f64, f64) {
    (db20(w - s).max(db20(w) - BAND_FLOOR_DB), db20(w + s))
}

fn element(m: &BlockModel, i: usize, j: usize) -> BodeElement {
    let log_f: Vec<f64> = m.frequency_hz.iter().map(|f| f.log10()).collect();
    let w: Vec<Complex64> = (0..log_f.len())
        .map(|k| Complex64::new(m.w_u.re[k][i][j], m.w_u.im[k][i][j]))
        .collect();
    let std: Vec<f64> = m.w_u_std.iter().map(|s| BAND_SIGMAS * s[i][j]).collect();
    let fitted: Vec<Complex64> = m.frequency_hz.iter().map(|&f| m.response(f)[(i, j)]).collect();
    let phase: Vec<f64> = w.iter().map(|z| z.arg().to_degrees()).collect();
    let model_phase: Vec<f64> = fitted.iter().map(|z| z.arg().to_degrees()).collect();
    let points = |ys: &[f64]| {
        log_f
            .iter()
            .zip(ys)
            .map(|(&x, &y)| PlotPoint::new(x, y))
            .collect()
    };
    let mag: Vec<f64> = w.iter().map(|z| db20(z.norm())).collect();
    let spread: Vec<f64> = w
        .iter()
        .zip(&std)
        .map(|(z, s)| {
            if *s < z.norm() {
                (s / z.norm()).asin().to_degrees()
            } else {
                180.0
            }
        })
        .collect();
    let diagonal = i == j;
    let omega = |k: usize| 2.0 * std::f64::consts::PI * m.frequency_hz[k];
    let dev: Vec<f64> = (0..w.len())
        .map(|k| deviation(w[k], omega(k), m.tau_s, m.k[i][j], diagonal))
        .collect();
    let scale = if diagonal { 1e6 } else { 1e3 };
    let model_dev: Vec<f64> = (0..w.len())
        .map(|k| deviation(fitted[k], omega(k), m.tau_s, m.k[i][j], diagonal))
        .collect();
    BodeElement {
        deviation: points(&dev),
        deviation_band: (
            dev.iter().zip(&std).map(|(d, s)| d - s * scale).collect(),
            dev.iter().zip(&std).map(|(d, s)| d + s * scale).collect(),
        ),
        model_deviation: points(&model_dev),
        deviation_unit: if diagonal { "ppm" } else { "mrad" },
        magnitude_db: points(&mag),
        magnitude_band_db: w.iter().zip(&std).map(|(z, &s)| band_db(z.norm(), s)).unzip(),
        phase_deg: points(&phase),
        phase_band_deg: (
            phase.iter().zip(&spread).map(|(p, s)| p - s).collect(),
            phase.iter().zip(&spread).map(|(p, s)| p + s).collect(),
        ),
        model_magnitude_db: points(&fitted.iter().map(|z| db20(z.norm())).collect::<Vec<_>>()),
        model_phase_deg: points(&model_phase),
        log_f,
    }
}

fn bode(b: &BlockIdentification, m: &BlockModel, reference: &ReferenceShare) -> BlockBode {
    let log_f: Vec<f64> = m.frequency_hz.iter().map(|f| f.log10()).collect();
    let elements = (0..9).map(|e| element(m, e / 3, e % 3)).collect();
    // Coherence over the whole usable range, not only the band, so the band's edges can be
    // judged against it.
    let nyquist = b.spectra.sample_rate_hz / 2.0;
    let wide: Vec<(f64, [f64; 3])> = native_bins(&b.spectra, [AUTO_LIMITS_HZ[0], 0.9 * nyquist])
        .into_iter()
        .map(|k| {
            (
                b.spectra.frequency_hz[k].log10(),
                multiple_coherence(&b.spectra, k),
            )
        })
        .collect();
    let coherence = std::array::from_fn(|i| wide.iter().map(|(x, c)| PlotPoint::new(*x, c[i])).collect());
    let noise_psd_db = (0..9)
        .map(|e| {
            let (i, j) = (e / 3, e % 3);
            (0..log_f.len())
                .map(|k| {
                    let z = Complex64::new(m.noise_psd.re[k][i][j], m.noise_psd.im[k][i][j]);
                    PlotPoint::new(log_f[k], 10.0 * z.norm().max(1e-300).log10())
                })
                .collect()
        })
        .collect();
    let reference_psd_db = std::array::from_fn(|i| {
        log_f
            .iter()
            .zip(&reference.psd[i])
            .filter(|(_, s)| **s > 0.0)
            .map(|(&x, s)| PlotPoint::new(x, 10.0 * s.log10()))
            .collect()
    });
    BlockBode {
        block: b.block,
        inputs: m.inputs.clone(),
        outputs: m.outputs.clone(),
        elements,
        coherence,
        noise_psd_db,
        band_hz: m.band_hz,
        reference_explanation: reference_explanation(
            b.block,
            &m.outputs,
            &reference_psd_db,
            &reference.dominated_hz,
        ),
        reference_psd_db,
        reference_dominated_hz: reference.dominated_hz.clone(),
    }
}

/// What the disturbance PSD is made of: the reference's angle error (dashed on the diagonal)
/// and where it is at least half of it, per output.
#[must_use]
fn reference_explanation(
    block: Block,
    outputs: &[String; 3],
    reference_psd_db: &[Vec<PlotPoint>; 3],
    dominated_hz: &[Vec<[f64; 2]>; 3],
) -> String {
    let how = match block {
        Block::Gyro => "differentiated into a rate error",
        Block::Accel => "as tilt against gravity and lever-arm acceleration",
    };
    if reference_psd_db.iter().all(Vec::is_empty) {
        return "No density of the stand's angle noise is known for this run's band (no dashed line): \
                the disturbance cannot be split between the reference and the sensor here."
            .to_owned();
    }
    let ranges: Vec<String> = (0..3)
        .filter(|&i| !dominated_hz[i].is_empty())
        .map(|i| {
            let spans: Vec<String> = dominated_hz[i]
                .iter()
                .map(|[a, b]| format!("{a:.2}-{b:.2} Hz"))
                .collect();
            format!("{} {}", outputs[i], spans.join(", "))
        })
        .collect();
    let line = format!(
        "Dashed on the diagonal: the white noise of the stand's angle measurement (the sidecar's \
         or the angles' floor) through the observer and the model ({how})."
    );
    if ranges.is_empty() {
        format!(
            "{line} It stays below half of the disturbance at every frequency: what the model does \
             not explain is not that noise (the reference's coloured noise, band limit or latency \
             cannot be told from the sensor's own noise with one block: see Missing effects)."
        )
    } else {
        format!(
            "{line} Where it is half of the disturbance or more, the disturbance is the reference's, \
             not the sensor's noise: {}.",
            ranges.join("; ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{BAND_FLOOR_DB, band_db};

    #[test]
    fn a_band_containing_zero_is_floored_below_the_estimate() {
        // |W| = 1e-3 with 2 std = 2e-3: the lower edge would be -inf dB.
        let (lower, upper) = band_db(1e-3, 2e-3);
        assert!((lower - (-60.0 - BAND_FLOOR_DB)).abs() < 1e-9, "{lower}");
        assert!((upper - 20.0 * 3e-3f64.log10()).abs() < 1e-9, "{upper}");
        // A tight band keeps its own edges.
        let (lower, upper) = band_db(1.0, 0.01);
        assert!((lower - 20.0 * 0.99f64.log10()).abs() < 1e-12);
        assert!((upper - 20.0 * 1.01f64.log10()).abs() < 1e-12);
    }
}
