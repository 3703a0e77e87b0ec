//! Text on the page: escaped, anchored, and placed where it crosses no line and no other
//! label (with a leader line back to its point where it had to move).

use std::fmt::Write;

use super::{Mark, CHAR, FONT};

pub(super) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Where a text's x is: its start, middle or end (SVG's text-anchor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    pub(super) fn name(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// A box on the page, px: left, top, right, bottom.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rect(
    pub(super) f64,
    pub(super) f64,
    pub(super) f64,
    pub(super) f64,
);

impl Rect {
    pub(super) fn overlaps(&self, o: &Rect) -> bool {
        self.0 < o.2 && o.0 < self.2 && self.1 < o.3 && o.1 < self.3
    }

    pub(super) fn inside(&self, o: &Rect) -> bool {
        self.0 >= o.0 && self.2 <= o.2 && self.1 >= o.1 && self.3 <= o.3
    }

    /// The box of `text` at `size` px with its baseline at y (a pixel of room around it).
    pub(super) fn of_text(x: f64, y: f64, text: &str, size: f64, anchor: Anchor) -> Rect {
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
pub(super) fn crosses(r: &Rect, (ax, ay): (f64, f64), (bx, by): (f64, f64)) -> bool {
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
pub(super) struct Placer {
    pub(super) area: Rect,
    pub(super) taken: Vec<Rect>,
    /// Polylines in px that a label must not cross.
    pub(super) lines: Vec<Vec<(f64, f64)>>,
}

impl Placer {
    pub(super) fn fits(&self, r: &Rect) -> bool {
        r.inside(&self.area)
            && !self.taken.iter().any(|t| t.overlaps(r))
            && !self.lines.iter().any(|l| {
                l.windows(2).any(|w| crosses(r, w[0], w[1]))
                    || l.len() == 1 && crosses(r, l[0], l[0])
            })
    }

    pub(super) fn place(
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
pub(super) fn around((x, y): (f64, f64), gap: f64) -> [(f64, f64, Anchor); 6] {
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
pub(super) fn leader(
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
pub(super) fn text(
    out: &mut String,
    (x, y, anchor): (f64, f64, Anchor),
    colour: &str,
    label: &str,
) {
    let _ = writeln!(
        out,
        r#"<text x="{x:.1}" y="{y:.1}" font-size="{FONT}" fill="{colour}" text-anchor="{}" stroke="white" stroke-width="3" stroke-linejoin="round" paint-order="stroke">{}</text>"#,
        anchor.name(),
        escape(label)
    );
}

/// What a legend row shows left of its text.
pub(super) enum Key {
    /// A line, dashed or not, with its points' mark where it draws them.
    Line(&'static str, Option<&'static str>, Option<Mark>),
    Dot(&'static str, Mark),
    Triangle(&'static str),
}

pub(super) fn triangle(out: &mut String, x: f64, y: f64, colour: &str) {
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
