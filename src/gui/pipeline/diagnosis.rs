//! The missing-effect diagnosis of a loaded run on the worker: the core's diagnosis on the run's
//! session, so the observer, spectra and factorisations the app already holds are used as they
//! are (only the order-0 fit over the diagnosis's band is new). The certificate is made the same
//! way. What the Missing effects tab says is made here once per diagnosis ([`Diagnosis`]), not
//! by the ui step each frame.

use super::analyse::RunCache;
use crate::block::Block;
use crate::diagnose::limits::Limit;
use crate::diagnose::{DiagnoseError, DiagnoseOptions, Report, Verdict, diagnose_prepared};
use crate::effect::Effect;
use crate::ident::settings::Settings;

/// A diagnosis as the Missing effects tab draws it: the core's report and its words.
#[derive(Debug)]
pub struct Diagnosis {
    /// The core's report.
    pub report: Report,
    /// The verdict, with what it covers where a block's band was ended.
    pub verdict: String,
    /// Warnings said with the verdict: blocks not diagnosed, what the findings leave
    /// unexplained, significant candidates set aside that outweigh every finding named.
    pub warnings: Vec<String>,
    /// Per finding (the report's order), its size in words ([`crate::diagnose::describe`]).
    pub sizes: Vec<Vec<String>>,
    /// Per block (the report's order), its search in words.
    pub blocks: Vec<BlockWords>,
}

/// One block's search in words.
#[derive(Debug)]
pub struct BlockWords {
    /// The block's name in the report.
    pub name: String,
    /// Band searched, worst-channel gaps and chi2/dof before and after.
    pub header: String,
    /// The limits of its search ([`Report::limits`]) but a warning said with the verdict.
    pub limits: Vec<Limit>,
    /// The significant candidates the user may accept all the same
    /// ([`crate::diagnose::not_named::Reason::may_be_accepted`]).
    pub not_named: Vec<(Block, Effect)>,
}

impl Diagnosis {
    /// The words of `report`.
    #[must_use]
    pub fn new(report: Report) -> Self {
        let verdict = match report.verdict {
            Verdict::EffectFound => "verdict: effect found",
            Verdict::NoMissingEffect => "verdict: no missing effect",
        };
        let verdict = format!("{verdict}{}", report.verdict_scope());
        let mut warnings: Vec<String> = report
            .refused_blocks
            .keys()
            .map(|name| {
                format!(
                    "{name} block not diagnosed: the run cannot identify it (Results says why); \
                     the verdict is the other block's"
                )
            })
            .chain(report.unexplained())
            .collect();
        let mut blocks = Vec::with_capacity(report.blocks.len());
        for (name, b) in &report.blocks {
            let (with_verdict, limits): (Vec<Limit>, Vec<Limit>) = report
                .limits(name)
                .into_iter()
                .partition(|l| l.warning && l.kind == crate::diagnose::limits::LimitKind::NotNamed);
            warnings.extend(with_verdict.into_iter().map(|l| l.words));
            let worst = |gaps: &[f64; 3]| gaps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            blocks.push(BlockWords {
                name: name.clone(),
                header: format!(
                    "{name}: searched {:.2}-{:.2} Hz; worst-channel gap {:.2} dB -> {:.2} dB; chi2/dof {:.3} -> {:.3}",
                    b.band_hz[0],
                    b.band_hz[1],
                    worst(&b.gap_db[0]),
                    worst(&b.gap_db[1]),
                    b.chi2_per_dof[0],
                    b.chi2_per_dof[1],
                ),
                limits,
                not_named: Block::from_name(name)
                    .map(|block| {
                        b.not_named
                            .iter()
                            .filter(|n| n.reason.may_be_accepted())
                            .map(|n| (block, n.effect))
                            .collect()
                    })
                    .unwrap_or_default(),
            });
        }
        Self {
            sizes: report
                .findings
                .iter()
                .map(crate::diagnose::describe::describe)
                .collect(),
            verdict,
            warnings,
            blocks,
            report,
        }
    }
}

/// Diagnoses the cached run.
///
/// # Errors
/// The diagnosis's error.
pub(super) fn diagnose(
    cache: &mut RunCache,
    settings: &Settings,
    rejected: &[(Block, Effect)],
) -> Result<Diagnosis, DiagnoseError> {
    let options = DiagnoseOptions {
        given: None,
        rejected: rejected.to_vec(),
    };
    // A rerun after a rejection starts from the cached identification and whole-record fits.
    Ok(Diagnosis::new(diagnose_prepared(
        &*cache.prepared(settings)?,
        &options,
    )))
}

/// Writes the cached run's model file to `path` with its noise terms (as `identify` does).
///
/// # Errors
/// The message, and whether it is the user's input.
pub(super) fn export_model(cache: &mut RunCache, path: &std::path::Path) -> Result<(), (String, bool)> {
    let model = model_with_noise(cache)?;
    model.write_file(path).map_err(|e| {
        let input = !matches!(e, crate::output::OutputError::NonFinite { .. });
        (e.to_string(), input)
    })
}

/// The cached run's current model with its noise terms (as `identify` writes it).
///
/// # Errors
/// The message, and whether it is the user's input.
pub(super) fn model_with_noise(cache: &mut RunCache) -> Result<crate::model::Model, (String, bool)> {
    let identification = cache
        .identification
        .clone()
        .ok_or_else(|| ("the run is not identified yet".to_owned(), true))?;
    let mut model = identification.model.clone();
    let settings = model.settings.clone();
    crate::noise::of_model::attach_noise(&mut model, &mut cache.session, &settings)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    Ok(model)
}

/// Writes the cached run's certificate to `path` (`crate::report`).
///
/// # Errors
/// The message, and whether it is the user's input (bad settings for the run, a path that
/// cannot be written) rather than our fault.
pub(super) fn report(
    cache: &mut RunCache,
    settings: &Settings,
    path: &std::path::Path,
) -> Result<(), (String, bool)> {
    let run = cache.session.run().clone();
    let settings = settings.for_run(&run);
    let report = crate::report::run_report(&mut cache.session, &settings, None)
        .map_err(|e| (e.to_string(), e.is_input_error()))?;
    let (page, _) = crate::report::render(&[report], None, &crate::report::utc_now());
    crate::report::write_page(path, &page).map_err(|e| (e.to_string(), true))
}
