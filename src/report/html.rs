//! The report as one self-contained HTML page: inline CSS and SVG, no script, no external
//! reference of any kind (it renders offline and prints to PDF as it is).

use std::fmt::Write as _;

use super::RunReport;
use super::spec::{Check, Verdict};
use super::svg::{Axis, Plot, Series};
use crate::block::Block;
use crate::diagnose::describe::describe_size;
use crate::model::BlockModel;
use crate::noise::BlockNoise;

const COLOURS: [&str; 3] = ["#c0392b", "#1e7b34", "#1f5fbf"];

const STYLE: &str = "body{font:13px/1.4 sans-serif;margin:24px;color:#222;max-width:1100px}\
h1{font-size:22px}h2{font-size:18px;border-bottom:2px solid #1f5fbf;margin-top:32px}\
h3{font-size:15px;margin-top:22px}table{border-collapse:collapse;margin:6px 0}\
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eef2f8}\
td.l,th.l{text-align:left}pre{background:#f6f6f6;padding:6px;font-size:11px;white-space:pre-wrap}\
.warn{color:#b00000;font-weight:bold}.pass{background:#d9f2dd}.fail{background:#f8d0d0}\
.undecided{background:#fbeec8}.grid{display:flex;flex-wrap:wrap;gap:4px}\
.bode{display:grid;grid-template-columns:repeat(3,max-content)}\
svg text.pt{font-size:11px;font-weight:bold}svg text.tk{font-size:9px}svg text.al{font-size:10px}\
svg text.lg{font-size:9px}@media print{h2{page-break-before:always}.grid{break-inside:avoid}}";

pub(super) fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// `value` with `digits` significant digits.
pub(super) fn sig(value: f64, digits: usize) -> String {
    if !value.is_finite() {
        return "n/a".to_owned();
    }
    if value == 0.0 {
        return "0".to_owned();
    }
    let magnitude = value.abs().log10().floor() as i32;
    if !(-4..6).contains(&magnitude) {
        return format!("{value:.prec$e}", prec = digits.saturating_sub(1));
    }
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    format!("{value:.decimals$}")
}

fn pm(value: f64, std: Option<f64>) -> String {
    match std {
        Some(s) if s.is_finite() => format!("{} &plusmn; {}", sig(value, 4), sig(s, 2)),
        _ => format!("{} (&plusmn; undetermined)", sig(value, 4)),
    }
}

/// The whole page: `runs` in order, the specification's checks, the time it was made.
#[must_use]
pub fn page(runs: &[RunReport], checks: &[Check], spec_given: bool, generated_utc: &str) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>imu-attest certification report</title><style>{STYLE}</style></head><body>"
    );
    let _ = write!(
        h,
        "<h1>Dynamic certification report</h1><p>Made by imu-attest {} on {generated_utc} from {} run(s). Method: identification of each sensor block's transfer matrix and disturbance spectrum from one stand run (READING.md); noise terms per IEEE 952-1997 (gyros) and IEEE 1293-2018 (accelerometers) from the disturbance.</p>",
        env!("CARGO_PKG_VERSION"),
        runs.len()
    );
    if spec_given {
        let _ = write!(
            h,
            "<p id=\"spec-summary\"><b>Specification:</b> {}</p>",
            super::spec::summary(checks)
        );
    }
    for run in runs {
        run_section(&mut h, run, checks);
    }
    if runs.len() > 1 {
        comparison(&mut h, runs);
    }
    h.push_str("</body></html>\n");
    h
}

fn run_section(h: &mut String, run: &RunReport, checks: &[Check]) {
    let m = &run.model;
    let _ = write!(
        h,
        "<h2 id=\"run-{id}\">Run {file}</h2><table class=\"run\"><tr><th class=\"l\">file</th><td class=\"l\">{file}</td></tr><tr><th class=\"l\">sha256</th><td class=\"l\"><code>{sha}</code></td></tr><tr><th class=\"l\">regime</th><td class=\"l\">{regime}</td></tr><tr><th class=\"l\">unit</th><td class=\"l\">{unit}</td></tr><tr><th class=\"l\">sample rate</th><td class=\"l\">{rate} Hz</td></tr><tr><th class=\"l\">analysed</th><td class=\"l\">{samples} samples, {dur} s</td></tr></table>",
        id = esc(&m.source.file).replace(' ', "_"),
        file = esc(&m.source.file),
        sha = esc(&m.source.sha256),
        regime = esc(&m.source.regime),
        unit = esc(run.unit.as_deref().unwrap_or("(not stated in the sidecar)")),
        rate = sig(m.source.sample_rate_hz, 6),
        samples = run.samples,
        dur = sig(run.duration_s, 5),
    );
    let settings = serde_json::to_string(&m.settings)
        .unwrap_or_default()
        .replace(",\"", ", \"");
    let _ = write!(
        h,
        "<h3>Settings</h3><pre class=\"settings\">{}</pre>",
        esc(&settings)
    );
    if !m.recording_faults.is_empty() {
        h.push_str("<h3>Recording faults</h3><ul>");
        for f in &m.recording_faults {
            let _ = write!(h, "<li class=\"warn\">{}</li>", esc(&f.to_string()));
        }
        h.push_str("</ul>");
    }
    let kept: Vec<&str> = m.blocks.keys().map(String::as_str).collect();
    for block in Block::BOTH {
        if let Some(b) = m.blocks.get(block.name()) {
            block_section(h, block, b);
        } else if let Some(r) = m.refused_blocks.get(block.name()) {
            let _ = write!(
                h,
                "<h3 id=\"block-{0}\">{0} block</h3><p class=\"warn\">{1}</p>",
                block.name(),
                esc(&r.words(block.name(), &kept))
            );
        }
    }
    super::html_diagnosis::diagnosis(h, run);
    let own: Vec<&Check> = checks.iter().filter(|c| c.run == m.source.file).collect();
    if !own.is_empty() {
        spec_table(h, &own);
    }
}

fn block_section(h: &mut String, block: Block, b: &BlockModel) {
    let _ = write!(h, "<h3 id=\"block-{0}\">{0} block</h3>", block.name());
    h.push_str("<div class=\"selfcheck\">");
    if b.fit.warnings.is_empty() {
        h.push_str("<p>Self-check: no warning.</p>");
    } else {
        h.push_str("<p class=\"warn\">Self-check warnings:</p><ul>");
        for w in &b.fit.warnings {
            let _ = write!(h, "<li class=\"warn\">{}</li>", esc(&w.to_string()));
        }
        h.push_str("</ul>");
    }
    h.push_str("</div>");
    equation(h, b);
    let _ = write!(
        h,
        "<table class=\"scale\"><tr><th class=\"l\">channel</th><th>scale-factor error, ppm</th></tr>"
    );
    for i in 0..3 {
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td></tr>",
            esc(&b.outputs[i]),
            pm(
                b.fit.scale_factor_error_ppm[i],
                b.fit.scale_factor_error_std_ppm[i]
            )
        );
    }
    h.push_str("</table><table class=\"misalignment\"><tr><th class=\"l\">misalignment, mrad</th>");
    for input in &b.inputs {
        let _ = write!(h, "<th>{}</th>", esc(input));
    }
    h.push_str("</tr>");
    for i in 0..3 {
        let _ = write!(h, "<tr><th class=\"l\">{}</th>", esc(&b.outputs[i]));
        for j in 0..3 {
            let cell = if i == j {
                "&mdash;".to_owned()
            } else {
                pm(b.fit.misalignment_mrad[i][j], b.fit.misalignment_std_mrad[i][j])
            };
            let _ = write!(h, "<td>{cell}</td>");
        }
        h.push_str("</tr>");
    }
    h.push_str("</table>");
    bode(h, b);
    if let Some(noise) = &b.noise {
        noise_section(h, block, noise);
    } else {
        h.push_str("<p class=\"warn\">No noise figures: the analysed span is too short.</p>");
    }
}

fn equation(h: &mut String, b: &BlockModel) {
    let tau = pm(b.tau_s * 1e3, b.fit.tau_std_s.map(|s| s * 1e3));
    let chosen = if b.order == 0 {
        "x(t) = K u(t &minus; &tau;) + &psi;(t)".to_owned()
    } else {
        format!(
            "x = N(s) / d(s) e<sup>&minus;&tau;s</sup> u + &psi;, order {} (N(0) = K)",
            b.order
        )
    };
    // With accepted effects the model is the joint fit: its own chi2/dof (not the
    // identification's, `fit.chi2_per_dof`), and the same fit's without them.
    let chi2 = match b.extended_by() {
        Some(e) => format!(
            "{} (whole-record fit with the accepted effects; {} without them)",
            sig(e.chi2_per_dof[1], 3),
            sig(e.chi2_per_dof[0], 3)
        ),
        None => sig(b.fit.chi2_per_dof, 3),
    };
    let _ = write!(
        h,
        "<p class=\"equation\">Model: {chosen}; delay &tau; = {tau} ms; band used {}&ndash;{} Hz; fit &chi;<sup>2</sup>/dof = {chi2}.</p>",
        sig(b.band_hz[0], 3),
        sig(b.band_hz[1], 3),
    );
    if !b.poles.is_empty() {
        h.push_str("<p>Poles: ");
        let parts: Vec<String> = b
            .poles
            .iter()
            .map(|p| esc(&crate::model::describe_pole(*p)))
            .collect();
        let _ = write!(h, "{}.</p>", parts.join("; "));
    }
    let why: Vec<String> = b
        .fit
        .candidates
        .iter()
        .map(|c| {
            let verdict = match &c.rejected {
                Some(r) => format!("order {}: rejected, {}", c.order, esc(&r.to_string())),
                None => format!(
                    "order {}: admissible (criterion {})",
                    c.order,
                    sig(c.criterion, 6)
                ),
            };
            match c.unstable_set_aside {
                Some(aside) => format!("{verdict}, {}", esc(&aside.to_string())),
                None => verdict,
            }
        })
        .collect();
    if !why.is_empty() {
        let _ = write!(h, "<p class=\"orders\">Orders tried: {}.</p>", why.join("; "));
    }
    accepted_effects(h, b);
}

/// The effects accepted into the block's model with their sizes, or that there are none.
fn accepted_effects(h: &mut String, b: &BlockModel) {
    let Some(e) = &b.effects else {
        h.push_str(
            "<p>Accepted effects: none (the diagnosis's findings below are not part of this model).</p>",
        );
        return;
    };
    let block = if b.inputs[0] == crate::ident::signals::channel_names(Block::Gyro).0[0] {
        Block::Gyro
    } else {
        Block::Accel
    };
    if e.extends() {
        let _ = write!(
            h,
            "<p>Accepted effects (the model above is the paper's model extended by them, fitted on the whole \
             record; identified without them: order {}, delay {} ms{}):</p><ul class=\"effects\">",
            e.identified.order,
            sig(e.identified.tau_s * 1e3, 4),
            esc(&e.identified.band_words(b.band_hz))
        );
    } else {
        h.push_str(
            "<p>Accepted effects: none could be added (the model above is as identified):</p><ul class=\"effects\">",
        );
    }
    for a in &e.accepted {
        let size = describe_size(block, a.effect, &a.parameters, &a.parameter_std).join("; ");
        let _ = write!(h, "<li><b>{}</b>: {}</li>", esc(&a.name), esc(&size));
    }
    for n in &e.not_added {
        let _ = write!(
            h,
            "<li>not added: {} ({})</li>",
            esc(&n.effect.name_on(block)),
            esc(&n.reason)
        );
    }
    h.push_str("</ul>");
}

fn bode(h: &mut String, b: &BlockModel) {
    h.push_str("<h4>Frequency response |W<sub>u</sub>| with its 2&sigma; band and the structural model</h4><div class=\"grid bode\">");
    for i in 0..3 {
        for j in 0..3 {
            let mut data = Series {
                name: if i == 0 && j == 0 {
                    "estimate".into()
                } else {
                    String::new()
                },
                colour: COLOURS[2].into(),
                ..Series::default()
            };
            let mut model = Series {
                name: if i == 0 && j == 0 {
                    "model".into()
                } else {
                    String::new()
                },
                colour: "#000".into(),
                dashed: true,
                ..Series::default()
            };
            for (k, &f) in b.frequency_hz.iter().enumerate() {
                let Some(w) = b.w_u.at(k) else { continue };
                let mag = w[(i, j)].norm();
                let std = b.w_u_std.get(k).map_or(0.0, |s| s[i][j]);
                data.points.push((f, mag));
                data.band.push((f, (mag - 2.0 * std).max(0.0), mag + 2.0 * std));
                let r = b.response(f);
                model.points.push((f, r[(i, j)].norm()));
            }
            let y_range = gain_range(&data, &model);
            let plot = Plot {
                title: format!("{} from {}", b.outputs[i], b.inputs[j]),
                size: (300.0, 160.0),
                x: Axis {
                    log: true,
                    label: "Hz".into(),
                },
                y: Axis {
                    log: false,
                    label: "gain".into(),
                },
                series: vec![data, model],
                band: Some(b.band_hz),
                y_range: Some(y_range),
                legend_width: 0.0,
            };
            h.push_str(&plot.render());
        }
    }
    h.push_str("</div>");
}

/// The gain axis: the model's values and the middle 90 % of the estimate's (the band's edges,
/// where the input has little power, would otherwise set the scale), with a margin.
fn gain_range(data: &Series, model: &Series) -> (f64, f64) {
    let mut v: Vec<f64> = data
        .points
        .iter()
        .map(|p| p.1)
        .filter(|v| v.is_finite())
        .collect();
    v.sort_by(f64::total_cmp);
    let pick = |q: f64| v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied();
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for x in [pick(0.05), pick(0.95)]
        .into_iter()
        .flatten()
        .chain(model.points.iter().map(|p| p.1))
    {
        if x.is_finite() {
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = 0.5 * (hi - lo).max(0.02 * hi.abs()).max(1e-9);
    ((lo - pad).max(0.0), hi + pad)
}

fn noise_section(h: &mut String, block: Block, noise: &BlockNoise) {
    let _ = write!(
        h,
        "<h4>Noise terms (from the residual of the model, {} samples; one-sigma intervals)</h4><table class=\"noise\"><tr><th class=\"l\">channel</th><th class=\"l\">term</th><th>value</th><th>interval</th><th class=\"l\">unit</th><th>seen at &tau;, s</th><th>share</th></tr>",
        noise.samples
    );
    for ch in &noise.channels {
        if ch.terms.is_empty() {
            let _ = write!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l\" colspan=\"6\">no term found</td></tr>",
                esc(&ch.channel)
            );
        }
        for t in &ch.terms {
            let _ = write!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{} &ndash; {}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td></tr>",
                esc(&ch.channel),
                if t.term == crate::noise::terms::NoiseTerm::Correlated {
                    format!(
                        "correlated noise (T<sub>c</sub> {} s)",
                        sig(ch.correlation_time_s, 2)
                    )
                } else {
                    t.term.name_on(block)
                },
                sig(t.value, 3),
                sig(t.interval[0], 2),
                sig(t.interval[1], 2),
                esc(&t.unit),
                sig(t.tau_s, 3),
                sig(t.share, 2)
            );
        }
    }
    h.push_str("</table>");
    for w in &noise.warnings {
        let _ = write!(h, "<p class=\"warn\">{}</p>", esc(&w.to_string()));
    }
    h.push_str("<p>A term whose share is below one half is barely visible in this record. The reference's part (the stand's angle noise through the observer and the model) is shown dashed and is subtracted before the fit.</p><div class=\"grid allan\">");
    let mut series = Vec::new();
    for (i, ch) in noise.channels.iter().enumerate() {
        series.push(Series {
            name: ch.channel.clone(),
            points: ch.allan.iter().map(|p| (p.tau_s, p.adev)).collect(),
            band: ch.allan.iter().map(|p| (p.tau_s, p.lo, p.hi)).collect(),
            colour: COLOURS[i].into(),
            bars: true,
            ..Series::default()
        });
        series.push(Series {
            name: format!("{} fit", ch.channel),
            points: ch
                .allan
                .iter()
                .map(|p| (p.tau_s, ch.fitted_adev(p.tau_s)))
                .collect(),
            colour: COLOURS[i].into(),
            ..Series::default()
        });
        series.push(Series {
            name: if i == 0 { "reference".into() } else { String::new() },
            points: ch
                .allan
                .iter()
                .zip(&ch.reference_adev)
                .map(|(p, r)| (p.tau_s, *r))
                .collect(),
            colour: COLOURS[i].into(),
            dashed: true,
            ..Series::default()
        });
    }
    let unit = match block {
        Block::Gyro => "rad/s",
        Block::Accel => "m/s^2",
    };
    let plot = Plot {
        title: format!("{} block: overlapping Allan deviation", block.name()),
        size: (640.0, 340.0),
        x: Axis {
            log: true,
            label: "averaging time tau, s".into(),
        },
        y: Axis {
            log: true,
            label: format!("Allan deviation, {unit}"),
        },
        series,
        band: None,
        y_range: None,
        legend_width: 100.0,
    };
    h.push_str(&plot.render());
    h.push_str("</div><table class=\"correlation\"><tr><th class=\"l\">noise correlation</th>");
    for ch in &noise.channels {
        let _ = write!(h, "<th>{}</th>", esc(&ch.channel));
    }
    h.push_str("</tr>");
    for (i, ch) in noise.channels.iter().enumerate() {
        let _ = write!(h, "<tr><th class=\"l\">{}</th>", esc(&ch.channel));
        for j in 0..3 {
            let _ = write!(h, "<td>{:.2}</td>", noise.correlation[i][j]);
        }
        h.push_str("</tr>");
    }
    h.push_str("</table>");
}

fn spec_table(h: &mut String, checks: &[&Check]) {
    h.push_str("<h3>Specification</h3><table class=\"spec\"><tr><th class=\"l\">block</th><th class=\"l\">figure</th><th class=\"l\">element</th><th>value</th><th>95 % band</th><th>limit</th><th class=\"l\">unit</th><th class=\"l\">verdict</th></tr>");
    for c in checks {
        let (class, word) = match c.verdict {
            Verdict::Pass => ("pass", "pass"),
            Verdict::Fail => ("fail", "fail"),
            Verdict::Undecided => ("undecided", "undecided"),
        };
        let band = c.band.map_or("undetermined".to_owned(), |[lo, hi]| {
            format!("{} &ndash; {}", sig(lo, 3), sig(hi, 3))
        });
        let _ = write!(
            h,
            "<tr class=\"{class}\"><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{band}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{word}</td></tr>",
            c.block.name(),
            esc(&c.quantity),
            esc(&c.element),
            sig(c.value, 4),
            sig(c.limit, 4),
            esc(&c.unit)
        );
    }
    h.push_str("</table>");
}

fn comparison(h: &mut String, runs: &[RunReport]) {
    h.push_str("<h2 id=\"comparison\">Comparison of the runs</h2>");
    for block in Block::BOTH {
        let models: Vec<Option<&BlockModel>> =
            runs.iter().map(|r| r.model.blocks.get(block.name())).collect();
        let Some(first) = models.iter().flatten().next() else {
            continue;
        };
        let _ = write!(
            h,
            "<h3>{} block</h3><table class=\"compare\"><tr><th class=\"l\">figure</th>",
            block.name()
        );
        for r in runs {
            let _ = write!(h, "<th>{}</th>", esc(&r.model.source.file));
        }
        h.push_str("</tr>");
        let mut row = |label: String, cell: &dyn Fn(&BlockModel) -> String| {
            let _ = write!(h, "<tr><th class=\"l\">{label}</th>");
            for m in &models {
                let _ = write!(h, "<td>{}</td>", m.map_or("&mdash;".to_owned(), cell));
            }
            h.push_str("</tr>");
        };
        for i in 0..3 {
            row(
                format!("{} scale-factor error, ppm", esc(&first.outputs[i])),
                &|b| {
                    pm(
                        b.fit.scale_factor_error_ppm[i],
                        b.fit.scale_factor_error_std_ppm[i],
                    )
                },
            );
        }
        for i in 0..3 {
            for j in (0..3).filter(|&j| j != i) {
                row(
                    format!(
                        "{}/{} misalignment, mrad",
                        esc(&first.outputs[i]),
                        esc(&first.inputs[j])
                    ),
                    &|b| pm(b.fit.misalignment_mrad[i][j], b.fit.misalignment_std_mrad[i][j]),
                );
            }
        }
        row("delay, ms".into(), &|b| {
            pm(b.tau_s * 1e3, b.fit.tau_std_s.map(|s| s * 1e3))
        });
        row("order".into(), &|b| b.order.to_string());
        let term = crate::noise::terms::NoiseTerm::RandomWalk;
        for i in 0..3 {
            let unit = term.unit_on(block).0;
            row(
                format!("{} {}, {unit}", esc(&first.outputs[i]), term.name_on(block)),
                &|b| {
                    b.noise
                        .as_ref()
                        .and_then(|n| n.channels[i].term(term))
                        .map_or("&mdash;".to_owned(), |t| sig(t.value, 3))
                },
            );
        }
        h.push_str("</table>");
        for r in runs
            .iter()
            .filter(|r| r.model.refused_blocks.contains_key(block.name()))
        {
            let _ = write!(
                h,
                "<p class=\"warn\">{}: the {} block was not identified (its run's section says why).</p>",
                esc(&r.model.source.file),
                block.name()
            );
        }
        if models.iter().flatten().any(|b| b.order != first.order) {
            h.push_str("<p class=\"warn\">The runs' models have different orders: their K are static gains of different structures.</p>");
        }
    }
}
