use super::draw::envelope;
use super::labels::{crosses, Anchor, Rect};
use super::*;

#[test]
fn positions_are_rounded_and_text_is_not() {
    let svg = r##"<line x1="715.02" y1="339.3206085338543" stroke="#d55e00" stroke-dasharray="4 3"/><text x="-0.001">"2.166666"</text><polyline points="1.005,2.5e-3 3,4"/>"##;
    assert_eq!(
        round_attributes(svg),
        r##"<line x1="715.02" y1="339.32" stroke="#d55e00" stroke-dasharray="4 3"/><text x="0">"2.166666"</text><polyline points="1,0 3,4"/>"##
    );
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
