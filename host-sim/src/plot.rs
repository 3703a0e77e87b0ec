//! Plots as SVG files a browser shows: line charts on linear or log axes, panels side by side.
//! Small on purpose: axes, ticks, lines with markers, a legend and vertical guide lines.

use std::fmt::Write;

/// One line of a panel.
#[derive(Clone, Debug, Default)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
}

/// How a series is drawn: the palette's next colour, a solid line, unless said otherwise.
#[derive(Clone, Copy, Debug, Default)]
pub struct Style {
    pub colour: Option<&'static str>,
    pub dashed: bool,
    /// Markers only, no line (points that are not a curve, e.g. stopped runs).
    pub dots_only: bool,
}

/// A point to point at: a crossing, a target.
#[derive(Clone, Debug)]
pub struct Marker {
    pub x: f64,
    pub y: f64,
    pub label: String,
    pub colour: &'static str,
}

/// Red, for limits and crossings.
pub const RED: &str = "#d62728";
/// Grey, for what is not data (stopped runs).
pub const GREY: &str = "#aaaaaa";

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
    /// Horizontal lines at these y (limits, caps), each with a label, in red.
    pub levels: Vec<(f64, String)>,
    pub markers: Vec<Marker>,
    /// Lines of text under the legend (what the plot cannot show: refused runs, counts).
    pub notes: Vec<String>,
}

const WIDTH: f64 = 520.0;
const HEIGHT: f64 = 400.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 36.0;
const BOTTOM: f64 = 50.0;
/// The legend's column, right of the plot, so it never covers a trace.
const LEGEND: f64 = 190.0;
/// Above this many points a series is drawn as its min/max envelope per pixel column.
const MAX_POINTS_PER_PIXEL: f64 = 2.0;
pub const COLOURS: [&str; 8] = [
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
        let ys = Axis::new(
            all()
                .map(|p| p.1)
                .chain(self.levels.iter().map(|l| l.0))
                .chain(self.markers.iter().map(|m| m.y)),
            self.log_y,
        );
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
        // Guide labels in rows from the top, each in the first row where it overlaps no
        // earlier label (about 6 px a character at 11 px).
        let mut row_ends: Vec<f64> = Vec::new();
        for (v, label) in &self.guides {
            if let Some(x) = px(*v) {
                let row = row_ends
                    .iter()
                    .position(|&end| x > end)
                    .unwrap_or(row_ends.len());
                let end = x + 6.0 + 6.0 * label.chars().count() as f64;
                match row_ends.get_mut(row) {
                    Some(e) => *e = end,
                    None => row_ends.push(end),
                }
                let _ = writeln!(
                    out,
                    r##"<line x1="{x}" y1="{TOP}" x2="{x}" y2="{}" stroke="#888" stroke-dasharray="4 3"/><text x="{}" y="{}" font-size="11" fill="#555">{}</text>"##,
                    TOP + h,
                    x + 3.0,
                    TOP + 12.0 + 13.0 * row as f64,
                    escape(label)
                );
            }
        }
        for (v, label) in &self.levels {
            if let Some(y) = py(*v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="{RED}" stroke-dasharray="6 3"/><text x="{}" y="{}" font-size="11" fill="{RED}" text-anchor="end">{}</text>"##,
                    x0 + LEFT,
                    x0 + LEFT + w,
                    x0 + LEFT + w - 4.0,
                    // Below the line, clear of the guides' labels along the top.
                    y + 13.0,
                    escape(label)
                );
            }
        }
        let mut legend_rows = 0;
        for (k, series) in self.series.iter().enumerate() {
            let colour = series.style.colour.unwrap_or(COLOURS[k % COLOURS.len()]);
            let dots: Vec<(f64, f64)> = envelope(
                series
                    .points
                    .iter()
                    .filter_map(|&(x, y)| Some((px(x)?, py(y)?))),
                (MAX_POINTS_PER_PIXEL * w) as usize,
            );
            if !series.style.dots_only {
                let path: Vec<String> =
                    dots.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
                let dash = if series.style.dashed {
                    r#" stroke-dasharray="5 3""#
                } else {
                    ""
                };
                let _ = writeln!(
                    out,
                    r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#,
                    path.join(" ")
                );
            }
            if dots.len() <= 40 || series.style.dots_only {
                for (x, y) in &dots {
                    let _ = writeln!(
                        out,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="{colour}"/>"#
                    );
                }
            }
            if series.name.is_empty() {
                continue;
            }
            let ly = TOP + 14.0 + 15.0 * legend_rows as f64;
            legend_rows += 1;
            let lx = x0 + LEFT + w + 12.0;
            let dash = if series.style.dashed {
                r#" stroke-dasharray="5 3""#
            } else {
                ""
            };
            let _ = writeln!(
                out,
                r#"<line x1="{lx}" y1="{}" x2="{}" y2="{}" stroke="{colour}" stroke-width="2"{dash}/><text x="{}" y="{ly}" font-size="11">{}</text>"#,
                ly - 4.0,
                lx + 18.0,
                ly - 4.0,
                lx + 22.0,
                escape(&series.name)
            );
        }
        for (k, note) in self.notes.iter().enumerate() {
            let _ = writeln!(
                out,
                r##"<text x="{}" y="{}" font-size="11" fill="#555">{}</text>"##,
                x0 + LEFT + w + 12.0,
                TOP + 14.0 + 15.0 * (legend_rows + 1 + k) as f64,
                escape(note)
            );
        }
        for m in &self.markers {
            if let (Some(x), Some(y)) = (px(m.x), py(m.y)) {
                let c = m.colour;
                // Labels right of the marker, or left of it in the plot's right third.
                let (lx, anchor) = if x > x0 + LEFT + 0.66 * w {
                    (x - 7.0, "end")
                } else {
                    (x + 7.0, "start")
                };
                let _ = writeln!(
                    out,
                    r#"<path d="M{} {} L{} {} M{} {} L{} {}" stroke="{c}" stroke-width="2.5"/><text x="{lx}" y="{}" font-size="11" fill="{c}" text-anchor="{anchor}">{}</text>"#,
                    x - 5.0,
                    y - 5.0,
                    x + 5.0,
                    y + 5.0,
                    x - 5.0,
                    y + 5.0,
                    x + 5.0,
                    y - 5.0,
                    y - 7.0,
                    escape(&m.label)
                );
            }
        }
    }

    /// The panel's width: the plot, and the legend's column when a series is named.
    fn width(&self) -> f64 {
        if self.series.iter().any(|s| !s.name.is_empty()) || !self.notes.is_empty() {
            WIDTH + LEGEND
        } else {
            WIDTH
        }
    }
}

/// Pixel points thinned to at most about `columns` × 2: within each pixel column, the first,
/// lowest, highest and last point in order (a min/max envelope, so a fast oscillation over
/// many periods is drawn as the band it sweeps, at a size independent of its length).
fn envelope(points: impl Iterator<Item = (f64, f64)>, columns: usize) -> Vec<(f64, f64)> {
    let points: Vec<(f64, f64)> = points.collect();
    if points.len() <= 2 * columns.max(1) {
        return points;
    }
    let mut out = Vec::with_capacity(4 * columns);
    let mut column: Vec<(f64, f64)> = Vec::new();
    let flush = |column: &mut Vec<(f64, f64)>, out: &mut Vec<(f64, f64)>| {
        let (Some(&first), Some(&last)) = (column.first(), column.last()) else {
            return;
        };
        let by_y = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        let low = *column.iter().min_by(by_y).unwrap_or(&first);
        let high = *column.iter().max_by(by_y).unwrap_or(&first);
        let (a, b) = if low.0 <= high.0 {
            (low, high)
        } else {
            (high, low)
        };
        for p in [first, a, b, last] {
            if out.last() != Some(&p) {
                out.push(p);
            }
        }
        column.clear();
    };
    for p in points {
        if column
            .first()
            .is_some_and(|c: &(f64, f64)| p.0.floor() != c.0.floor())
        {
            flush(&mut column, &mut out);
        }
        column.push(p);
    }
    flush(&mut column, &mut out);
    out
}

/// Panels side by side, as one SVG document.
pub fn svg(panels: &[Panel]) -> String {
    let total: f64 = panels.iter().map(Panel::width).sum::<f64>().max(WIDTH);
    let mut out = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total}" height="{HEIGHT}" font-family="sans-serif" viewBox="0 0 {total} {HEIGHT}">
<rect width="100%" height="100%" fill="white"/>
"#
    );
    let mut x0 = 0.0;
    for panel in panels {
        panel.draw(&mut out, x0);
        x0 += panel.width();
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
                    ..Series::default()
                },
                Series {
                    name: "two".into(),
                    points: vec![(1.0, 2.0), (2.0, 3.0)],
                    ..Series::default()
                },
            ],
            ..Panel::default()
        };
        let doc = svg(&[panel.clone(), panel]);
        assert!(doc.starts_with("<svg") && doc.ends_with("</svg>\n"));
        assert_eq!(doc.matches("<polyline").count(), 4);
        assert!(doc.contains("a &lt; b"));
    }

    /// A million-point oscillation is drawn as its envelope: the same extremes in each pixel
    /// column, a bounded number of points.
    #[test]
    fn long_series_are_drawn_as_their_envelope() {
        let n = 1_000_000;
        let points = (0..n).map(|k| {
            let x = 400.0 * k as f64 / n as f64;
            (x, (k as f64 * 0.37).sin())
        });
        let thin = envelope(points.clone(), 400);
        assert!(thin.len() <= 4 * 401, "{}", thin.len());
        for col in [0usize, 17, 399] {
            let in_col = |p: &&(f64, f64)| p.0.floor() as usize == col;
            let max = |v: Vec<f64>| v.into_iter().fold(f64::NEG_INFINITY, f64::max);
            let all: Vec<f64> = points.clone().filter(|p| in_col(&p)).map(|p| p.1).collect();
            let kept: Vec<f64> = thin.iter().filter(in_col).map(|p| p.1).collect();
            assert_eq!(max(all), max(kept));
        }
        assert!(thin.windows(2).all(|w| w[0].0 <= w[1].0));
    }
}
