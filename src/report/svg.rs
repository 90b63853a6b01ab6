//! Small inline SVG plots for the report: linear or logarithmic axes with readable ticks, lines,
//! shaded bands, error bars and a shaded frequency band. Plain strings out; no fonts or scripts
//! beyond the page's own (the report must render without network access).

use std::fmt::Write as _;

/// One axis.
#[derive(Clone, Debug)]
pub struct Axis {
    /// Logarithmic (base 10).
    pub log: bool,
    /// Label under or beside the axis.
    pub label: String,
}

/// One drawn series.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Legend text (empty: not in the legend).
    pub name: String,
    /// `(x, y)` points of the line (non-finite or, on log axes, non-positive points skipped).
    pub points: Vec<(f64, f64)>,
    /// CSS colour.
    pub colour: String,
    /// Dashed line.
    pub dashed: bool,
    /// A band `(x, lo, hi)` drawn under the line.
    pub band: Vec<(f64, f64, f64)>,
    /// Error bars `(x, lo, hi)` with a marker at each point instead of a band.
    pub bars: bool,
}

/// A plot.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Width and height, px.
    pub size: (f64, f64),
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Series in drawing order.
    pub series: Vec<Series>,
    /// A horizontal range `[x0, x1]` marked as the analysis band.
    pub band: Option<[f64; 2]>,
    /// The vertical range, if not from the data (what lies outside is clipped).
    pub y_range: Option<(f64, f64)>,
    /// Width kept right of the plot area for the legend, px (0: legend inside, top right).
    pub legend_width: f64,
}

/// Plots drawn so far: each clip path gets its own id on a page with many plots.
static PLOTS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

const MARGIN: (f64, f64, f64, f64) = (56.0, 12.0, 24.0, 34.0); // left, right, top, bottom

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Tick values for `[lo, hi]`: decades (and 2, 5 when few) on log axes, 1-2-5 steps otherwise.
fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    if log {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let few = b - a <= 2;
        let mut out = Vec::new();
        for e in a..=b {
            let d = 10f64.powi(e);
            for m in if few { &[1.0, 2.0, 5.0][..] } else { &[1.0][..] } {
                let v = m * d;
                if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                    out.push(v);
                }
            }
        }
        return out;
    }
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut v = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while v <= hi + 1e-9 * step {
        out.push(if v.abs() < 1e-12 * step { 0.0 } else { v });
        v += step;
    }
    out
}

fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_owned()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

impl Plot {
    fn range(&self, pick: impl Fn(&Series) -> Vec<f64>, log: bool) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for s in &self.series {
            for v in pick(s) {
                if v.is_finite() && (!log || v > 0.0) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return if log { (1.0, 10.0) } else { (0.0, 1.0) };
        }
        if log {
            (10f64.powf(lo.log10().floor()), 10f64.powf(hi.log10().ceil()))
        } else if hi - lo < 1e-12 * hi.abs().max(1e-300) {
            (lo - 0.5 * lo.abs().max(1e-12), hi + 0.5 * hi.abs().max(1e-12))
        } else {
            let pad = 0.05 * (hi - lo);
            (lo - pad, hi + pad)
        }
    }

    /// The plot as an `<svg>` element.
    #[must_use]
    pub fn render(&self) -> String {
        let (w, h) = self.size;
        let (ml, mr, mt, mb) = MARGIN;
        let (pw, ph) = (w - ml - mr - self.legend_width, h - mt - mb);
        let clip = PLOTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let xr = self.range(|s| s.points.iter().map(|p| p.0).collect(), self.x.log);
        let yr = self.y_range.unwrap_or_else(|| {
            self.range(
                |s| {
                    s.points
                        .iter()
                        .map(|p| p.1)
                        .chain(s.band.iter().flat_map(|b| [b.1, b.2]))
                        .collect()
                },
                self.y.log,
            )
        });
        let map = |v: f64, (lo, hi): (f64, f64), log: bool| {
            if log {
                (v.log10() - lo.log10()) / (hi.log10() - lo.log10())
            } else {
                (v - lo) / (hi - lo)
            }
        };
        let px = |x: f64| ml + pw * map(x, xr, self.x.log);
        let py = |y: f64| mt + ph * (1.0 - map(y, yr, self.y.log));
        let ok = |x: f64, y: f64| {
            x.is_finite() && y.is_finite() && (!self.x.log || x > 0.0) && (!self.y.log || y > 0.0)
        };
        let mut s = String::new();
        let _ = write!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" aria-label="{t}"><text x="{ml}" y="14" class="pt">{t}</text>"#,
            t = escape(&self.title)
        );
        let _ = write!(
            s,
            r##"<clipPath id="c{clip}"><rect x="{ml}" y="{mt}" width="{pw}" height="{ph}"/></clipPath><rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="#fff" stroke="#999"/>"##
        );
        if let Some([a, b]) = self.band {
            let (xa, xb) = (
                px(a.max(xr.0)).clamp(ml, ml + pw),
                px(b.min(xr.1)).clamp(ml, ml + pw),
            );
            let _ = write!(
                s,
                r##"<rect x="{xa:.1}" y="{mt}" width="{:.1}" height="{ph}" fill="#e8f0fb"/>"##,
                (xb - xa).max(0.0)
            );
        }
        for t in ticks(xr.0, xr.1, self.x.log) {
            let x = px(t);
            let _ = write!(
                s,
                r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" class="tk" text-anchor="middle">{}</text>"##,
                mt + ph,
                mt + ph + 12.0,
                tick_label(t)
            );
        }
        for t in ticks(yr.0, yr.1, self.y.log) {
            let y = py(t);
            let _ = write!(
                s,
                r##"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" class="tk" text-anchor="end">{}</text>"##,
                ml + pw,
                ml - 3.0,
                y + 3.0,
                tick_label(t)
            );
        }
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{:.1}" class="al" text-anchor="middle">{}</text><text x="10" y="{:.1}" class="al" text-anchor="middle" transform="rotate(-90 10 {:.1})">{}</text>"#,
            ml + pw / 2.0,
            h - 4.0,
            escape(&self.x.label),
            mt + ph / 2.0,
            mt + ph / 2.0,
            escape(&self.y.label)
        );
        let _ = write!(s, r#"<g clip-path="url(#c{clip})">"#);
        for series in &self.series {
            let c = &series.colour;
            let pts: Vec<(f64, f64)> = series
                .band
                .iter()
                .filter(|b| ok(b.0, b.1) && ok(b.0, b.2))
                .map(|b| (b.0, b.1))
                .collect();
            if series.bars {
                for b in series.band.iter().filter(|b| ok(b.0, b.1) && ok(b.0, b.2)) {
                    let _ = write!(
                        s,
                        r#"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="{c}"/>"#,
                        py(b.1),
                        py(b.2),
                        x = px(b.0)
                    );
                }
            } else if !pts.is_empty() {
                let upper: Vec<String> = series
                    .band
                    .iter()
                    .filter(|b| ok(b.0, b.2) && ok(b.0, b.1))
                    .map(|b| format!("{:.1},{:.1}", px(b.0), py(b.2)))
                    .collect();
                let lower: Vec<String> = pts
                    .iter()
                    .rev()
                    .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
                    .collect();
                let _ = write!(
                    s,
                    r#"<polygon points="{} {}" fill="{c}" fill-opacity="0.15" stroke="none"/>"#,
                    upper.join(" "),
                    lower.join(" ")
                );
            }
            let line: Vec<String> = series
                .points
                .iter()
                .filter(|p| ok(p.0, p.1))
                .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
                .collect();
            if series.bars {
                for p in series.points.iter().filter(|p| ok(p.0, p.1)) {
                    let _ = write!(
                        s,
                        r#"<circle cx="{:.1}" cy="{:.1}" r="2" fill="{c}"/>"#,
                        px(p.0),
                        py(p.1)
                    );
                }
            } else if !line.is_empty() {
                let dash = if series.dashed {
                    r#" stroke-dasharray="5 3""#
                } else {
                    ""
                };
                let _ = write!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{c}" stroke-width="1.4"{dash}/>"#,
                    line.join(" ")
                );
            }
        }
        s.push_str("</g>");
        let mut ly = mt + 12.0;
        let lx = if self.legend_width > 0.0 {
            ml + pw + 8.0
        } else {
            ml + pw - 120.0
        };
        for series in self.series.iter().filter(|s| !s.name.is_empty()) {
            let dash = if series.dashed {
                r#" stroke-dasharray="5 3""#
            } else {
                ""
            };
            let _ = write!(
                s,
                r#"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{}" stroke-width="2"{dash}/><text x="{:.1}" y="{:.1}" class="lg">{}</text>"#,
                lx,
                lx + 16.0,
                series.colour,
                lx + 20.0,
                ly + 3.0,
                escape(&series.name)
            );
            ly += 12.0;
        }
        s.push_str("</svg>");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_readable() {
        assert_eq!(ticks(0.0, 10.0, false), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(
            ticks(0.01, 1000.0, true),
            vec![0.01, 0.1, 1.0, 10.0, 100.0, 1000.0]
        );
        assert_eq!(ticks(1.0, 10.0, true), vec![1.0, 2.0, 5.0, 10.0]);
        assert_eq!(tick_label(0.25), "0.25");
        assert_eq!(tick_label(1e-6), "1e-6");
        assert!(ticks(1.0, f64::NAN, false).is_empty());
    }

    #[test]
    fn a_plot_is_one_svg_element_without_external_references() {
        let plot = Plot {
            title: "a < b".into(),
            size: (300.0, 200.0),
            x: Axis {
                log: true,
                label: "tau, s".into(),
            },
            y: Axis {
                log: true,
                label: "adev".into(),
            },
            series: vec![Series {
                name: "gx".into(),
                points: vec![(0.01, 1.0), (0.1, 0.3), (1.0, 0.1), (-1.0, 5.0)],
                colour: "#c00".into(),
                band: vec![(0.01, 0.9, 1.1), (1.0, 0.09, 0.11)],
                bars: true,
                ..Series::default()
            }],
            band: Some([0.05, 0.5]),
            y_range: None,
            legend_width: 0.0,
        };
        let svg = plot.render();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert!(svg.contains("a &lt; b"));
        assert_eq!(
            svg.matches("<circle").count(),
            3,
            "the negative point is skipped on a log axis"
        );
        assert!(!svg.contains("href"));
    }
}
