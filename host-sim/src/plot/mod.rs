//! Plots as SVG files a browser shows: line charts on linear or log axes, panels side by side.
//! Small on purpose: axes, ticks, lines with markers, a legend and vertical guide lines.

use std::fmt::Write;

/// One line of a panel.
#[derive(Clone, Debug, Default)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
    /// A label written beside the line, in its colour, where it overprints no other text
    /// (its end first, then along it): which curve of a family this is.
    pub label: String,
}

/// How a series is drawn: the palette's next colour, a solid line, unless said otherwise.
#[derive(Clone, Copy, Debug, Default)]
pub struct Style {
    pub colour: Option<&'static str>,
    pub dashed: bool,
    /// Markers only, no line (points that are not a curve).
    pub dots_only: bool,
    /// Points with no value (stopped runs): open triangles along the x axis at their x, their
    /// y ignored, so they never read as data.
    pub on_axis: bool,
    /// The shape of its points, where they are drawn: a second cue beside the colour.
    pub mark: Mark,
}

/// A point's shape.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Mark {
    #[default]
    Circle,
    Square,
    Diamond,
}

impl Mark {
    /// Every shape, for a caller that gives one per group.
    pub const ALL: [Mark; 3] = [Mark::Circle, Mark::Square, Mark::Diamond];

    /// The shape at (x, y), about 2r across, filled.
    fn draw(self, out: &mut String, x: f64, y: f64, r: f64, colour: &str) {
        let _ = match self {
            Mark::Circle => writeln!(
                out,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" fill="{colour}"/>"#
            ),
            Mark::Square => writeln!(
                out,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}"/>"#,
                x - 0.9 * r,
                y - 0.9 * r,
                1.8 * r,
                1.8 * r
            ),
            Mark::Diamond => writeln!(
                out,
                r#"<path d="M{:.1} {:.1} L{:.1} {:.1} L{:.1} {:.1} L{:.1} {:.1} Z" fill="{colour}"/>"#,
                x,
                y - 1.3 * r,
                x + 1.3 * r,
                y,
                x,
                y + 1.3 * r,
                x - 1.3 * r,
                y
            ),
        };
    }
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
pub const GREY: &str = "#888888";

/// One chart.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    /// Vertical dashed lines at these x, each with a label: written along the top where the
    /// labels fit, otherwise a colour per distinct label and the labels in the legend.
    pub guides: Vec<(f64, String)>,
    /// The x axis spans at least this range (panels that share one: stacked, compared).
    pub x_span: Option<(f64, f64)>,
    /// The guides' distinct labels in the order they take `GUIDE_COLOURS` (empty: their
    /// order in `guides`); a zoom keeps its whole panel's, so a guide keeps its colour.
    pub guide_order: Vec<String>,
    /// Horizontal lines at these y (limits, caps), each with a label, in red: written beside
    /// its own line where that cannot be read as another's, otherwise in the legend with a
    /// dash pattern each.
    pub levels: Vec<(f64, String)>,
    pub markers: Vec<Marker>,
    /// Lines of text under the legend (what the plot cannot show: refused runs, counts).
    pub notes: Vec<String>,
    /// The panel's width without its legend, px (`None`: 520).
    pub width: Option<f64>,
}

const WIDTH: f64 = 520.0;
const HEIGHT: f64 = 400.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 36.0;
const BOTTOM: f64 = 50.0;
/// A zoom panel's width: beside a whole run and its legend within `MAX_WIDTH`.
const ZOOM_WIDTH: f64 = 420.0;
/// Panels go side by side up to this width, then on a new row.
pub const MAX_WIDTH: f64 = 1200.0;
/// Labels' font size, px.
const FONT: f64 = 11.0;
/// A character's width as a fraction of the font size: a little above DejaVu Sans' average
/// (~0.6), so that boxes estimated from it hold the text drawn.
const CHAR: f64 = 0.62;
/// Above this many points a series is drawn as its min/max envelope per pixel column.
const MAX_POINTS_PER_PIXEL: f64 = 2.0;
/// Series' colours: Okabe and Ito's, which colour-blind readers tell apart (blue, orange,
/// bluish green, reddish purple, sky blue, black, vermillion, grey); red is the limits'.
pub const COLOURS: [&str; 8] = [
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#000000", "#D55E00", "#999999",
];
/// Guides' colours when their labels go in the legend (none is the series' blue or the
/// limits' red).
const GUIDE_COLOURS: [&str; 7] = [
    "#999999", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#000000", "#D55E00",
];
/// Levels' dash patterns and reds when their labels go in the legend.
const LEVEL_STYLES: [(&str, &str); 4] = [
    (RED, "6 3"),
    ("#8b0000", "2 2"),
    (RED, "10 3 2 3"),
    ("#8b0000", "12 4"),
];

mod axis;
mod draw;
mod labels;
#[cfg(test)]
mod tests;

impl Panel {
    /// The same panel over x in [from, to] only (its series clipped, unnamed so that it has
    /// no legend of its own, their colours kept), under another title: the detail a long run
    /// draws as a solid band. Levels are left out, so that the y axis fits the detail.
    pub fn zoom(&self, from: f64, to: f64, title: String) -> Panel {
        let inside = |x: f64| x >= from && x <= to;
        Panel {
            title,
            series: self
                .series
                .iter()
                .enumerate()
                .map(|(k, s)| Series {
                    name: String::new(),
                    points: s.points.iter().copied().filter(|p| inside(p.0)).collect(),
                    style: Style {
                        colour: Some(s.style.colour.unwrap_or(COLOURS[k % COLOURS.len()])),
                        ..s.style
                    },
                    label: String::new(),
                })
                .collect(),
            guides: self
                .guides
                .iter()
                .filter(|g| inside(g.0))
                .cloned()
                .collect(),
            guide_order: self.guide_kinds(),
            x_span: Some((from, to)),
            levels: Vec::new(),
            markers: self
                .markers
                .iter()
                .filter(|m| inside(m.x))
                .cloned()
                .collect(),
            notes: Vec::new(),
            width: Some(ZOOM_WIDTH),
            ..self.clone()
        }
    }

    /// The guides' distinct labels, in the order they take their colours.
    fn guide_kinds(&self) -> Vec<String> {
        let mut kinds = self.guide_order.clone();
        for (_, label) in &self.guides {
            if !kinds.contains(label) {
                kinds.push(label.clone());
            }
        }
        kinds
    }
}

/// Panels side by side, on as many rows as keep the page within `MAX_WIDTH`, as one SVG
/// document.
pub fn svg(panels: &[Panel]) -> String {
    let widths: Vec<f64> = panels
        .iter()
        .map(|p| p.draw(&mut String::new(), 0.0, 0.0))
        .collect();
    let mut rows: Vec<Vec<usize>> = Vec::new();
    let mut row_width = 0.0;
    for (k, &w) in widths.iter().enumerate() {
        match rows.last_mut() {
            Some(row) if row_width + w <= MAX_WIDTH => {
                row.push(k);
                row_width += w;
            }
            _ => {
                rows.push(vec![k]);
                row_width = w;
            }
        }
    }
    // Columns aligned across rows where the page allows (each as wide as its widest panel),
    // so that panels stacked in a column (a zoom beside each plot) share their left edge.
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let column_widths: Vec<f64> = (0..columns)
        .map(|j| {
            rows.iter()
                .filter_map(|r| r.get(j))
                .map(|&k| widths[k])
                .fold(0.0, f64::max)
        })
        .collect();
    let aligned = column_widths.iter().sum::<f64>() <= MAX_WIDTH;
    let x0 = |row: &[usize], j: usize| -> f64 {
        if aligned {
            column_widths[..j].iter().sum()
        } else {
            row[..j].iter().map(|&k| widths[k]).sum()
        }
    };
    let total = rows
        .iter()
        .map(|r| x0(r, r.len()))
        .fold(WIDTH, f64::max)
        .ceil();
    let height = HEIGHT * rows.len().max(1) as f64;
    let mut out = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total}" height="{height}" font-family="sans-serif" viewBox="0 0 {total} {height}">
<rect width="100%" height="100%" fill="white"/>
"#
    );
    for (r, row) in rows.iter().enumerate() {
        for (j, &k) in row.iter().enumerate() {
            panels[k].draw(&mut out, x0(row, j), HEIGHT * r as f64);
        }
    }
    out.push_str("</svg>\n");
    round_attributes(&out)
}

/// Numbers inside attribute values (positions, in px) to 2 decimals: a hundredth of a pixel
/// is below what a screen or a printer shows, and the file is the same wherever the last
/// bits of a float differ (docs/plots/ is compared with what scripts/plots.sh makes). Text
/// (labels, titles) is left as written.
fn round_attributes(svg: &str) -> String {
    let mut out = String::with_capacity(svg.len());
    // Inside a tag, and inside a quoted value of it.
    let (mut in_tag, mut in_value) = (false, false);
    let mut chars = svg.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '<' if !in_value => in_tag = true,
            '>' if !in_value => in_tag = false,
            '"' if in_tag => in_value = !in_value,
            _ => {}
        }
        let starts_number = in_value
            && (c.is_ascii_digit() || c == '-')
            && !out.ends_with(|p: char| p.is_ascii_alphanumeric() || p == '.' || p == '#');
        if !starts_number {
            out.push(c);
            continue;
        }
        let mut end = i + c.len_utf8();
        while let Some(&(j, d)) = chars.peek() {
            if d.is_ascii_digit()
                || d == '.'
                || d == 'e'
                || d == 'E'
                || d == '-' && end == j && svg[..j].ends_with(['e', 'E'])
            {
                end = j + d.len_utf8();
                chars.next();
            } else {
                break;
            }
        }
        let word = &svg[i..end];
        match word.parse::<f64>() {
            Ok(x) if word.contains('.') => {
                let rounded = format!("{x:.2}");
                let rounded = rounded.trim_end_matches('0').trim_end_matches('.');
                out.push_str(if rounded == "-0" { "0" } else { rounded });
            }
            _ => out.push_str(word),
        }
    }
    out
}
