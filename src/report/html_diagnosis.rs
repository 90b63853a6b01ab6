//! The certificate's diagnosis section: the verdict, each finding with its size and evidence,
//! and per block the search's band and what it could not do or did not name (the notes and
//! warnings the command line prints and the app shows, in the same words).

use std::fmt::Write as _;

use super::RunReport;
use super::html::{esc, sig};

/// The diagnosis of `run`, or why it could not be made.
pub(super) fn diagnosis(h: &mut String, run: &RunReport) {
    h.push_str("<h3 id=\"diagnosis\">Diagnosis (missing effects)</h3>");
    match &run.diagnosis {
        Err(e) => {
            let _ = write!(
                h,
                "<p class=\"warn\">The diagnosis could not be made: {}</p>",
                esc(e)
            );
        }
        Ok(report) if report.findings.is_empty() => {
            h.push_str("<p>Verdict: no missing effect. The model explains the measurement to its noise");
            only_searched(h, report);
            h.push_str(".</p>");
        }
        Ok(report) => {
            h.push_str("<p>Verdict: effect found");
            only_searched(h, report);
            h.push_str(".</p><ol>");
            for f in &report.findings {
                let _ = write!(
                    h,
                    "<li><b>{}</b>: gap {} &rarr; {} dB. {}<br>{}</li>",
                    esc(&f.name),
                    sig(f.gap_before_db, 4),
                    sig(f.gap_after_db, 4),
                    esc(&crate::diagnose::describe::describe(f).join("; ")),
                    esc(&f.evidence)
                );
            }
            h.push_str("</ol>");
        }
    }
    if let Ok(report) = &run.diagnosis {
        // What the findings leave unexplained: their sizes are then not certifiable.
        for words in report.unexplained() {
            let _ = write!(h, "<p class=\"warn\">{}.</p>", esc(&words));
        }
        // Each block's band searched and the limits of its search.
        for (name, b) in &report.blocks {
            let range = format!("{}&ndash;{} Hz", sig(b.band_hz[0], 3), sig(b.band_hz[1], 3));
            let _ = write!(h, "<p>{} block: searched {range}.", esc(name));
            for limit in report.limits(name) {
                let class = if limit.warning { " class=\"warn\"" } else { "" };
                let _ = write!(h, "</p><p{class}>{}.", esc(&limit.words));
            }
            h.push_str("</p>");
        }
    }
}

/// What the verdict covers where a band was ended below the band asked for.
fn only_searched(h: &mut String, report: &crate::diagnose::Report) {
    h.push_str(&esc(&report.verdict_scope()));
}
