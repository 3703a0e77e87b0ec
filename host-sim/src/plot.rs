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

/// 10^e as people write it: 1, 10, 100, 10³, 10⁻³.
fn power_of_ten(e: i32) -> String {
    match e {
        0 => "1".into(),
        1 => "10".into(),
        2 => "100".into(),
        _ => {
            const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
            let digits: String = e
                .unsigned_abs()
                .to_string()
                .chars()
                .filter_map(|d| d.to_digit(10).and_then(|d| SUPERSCRIPT.get(d as usize)))
                .collect();
            format!("10{}{digits}", if e < 0 { "⁻" } else { "" })
        }
    }
}

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
                .map(|e| (10f64.powi(e), power_of_ten(e)))
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

/// Where a text's x is: its start, middle or end (SVG's text-anchor).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    fn name(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// A box on the page, px: left, top, right, bottom.
#[derive(Clone, Copy, Debug)]
struct Rect(f64, f64, f64, f64);

impl Rect {
    fn overlaps(&self, o: &Rect) -> bool {
        self.0 < o.2 && o.0 < self.2 && self.1 < o.3 && o.1 < self.3
    }

    fn inside(&self, o: &Rect) -> bool {
        self.0 >= o.0 && self.2 <= o.2 && self.1 >= o.1 && self.3 <= o.3
    }

    /// The box of `text` at `size` px with its baseline at y (a pixel of room around it).
    fn of_text(x: f64, y: f64, text: &str, size: f64, anchor: Anchor) -> Rect {
        let w = CHAR * size * text.chars().count() as f64;
        let left = match anchor {
            Anchor::Start => x,
            Anchor::Middle => x - w / 2.0,
            Anchor::End => x - w,
        };
        Rect(
            left - 1.0,
            y - size - 1.0,
            left + w + 1.0,
            y + 0.3 * size + 1.0,
        )
    }
}

/// Whether the segment from a to b passes through the box (Liang and Barsky's clipping: the
/// part of the segment inside each pair of the box's edges, intersected).
fn crosses(r: &Rect, (ax, ay): (f64, f64), (bx, by): (f64, f64)) -> bool {
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (p, q) in [
        (ax - bx, ax - r.0),
        (bx - ax, r.2 - ax),
        (ay - by, ay - r.1),
        (by - ay, r.3 - ay),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Labels put where they overprint no other and no line: each takes the first of its
/// candidate places that lies inside the area, clear of every box taken and of every
/// line drawn (the series' traces, the levels').
#[derive(Clone)]
struct Placer {
    area: Rect,
    taken: Vec<Rect>,
    /// Polylines in px that a label must not cross.
    lines: Vec<Vec<(f64, f64)>>,
}

impl Placer {
    fn fits(&self, r: &Rect) -> bool {
        r.inside(&self.area)
            && !self.taken.iter().any(|t| t.overlaps(r))
            && !self.lines.iter().any(|l| {
                l.windows(2).any(|w| crosses(r, w[0], w[1]))
                    || l.len() == 1 && crosses(r, l[0], l[0])
            })
    }

    fn place(
        &mut self,
        text: &str,
        candidates: impl IntoIterator<Item = (f64, f64, Anchor)>,
        also: impl Fn(&Rect) -> bool,
    ) -> Option<(f64, f64, Anchor)> {
        let found = candidates.into_iter().find(|&(x, y, a)| {
            let r = Rect::of_text(x, y, text, FONT, a);
            self.fits(&r) && also(&r)
        })?;
        self.taken
            .push(Rect::of_text(found.0, found.1, text, FONT, found.2));
        Some(found)
    }
}

/// Six places a label may take around a point, `gap` pixels off it: beside, above, below.
fn around((x, y): (f64, f64), gap: f64) -> [(f64, f64, Anchor); 6] {
    [
        (x + gap, y + 4.0, Anchor::Start),
        (x - gap, y + 4.0, Anchor::End),
        (x - gap, y - gap, Anchor::End),
        (x + gap, y - gap, Anchor::Start),
        (x - gap, y + 8.0 + gap, Anchor::End),
        (x + gap, y + 8.0 + gap, Anchor::Start),
    ]
}

/// A leader line from `(x, y)` to the nearest point of the label placed `at`, where the label
/// does not touch the point; the labels placed after it keep off it too.
fn leader(
    out: &mut String,
    placer: &mut Placer,
    (x, y): (f64, f64),
    at: (f64, f64, Anchor),
    label: &str,
    colour: &str,
) {
    let r = Rect::of_text(at.0, at.1, label, FONT, at.2);
    if r.overlaps(&Rect(x - 6.0, y - 6.0, x + 6.0, y + 6.0)) {
        return;
    }
    let (cx, cy) = (x.clamp(r.0, r.2), y.clamp(r.1, r.3));
    let _ = writeln!(
        out,
        r#"<line x1="{x}" y1="{y}" x2="{cx}" y2="{cy}" stroke="{colour}" stroke-width="0.8"/>"#
    );
    placer.lines.push(vec![(x, y), (cx, cy)]);
}

/// A label, on a white halo so that lines under it do not strike it through.
fn text(out: &mut String, (x, y, anchor): (f64, f64, Anchor), colour: &str, label: &str) {
    let _ = writeln!(
        out,
        r#"<text x="{x:.1}" y="{y:.1}" font-size="{FONT}" fill="{colour}" text-anchor="{}" stroke="white" stroke-width="3" stroke-linejoin="round" paint-order="stroke">{}</text>"#,
        anchor.name(),
        escape(label)
    );
}

/// What a legend row shows left of its text.
enum Key {
    /// A line, dashed or not, with its points' mark where it draws them.
    Line(&'static str, Option<&'static str>, Option<Mark>),
    Dot(&'static str, Mark),
    Triangle(&'static str),
}

fn triangle(out: &mut String, x: f64, y: f64, colour: &str) {
    let _ = writeln!(
        out,
        r#"<path d="M{:.1} {:.1} L{:.1} {:.1} L{:.1} {:.1} Z" fill="white" stroke="{colour}" stroke-width="1.5"/>"#,
        x,
        y - 7.0,
        x - 4.5,
        y,
        x + 4.5,
        y
    );
}

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

    /// Draw the panel with its top left corner at (x0, y0); its width.
    fn draw(&self, out: &mut String, x0: f64, y0: f64) -> f64 {
        let all = || {
            self.series
                .iter()
                .filter(|s| !s.style.on_axis)
                .flat_map(|s| s.points.iter())
        };
        let xs = Axis::new(
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .map(|p| p.0)
                .chain(self.guides.iter().map(|g| g.0))
                .chain(self.x_span.into_iter().flat_map(|(a, b)| [a, b])),
            self.log_x,
        );
        let ys = Axis::new(
            all()
                .map(|p| p.1)
                .chain(self.levels.iter().map(|l| l.0))
                .chain(self.markers.iter().map(|m| m.y)),
            self.log_y,
        );
        let width = self.width.unwrap_or(WIDTH);
        let (w, h) = (width - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
        let (left, top) = (x0 + LEFT, y0 + TOP);
        let (right, bottom) = (left + w, top + h);
        let px = |x: f64| xs.fraction(x).map(|f| left + f * w);
        let py = |y: f64| ys.fraction(y).map(|f| top + (1.0 - f) * h);
        // The title over the plot, or from the panel's left when wider than the plot.
        let title_w = 0.65 * 14.0 * self.title.chars().count() as f64;
        let (tx, ta) = if title_w > w {
            (x0 + 8.0, "start")
        } else {
            (left + w / 2.0, "middle")
        };
        let _ = writeln!(
            out,
            r#"<text x="{tx}" y="{}" text-anchor="{ta}" font-size="14" font-weight="bold">{}</text>"#,
            y0 + 20.0,
            escape(&self.title)
        );
        let _ = writeln!(
            out,
            r##"<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="#444"/>"##,
        );
        for (v, label) in xs.ticks() {
            if let Some(x) = px(v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{x}" y1="{top}" x2="{x}" y2="{bottom}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle" font-size="{FONT}">{label}</text>"##,
                    bottom + 15.0
                );
            }
        }
        for (v, label) in ys.ticks() {
            if let Some(y) = py(v) {
                let _ = writeln!(
                    out,
                    r##"<line x1="{left}" y1="{y}" x2="{right}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end" font-size="{FONT}">{label}</text>"##,
                    left - 4.0,
                    y + 4.0
                );
            }
        }
        let _ = writeln!(
            out,
            r#"<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>"#,
            left + w / 2.0,
            y0 + HEIGHT - 12.0,
            escape(&self.x_label)
        );
        let (yx, yy) = (x0 + 16.0, top + h / 2.0);
        let _ = writeln!(
            out,
            r#"<text x="{yx}" y="{yy}" text-anchor="middle" font-size="12" transform="rotate(-90 {yx} {yy})">{}</text>"#,
            escape(&self.y_label)
        );

        // Each series' points in px, thinned to what a pixel column shows (drawn below, and
        // kept clear by the labels); none for points drawn on the axis.
        let traces: Vec<Vec<(f64, f64)>> = self
            .series
            .iter()
            .map(|series| {
                if series.style.on_axis {
                    return Vec::new();
                }
                envelope(
                    series
                        .points
                        .iter()
                        .filter_map(|&(x, y)| Some((px(x)?, py(y)?))),
                    (MAX_POINTS_PER_PIXEL * w) as usize,
                )
            })
            .collect();
        // Labels inside the plot, over no other and across no trace: the markers' crosses
        // first.
        let mut placer = Placer {
            area: Rect(left + 1.0, top + 1.0, right - 1.0, bottom - 1.0),
            taken: Vec::new(),
            lines: Vec::new(),
        };
        for (series, trace) in self.series.iter().zip(&traces) {
            if series.style.dots_only {
                placer.taken.extend(
                    trace
                        .iter()
                        .map(|&(x, y)| Rect(x - 3.0, y - 3.0, x + 3.0, y + 3.0)),
                );
            } else {
                placer.lines.push(trace.clone());
            }
            if series.style.on_axis {
                for x in series.points.iter().filter_map(|p| px(p.0)) {
                    placer
                        .taken
                        .push(Rect(x - 5.0, bottom - 8.0, x + 5.0, bottom));
                }
            }
        }
        let crosses: Vec<(f64, f64, &Marker)> = self
            .markers
            .iter()
            .filter_map(|m| Some((px(m.x)?, py(m.y)?, m)))
            .collect();
        for (x, y, _) in &crosses {
            placer.taken.push(Rect(x - 6.0, y - 6.0, x + 6.0, y + 6.0));
        }
        let mut legend: Vec<(Option<Key>, String)> = Vec::new();
        let mut labels = String::new();

        let level_ys: Vec<f64> = self.levels.iter().filter_map(|l| py(l.0)).collect();
        // Marker labels: near the cross, the nearest place that is clear.
        for (x, y, m) in &crosses {
            let mut candidates = Vec::new();
            for dy in [-7.0, 15.0, -20.0, 28.0, -33.0, 41.0] {
                for (dx, a) in [(8.0, Anchor::Start), (-8.0, Anchor::End)] {
                    candidates.push((x + dx, y + dy, a));
                }
            }
            for (dx, a) in [(10.0, Anchor::Start), (-10.0, Anchor::End)] {
                candidates.push((x + dx, y + 4.0, a));
            }
            // Not across a level's line, where it would read as that line's label.
            let clear = |r: &Rect| !level_ys.iter().any(|l| *l >= r.1 && *l <= r.3);
            if let Some(at) = placer.place(&m.label, candidates, clear) {
                text(&mut labels, at, m.colour, &m.label);
                continue;
            }
            if m.label.is_empty() {
                continue;
            }
            // Where the marks crowd: a little off, with a leader line to the cross.
            let far = [16.0, 28.0, 44.0, 64.0]
                .into_iter()
                .flat_map(|gap| around((*x, *y), gap));
            if let Some(at) = placer.place(&m.label, far, clear) {
                leader(&mut labels, &mut placer, (*x, *y), at, &m.label, m.colour);
                text(&mut labels, at, m.colour, &m.label);
            } else {
                legend.push((None, format!("× {}", m.label)));
            }
        }

        // Levels: a label beside its own line, on a side where no other level's line is
        // near (so it cannot be read as that one's); if one has no such place, all go in
        // the legend.
        let lines: Vec<(f64, &String)> = self
            .levels
            .iter()
            .filter_map(|(v, l)| Some((py(*v)?, l)))
            .collect();
        let mut trial = placer.clone();
        let mut inline = Vec::new();
        for (k, &(y, label)) in lines.iter().enumerate() {
            let others: Vec<f64> = lines
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, l)| l.0)
                .collect();
            let candidates = [right - 4.0, left + 4.0, left + w / 2.0]
                .into_iter()
                .zip([Anchor::End, Anchor::Start, Anchor::Middle])
                // Below or above the line, clear of it (a box reaches 0.3 of the font
                // under its baseline).
                .flat_map(|(x, a)| [(x, y + 13.0, a), (x, y - 5.0, a)]);
            let clear = |r: &Rect| {
                let (a, b) = (r.1.min(y) - 4.0, r.3.max(y) + 4.0);
                !others.iter().any(|o| *o >= a && *o <= b)
            };
            match trial.place(label, candidates, clear) {
                Some(at) => inline.push((at, label)),
                None => break,
            }
        }
        let levels_inline = inline.len() == lines.len();
        if levels_inline {
            placer = trial;
            for (at, label) in inline {
                text(&mut labels, at, RED, label);
            }
        }
        // The series' labels, placed next, cross no level's line either.
        placer
            .lines
            .extend(lines.iter().map(|&(y, _)| vec![(left, y), (right, y)]));
        let mut back = String::new();
        for (k, &(y, label)) in lines.iter().enumerate() {
            let (colour, dash) = if levels_inline {
                LEVEL_STYLES[0]
            } else {
                LEVEL_STYLES[k % LEVEL_STYLES.len()]
            };
            let _ = writeln!(
                back,
                r#"<line x1="{left}" y1="{y}" x2="{right}" y2="{y}" stroke="{colour}" stroke-width="1.2" stroke-dasharray="{dash}"/>"#,
            );
            if !levels_inline {
                legend.push((Some(Key::Line(colour, Some(dash), None)), label.clone()));
            }
        }

        // Series' own labels: at the end, else along the line from its end.
        for (k, series) in self.series.iter().enumerate() {
            if series.label.is_empty() {
                continue;
            }
            let colour = series.style.colour.unwrap_or(COLOURS[k % COLOURS.len()]);
            let along: Vec<(f64, f64)> = series
                .points
                .iter()
                .rev()
                .filter_map(|&(x, y)| Some((px(x)?, py(y)?)))
                .collect();
            let step = (along.len() / 24).max(1);
            // Beside a point of the line; failing that, a little off it with a leader line
            // to the point (where the lines crowd).
            let beside = |p: (f64, f64), gap: f64| around(p, gap).map(|c| (p, c));
            let candidates = [5.0, 16.0, 28.0, 44.0, 64.0].into_iter().flat_map(|gap| {
                along
                    .iter()
                    .step_by(step)
                    .flat_map(move |&p| beside(p, gap))
            });
            let mut from = None;
            let found = placer.place(
                &series.label,
                candidates.map(|(p, c)| {
                    from = Some(p);
                    c
                }),
                |_| true,
            );
            match (found, from) {
                (Some(at), Some(point)) => {
                    leader(&mut labels, &mut placer, point, at, &series.label, colour);
                    text(&mut labels, at, colour, &series.label)
                }
                _ => legend.push((None, format!("{} (no room on the plot)", series.label))),
            }
        }

        // Guides: labels along the top in up to three rows, clear of other guides' lines;
        // if one does not fit, a colour per distinct label and the labels in the legend.
        let guides: Vec<(f64, &String)> = self
            .guides
            .iter()
            .filter_map(|(v, l)| Some((px(*v)?, l)))
            .collect();
        let mut trial = placer.clone();
        let mut inline = Vec::new();
        for &(x, label) in &guides {
            let candidates = (0..3).flat_map(|row| {
                let y = top + 13.0 + 13.0 * row as f64;
                [(x + 3.0, y, Anchor::Start), (x - 3.0, y, Anchor::End)]
            });
            let clear = |r: &Rect| {
                !guides
                    .iter()
                    .any(|&(g, _)| g != x && g >= r.0 - 1.0 && g <= r.2 + 1.0)
            };
            match trial.place(label, candidates, clear) {
                Some(at) => inline.push((at, label)),
                None => break,
            }
        }
        // A colour per distinct label, the same inline or in the legend.
        let kinds = self.guide_kinds();
        let colour_of = |label: &String| {
            GUIDE_COLOURS[kinds.iter().position(|k| k == label).unwrap_or(0) % GUIDE_COLOURS.len()]
        };
        let guides_inline = inline.len() == guides.len();
        if guides_inline {
            for (at, label) in inline {
                text(&mut labels, at, colour_of(label), label);
            }
        }
        for &(x, label) in &guides {
            let _ = writeln!(
                back,
                r#"<line x1="{x}" y1="{top}" x2="{x}" y2="{bottom}" stroke="{}" stroke-dasharray="4 3"/>"#,
                colour_of(label)
            );
        }
        for kind in &kinds {
            let n = guides.iter().filter(|g| g.1 == kind).count();
            if guides_inline || n == 0 {
                continue;
            }
            let times = if n > 1 {
                format!(" (×{n})")
            } else {
                String::new()
            };
            legend.push((
                Some(Key::Line(colour_of(kind), Some("4 3"), None)),
                format!("{kind}{times}"),
            ));
        }
        out.push_str(&back);

        // The data.
        let mut named: Vec<(Option<Key>, String)> = Vec::new();
        for (k, series) in self.series.iter().enumerate() {
            let colour = series.style.colour.unwrap_or(COLOURS[k % COLOURS.len()]);
            let dash = series.style.dashed.then_some("5 3");
            if series.style.on_axis {
                for x in series.points.iter().filter_map(|p| px(p.0)) {
                    triangle(out, x, bottom - 1.0, colour);
                }
                if !series.name.is_empty() {
                    named.push((Some(Key::Triangle(colour)), series.name.clone()));
                }
                continue;
            }
            let dots = &traces[k];
            if !series.style.dots_only {
                let path: Vec<String> =
                    dots.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
                let dash = dash
                    .map(|d| format!(r#" stroke-dasharray="{d}""#))
                    .unwrap_or_default();
                let _ = writeln!(
                    out,
                    r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#,
                    path.join(" ")
                );
            }
            let marked = dots.len() <= 40 || series.style.dots_only;
            if marked {
                for &(x, y) in dots {
                    series.style.mark.draw(out, x, y, 2.5, colour);
                }
            }
            if !series.name.is_empty() {
                let key = if series.style.dots_only {
                    Key::Dot(colour, series.style.mark)
                } else {
                    Key::Line(colour, dash, marked.then_some(series.style.mark))
                };
                named.push((Some(key), series.name.clone()));
            }
        }
        for (x, y, m) in &crosses {
            let c = m.colour;
            let _ = writeln!(
                out,
                r#"<path d="M{} {} L{} {} M{} {} L{} {}" stroke="{c}" stroke-width="2.5"/>"#,
                x - 5.0,
                y - 5.0,
                x + 5.0,
                y + 5.0,
                x - 5.0,
                y + 5.0,
                x + 5.0,
                y - 5.0,
            );
        }
        out.push_str(&labels);

        // The legend's column, right of the plot, so it never covers a trace: the series,
        // then what went there for want of room, then the notes.
        named.append(&mut legend);
        let lx = right + 12.0;
        let mut widest: f64 = 0.0;
        let mut row = 0;
        for (key, label) in &named {
            let ly = top + 14.0 + 15.0 * row as f64;
            row += 1;
            let tx = match key {
                Some(_) => lx + 22.0,
                None => lx,
            };
            match key {
                Some(Key::Line(colour, dash, mark)) => {
                    let dash = dash
                        .map(|d| format!(r#" stroke-dasharray="{d}""#))
                        .unwrap_or_default();
                    let _ = writeln!(
                        out,
                        r#"<line x1="{lx}" y1="{}" x2="{}" y2="{}" stroke="{colour}" stroke-width="2"{dash}/>"#,
                        ly - 4.0,
                        lx + 18.0,
                        ly - 4.0,
                    );
                    if let Some(mark) = mark {
                        mark.draw(out, lx + 9.0, ly - 4.0, 3.0, colour);
                    }
                }
                Some(Key::Dot(colour, mark)) => mark.draw(out, lx + 9.0, ly - 4.0, 3.0, colour),
                Some(Key::Triangle(colour)) => triangle(out, lx + 9.0, ly, colour),
                None => {}
            }
            let colour = if key.is_some() { "black" } else { "#555" };
            text(out, (tx, ly, Anchor::Start), colour, label);
            widest = widest.max(tx - lx + CHAR * FONT * label.chars().count() as f64);
        }
        if !named.is_empty() && !self.notes.is_empty() {
            row += 1;
        }
        for note in &self.notes {
            let ly = top + 14.0 + 15.0 * row as f64;
            row += 1;
            text(out, (lx, ly, Anchor::Start), "#555", note);
            widest = widest.max(CHAR * FONT * note.chars().count() as f64);
        }
        if row == 0 {
            width
        } else {
            width + 12.0 + widest + 16.0
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_of_ten_are_written_as_people_write_them() {
        let written: Vec<String> = [-12, -3, -1, 0, 1, 2, 3, 10].map(power_of_ten).into();
        assert_eq!(
            written,
            ["10⁻¹²", "10⁻³", "10⁻¹", "1", "10", "100", "10³", "10¹⁰"]
        );
    }

    #[test]
    fn positions_are_rounded_and_text_is_not() {
        let svg = r##"<line x1="715.02" y1="339.3206085338543" stroke="#d55e00" stroke-dasharray="4 3"/><text x="-0.001">"2.166666"</text><polyline points="1.005,2.5e-3 3,4"/>"##;
        assert_eq!(
            round_attributes(svg),
            r##"<line x1="715.02" y1="339.32" stroke="#d55e00" stroke-dasharray="4 3"/><text x="0">"2.166666"</text><polyline points="1,0 3,4"/>"##
        );
    }

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

    /// A panel of two named lines.
    fn two_series(first: &str, second: &str) -> Panel {
        let line = |name: &str, points: Vec<(f64, f64)>| Series {
            name: name.into(),
            points,
            ..Series::default()
        };
        Panel {
            series: vec![
                line(first, vec![(1.0, 1.0), (2.0, 4.0)]),
                line(second, vec![(1.0, 2.0), (2.0, 3.0)]),
            ],
            ..Panel::default()
        }
    }

    #[test]
    fn svg_is_one_document_with_a_line_per_series() {
        let panel = Panel {
            title: "a < b".into(),
            ..two_series("one", "two")
        };
        let doc = svg(&[panel.clone(), panel]);
        assert!(doc.starts_with("<svg") && doc.ends_with("</svg>\n"));
        assert_eq!(doc.matches("<polyline").count(), 4);
        assert!(doc.contains("a &lt; b"));
    }

    /// Panels stacked in a column share their left edge whatever the legends beside the
    /// panels before them (a plot with its zoom beside it, on two rows).
    #[test]
    fn a_columns_panels_share_their_left_edge() {
        let zoom = Panel {
            series: vec![Series {
                points: vec![(1.0, 1.0), (2.0, 4.0)],
                ..Series::default()
            }],
            ..Panel::default()
        };
        let (short, long) = (two_series("a", "b"), two_series("amplifier output", "b"));
        let doc = svg(&[short, zoom.clone(), long, zoom]);
        // The plot frames' corners, in the order drawn: row 0's two, then row 1's.
        let frames: Vec<(f64, f64)> = doc
            .lines()
            .filter(|l| l.starts_with("<rect x=") && l.contains(r##"stroke="#444""##))
            .map(|l| {
                let number = |key: &str| -> f64 {
                    let rest = &l[l.find(key).unwrap() + key.len()..];
                    rest[..rest.find('"').unwrap()].parse().unwrap()
                };
                (number(" x=\""), number(" y=\""))
            })
            .collect();
        assert_eq!(frames.len(), 4, "{frames:?}");
        assert!(frames[0].1 < frames[2].1, "two rows: {frames:?}");
        assert_eq!(frames[0].0, frames[2].0, "{frames:?}");
        assert_eq!(frames[1].0, frames[3].0, "{frames:?}");
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

    /// Three panels with legends (e.g. a study over three scenes) wrap onto rows: the page
    /// stays within `MAX_WIDTH` and its text at its size.
    #[test]
    fn panels_wrap_within_the_page_width() {
        let panel = Panel {
            series: vec![Series {
                name: "a long series name for the legend".into(),
                points: vec![(1.0, 1.0), (2.0, 4.0)],
                ..Series::default()
            }],
            ..Panel::default()
        };
        let doc = svg(&[panel.clone(), panel.clone(), panel]);
        let head = doc.lines().next().unwrap();
        let width: f64 = head
            .split("width=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(width <= MAX_WIDTH, "{width}");
        assert!(
            head.contains(&format!("height=\"{}\"", 3.0 * HEIGHT)),
            "{head}"
        );
    }

    /// Two levels close together (a cap just under a limit) are told apart: each its own
    /// dash pattern and its label once, in the legend.
    #[test]
    fn close_levels_are_told_apart() {
        let panel = Panel {
            series: vec![Series {
                name: "output".into(),
                points: vec![(0.0, 0.0), (10.0, 7400.0)],
                ..Series::default()
            }],
            levels: vec![(9362.0, "cap".into()), (9855.0, "limit".into())],
            ..Panel::default()
        };
        let doc = svg(&[panel]);
        let dashes: Vec<&str> = doc
            .lines()
            .filter(|l| l.contains("stroke-width=\"1.2\""))
            .filter_map(|l| l.split("stroke-dasharray=\"").nth(1)?.split('"').next())
            .collect();
        assert_eq!(dashes.len(), 2);
        assert_ne!(dashes[0], dashes[1]);
        assert_eq!(doc.matches(">cap<").count(), 1);
        assert_eq!(doc.matches(">limit<").count(), 1);
    }

    #[test]
    fn a_segment_crosses_a_box_only_through_it() {
        let r = Rect(10.0, 10.0, 20.0, 20.0);
        assert!(crosses(&r, (0.0, 15.0), (30.0, 15.0)));
        assert!(crosses(&r, (15.0, 15.0), (15.0, 15.0)));
        assert!(crosses(&r, (0.0, 0.0), (30.0, 30.0)));
        assert!(!crosses(&r, (0.0, 25.0), (30.0, 25.0)));
        assert!(!crosses(&r, (0.0, 12.0), (9.0, 30.0)));
        assert!(!crosses(&r, (21.0, 0.0), (21.0, 30.0)));
    }

    /// The numbers of an attribute in an SVG line.
    fn attribute(line: &str, name: &str) -> Option<String> {
        let at = line.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(line[at..].split('"').next()?.to_string())
    }

    /// Every label drawn on the plot (the halo'd texts but the legend's, which starts right
    /// of the plot) against every line drawn: the traces' polylines and the levels', read
    /// back from the SVG.
    fn labels_and_lines(doc: &str, plot_right: f64) -> (Vec<Rect>, Vec<Vec<(f64, f64)>>) {
        let mut boxes = Vec::new();
        let mut lines = Vec::new();
        for line in doc.lines() {
            let num = |n: &str| attribute(line, n).and_then(|v| v.parse::<f64>().ok());
            if line.starts_with("<text") && line.contains("paint-order") {
                let (Some(x), Some(y)) = (num("x"), num("y")) else {
                    continue;
                };
                let anchor = match attribute(line, "text-anchor").as_deref() {
                    Some("end") => Anchor::End,
                    Some("middle") => Anchor::Middle,
                    _ => Anchor::Start,
                };
                let words = line
                    .split('>')
                    .nth(1)
                    .unwrap_or("")
                    .split('<')
                    .next()
                    .unwrap_or("");
                if x < plot_right {
                    boxes.push(Rect::of_text(x, y, words, FONT, anchor));
                }
            } else if line.starts_with("<polyline") {
                let points = attribute(line, "points").unwrap_or_default();
                lines.push(
                    points
                        .split(' ')
                        .filter_map(|p| {
                            let (x, y) = p.split_once(',')?;
                            Some((x.parse().ok()?, y.parse().ok()?))
                        })
                        .collect(),
                );
            } else if line.starts_with("<line") && line.contains("stroke-width=\"1.2\"") {
                if let (Some(a), Some(b), Some(c), Some(d)) =
                    (num("x1"), num("y1"), num("x2"), num("y2"))
                {
                    lines.push(vec![(a, b), (c, d)]);
                }
            }
        }
        (boxes, lines)
    }

    #[test]
    fn no_label_crosses_a_line_or_another_label() {
        // A family of crowded curves, each labelled, a level through them and markers on them.
        let series: Vec<Series> = (0..12)
            .map(|k| Series {
                name: format!("curve {k}"),
                points: (0..200)
                    .map(|i| {
                        let x = f64::from(i) / 20.0;
                        (
                            x,
                            (x * (1.0 + 0.05 * f64::from(k))).sin() + 0.1 * f64::from(k),
                        )
                    })
                    .collect(),
                label: format!("k = {k}"),
                ..Series::default()
            })
            .collect();
        let panel = Panel {
            series,
            levels: vec![(1.2, "limit".into()), (-0.4, "floor".into())],
            markers: vec![Marker {
                x: 5.0,
                y: 5f64.sin(),
                label: "crossing at 5 s".into(),
                colour: RED,
            }],
            ..Panel::default()
        };
        let doc = svg(&[panel]);
        let (boxes, lines) = labels_and_lines(&doc, LEFT + WIDTH - LEFT - RIGHT);
        // Most of the 12 curves' labels, the marker's and the levels' find room on the plot
        // (the rest go to the legend), so the checks below are not of an empty plot.
        assert!(boxes.len() >= 10, "{} labels on the plot", boxes.len());
        for (k, b) in boxes.iter().enumerate() {
            for l in &lines {
                // A level's own label sits beside its line, not across it.
                assert!(
                    !l.windows(2).any(|w| crosses(b, w[0], w[1])),
                    "label {k} at {b:?} crosses a line"
                );
            }
            for (j, o) in boxes.iter().enumerate() {
                assert!(j == k || !b.overlaps(o), "labels {k} and {j} overlap");
            }
        }
    }

    #[test]
    fn a_zoom_keeps_its_guides_colours() {
        let panel = Panel {
            series: vec![Series {
                name: "run".into(),
                points: (0..100).map(|i| (f64::from(i), f64::from(i % 7))).collect(),
                ..Series::default()
            }],
            guides: vec![
                (10.0, "at bias".into()),
                (50.0, "drive on".into()),
                (90.0, "fault".into()),
            ],
            ..Panel::default()
        };
        // The guides' lines' colours, left to right.
        let colours = |doc: &str| -> Vec<String> {
            doc.lines()
                .filter(|l| l.starts_with("<line") && l.contains("stroke-dasharray=\"4 3\""))
                // Not the legend's keys, which are drawn thicker.
                .filter(|l| !l.contains("stroke-width"))
                .filter_map(|l| attribute(l, "stroke"))
                .collect()
        };
        let whole = colours(&svg(std::slice::from_ref(&panel)));
        let zoom = colours(&svg(&[panel.zoom(80.0, 99.0, "the end".into())]));
        assert_eq!(whole.len(), 3);
        assert!(whole[0] != whole[1] && whole[1] != whole[2] && whole[0] != whole[2]);
        assert_eq!(zoom, [whole[2].clone()]);
    }

    #[test]
    fn each_series_mark_is_drawn_at_its_points_and_in_its_legend_key() {
        let series = |name: &str, mark| Series {
            name: name.into(),
            points: vec![(1.0, 1.0), (2.0, 2.0), (3.0, 1.5)],
            style: Style {
                mark,
                ..Style::default()
            },
            ..Series::default()
        };
        let doc = svg(&[Panel {
            series: vec![
                series("circles", Mark::Circle),
                series("squares", Mark::Square),
                series("diamonds", Mark::Diamond),
            ],
            ..Panel::default()
        }]);
        // Three points and a legend key each.
        assert_eq!(doc.matches("<circle").count(), 4);
        assert_eq!(
            doc.matches("<rect x=").count(),
            1 + 4,
            "the frame and the squares"
        );
        assert_eq!(doc.matches(" Z\" fill=").count(), 4);
    }
}
