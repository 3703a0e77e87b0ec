//! A panel drawn: its axes, guides, levels, series (long ones as their envelope), markers
//! and legend.

use std::fmt::Write;

use super::axis::Axis;
use super::labels::{around, escape, leader, text, triangle, Anchor, Key, Placer, Rect};
use super::*;

impl Panel {
    /// Draw the panel with its top left corner at (x0, y0); its width.
    pub(super) fn draw(&self, out: &mut String, x0: f64, y0: f64) -> f64 {
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
pub(super) fn envelope(
    points: impl Iterator<Item = (f64, f64)>,
    columns: usize,
) -> Vec<(f64, f64)> {
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
