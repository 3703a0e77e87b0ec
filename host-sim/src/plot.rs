//! Plots as SVG files a browser shows: line charts on linear or log axes, panels side by side.
//! Small on purpose: axes, ticks, lines with markers, a legend and vertical guide lines.

use std::fmt::Write;

/// One line of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// One chart.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    /// Vertical dashed lines at these x, each with a label.
    pub guides: Vec<(f64, String)>,
}

const WIDTH: f64 = 520.0;
const HEIGHT: f64 = 400.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 36.0;
const BOTTOM: f64 = 50.0;
const COLOURS: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

/// An axis: data range mapped onto pixels, linear or log10.
struct Axis {
    low: f64,
    high: f64,
    log: bool,
}

impl Axis {
    fn new(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
            let v = if log { v.log10() } else { v };
            low = low.min(v);
            high = high.max(v);
        }
        if !low.is_finite() {
            (low, high) = (0.0, 1.0);
        }
        if log {
            (low, high) = (low.floor(), high.ceil().max(low.floor() + 1.0));
        } else {
            // A flat line gets a range around it (a zero span has no ticks).
            let pad = if high - low > 1e-9 * high.abs().max(low.abs()) {
                0.05 * (high - low)
            } else {
                0.1 * high.abs().max(1.0)
            };
            (low, high) = (low - pad, high + pad);
        }
        Axis { low, high, log }
    }

    /// Position in [0, 1], or None when the value cannot be drawn.
    fn fraction(&self, v: f64) -> Option<f64> {
        let v = if self.log {
            (v > 0.0).then(|| v.log10())?
        } else {
            v
        };
        v.is_finite()
            .then(|| (v - self.low) / (self.high - self.low))
    }

    /// Tick positions (data values) and labels.
    fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (a, b) = (self.low as i32, self.high as i32);
            let every = ((b - a) / 8).max(1);
            return (a..=b)
                .step_by(every as usize)
                .map(|e| (10f64.powi(e), format!("1e{e}")))
                .collect();
        }
        let span = self.high - self.low;
        let raw = span / 6.0;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * magnitude);
        let first = (self.low / step).ceil() as i64;
        let last = (self.high / step).floor() as i64;
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        (first..=last)
            .map(|k| {
                let v = k as f64 * step;
                (v, format!("{v:.decimals$}"))
            })
            .collect()
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

impl Panel {
    fn draw(&self, out: &mut String, x0: f64) {
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let xs = Axis::new(
            all().map(|p| p.0).chain(self.guides.iter().map(|g| g.0)),
            self.log_x,
        );
        let ys = Axis::new(all().map(|p| p.1), self.log_y);
        let (w, h) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
        let px = |x: f64| xs.fraction(x).map(|f| x0 + LEFT + f * w);
        let py = |y: f64| ys.fraction(y).map(|f| TOP + (1.0 - f) * h);
        let _ = writeln!(
            out,
            r#"<text x="{}" y="20" text-anchor="middle" font-weight="bold">{}</text>"#,
            x0 + LEFT + w / 2.0,
            escape(&self.title)
        );
        let _ = writeln!(
            out,
            r##"<rect x="{}" y="{TOP}" width="{w}" height="{h}" fill="none" stroke="#444"/>"##,
            x0 + LEFT
        );
        for (v, label) in xs.ticks() {
            if let Some(x) = px(v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{x}" y1="{TOP}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle" font-size="11">{label}</text>"##,
                    TOP + h,
                    TOP + h + 15.0
                );
            }
        }
        for (v, label) in ys.ticks() {
            if let Some(y) = py(v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end" font-size="11">{label}</text>"##,
                    x0 + LEFT,
                    x0 + LEFT + w,
                    x0 + LEFT - 4.0,
                    y + 4.0
                );
            }
        }
        let _ = writeln!(
            out,
            r#"<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>"#,
            x0 + LEFT + w / 2.0,
            HEIGHT - 12.0,
            escape(&self.x_label)
        );
        let (yx, yy) = (x0 + 16.0, TOP + h / 2.0);
        let _ = writeln!(
            out,
            r#"<text x="{yx}" y="{yy}" text-anchor="middle" font-size="12" transform="rotate(-90 {yx} {yy})">{}</text>"#,
            escape(&self.y_label)
        );
        for (v, label) in &self.guides {
            if let Some(x) = px(*v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{x}" y1="{TOP}" x2="{x}" y2="{}" stroke="#888" stroke-dasharray="4 3"/><text x="{}" y="{}" font-size="11" fill="#555">{}</text>"##,
                    TOP + h,
                    x + 3.0,
                    TOP + h - 6.0,
                    escape(label)
                );
            }
        }
        for (k, series) in self.series.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let dots: Vec<(f64, f64)> = series
                .points
                .iter()
                .filter_map(|&(x, y)| Some((px(x)?, py(y)?)))
                .collect();
            let path: Vec<String> = dots.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
            let _ = writeln!(
                out,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
                path.join(" ")
            );
            if dots.len() <= 40 {
                for (x, y) in &dots {
                    let _ = writeln!(
                        out,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="{colour}"/>"#
                    );
                }
            }
            let ly = TOP + 14.0 + 15.0 * k as f64;
            let lx = x0 + LEFT + w - 150.0;
            let _ = writeln!(
                out,
                r#"<line x1="{lx}" y1="{}" x2="{}" y2="{}" stroke="{colour}" stroke-width="2"/><text x="{}" y="{ly}" font-size="11">{}</text>"#,
                ly - 4.0,
                lx + 18.0,
                ly - 4.0,
                lx + 22.0,
                escape(&series.name)
            );
        }
    }
}

/// Panels side by side, as one SVG document.
pub fn svg(panels: &[Panel]) -> String {
    let total = WIDTH * panels.len().max(1) as f64;
    let mut out = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total}" height="{HEIGHT}" font-family="sans-serif" viewBox="0 0 {total} {HEIGHT}">
<rect width="100%" height="100%" fill="white"/>
"#
    );
    for (k, panel) in panels.iter().enumerate() {
        panel.draw(&mut out, k as f64 * WIDTH);
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_axis_spans_whole_decades_and_drops_what_it_cannot_draw() {
        let axis = Axis::new([3e-7, 2e-2, 0.0, f64::NAN].into_iter(), true);
        assert_eq!((axis.low, axis.high), (-7.0, -1.0));
        assert_eq!(axis.fraction(1e-4), Some(0.5));
        assert_eq!(axis.fraction(0.0), None);
    }

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let axis = Axis::new([0.0, 100.0].into_iter(), false);
        let ticks = axis.ticks();
        assert!(ticks.iter().all(|(v, _)| *v >= axis.low && *v <= axis.high));
        let labels: Vec<&str> = ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0", "20", "40", "60", "80", "100"]);
        let fine = Axis::new([0.3, 0.9].into_iter(), false);
        assert!(fine.ticks().iter().any(|(_, l)| l == "0.6"));
    }

    #[test]
    fn svg_is_one_document_with_a_line_per_series() {
        let panel = Panel {
            title: "a < b".into(),
            series: vec![
                Series {
                    name: "one".into(),
                    points: vec![(1.0, 1.0), (2.0, 4.0)],
                },
                Series {
                    name: "two".into(),
                    points: vec![(1.0, 2.0), (2.0, 3.0)],
                },
            ],
            ..Panel::default()
        };
        let doc = svg(&[panel.clone(), panel]);
        assert!(doc.starts_with("<svg") && doc.ends_with("</svg>\n"));
        assert_eq!(doc.matches("<polyline").count(), 4);
        assert!(doc.contains("a &lt; b"));
    }
}
