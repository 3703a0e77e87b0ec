//! The plots the commands draw, read back as SVG text: labels readable (none over another),
//! what is not data not drawn as data, marks where they say they are.

mod common;

use std::path::Path;

use host_sim::plot::RED;
use serde_json::Value;

/// Run host-sim (exit status 0, or 1 for a limit crossed); its JSON report.
fn ran(args: &[&str]) -> Value {
    let out = common::host_sim()
        .args(args)
        .output()
        .expect("host-sim runs");
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or(Value::Null)
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// An attribute's value in one element's text.
fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let at = element.find(&format!(" {name}=\""))? + name.len() + 3;
    element[at..].split('"').next()
}

fn num(element: &str, name: &str) -> f64 {
    attr(element, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{name} in {element}"))
}

/// A text element: its box estimated at 0.6 × font size a character, one font size high.
#[derive(Debug)]
struct Text {
    content: String,
    x: f64,
    y: f64,
    fill: String,
    left: f64,
    top: f64,
    right: f64,
    bottom: f64,
}

/// Every unrotated text of the document.
fn texts(svg: &str) -> Vec<Text> {
    svg.split("<text")
        .skip(1)
        .filter_map(|rest| {
            let (head, tail) = rest.split_once('>')?;
            if head.contains("transform") {
                return None;
            }
            let content = tail
                .split("</text>")
                .next()?
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&amp;", "&");
            let size = attr(head, "font-size").map_or(16.0, |s| s.parse().unwrap());
            let (x, y) = (num(head, "x"), num(head, "y"));
            let w = 0.6 * size * content.chars().count() as f64;
            let left = match attr(head, "text-anchor").unwrap_or("start") {
                "middle" => x - w / 2.0,
                "end" => x - w,
                _ => x,
            };
            Some(Text {
                content,
                x,
                y,
                fill: attr(head, "fill").unwrap_or("black").to_string(),
                left,
                top: y - 0.8 * size,
                right: left + w,
                bottom: y + 0.2 * size,
            })
        })
        .collect()
}

/// No two texts' boxes overlap, and no label inside a plot's frame lies on a line drawn
/// there: a trace (a polyline) or a level (a horizontal line 1.2 px wide), each walked in
/// half-pixel steps.
fn no_overlaps(name: &str, svg: &str) {
    let all = texts(svg);
    for (i, a) in all.iter().enumerate() {
        for b in &all[i + 1..] {
            let overlap =
                a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
            assert!(!overlap, "{name}: {:?} overlaps {:?}", a.content, b.content);
        }
    }
    let frames: Vec<(f64, f64, f64, f64)> = svg
        .lines()
        .filter(|l| l.starts_with("<rect x=") && l.contains("fill=\"none\""))
        .map(|l| {
            let (x, y) = (num(l, "x"), num(l, "y"));
            (x, y, x + num(l, "width"), y + num(l, "height"))
        })
        .collect();
    let mut lines: Vec<Vec<(f64, f64)>> = Vec::new();
    for l in svg.lines() {
        if l.starts_with("<polyline") {
            lines.push(
                attr(l, "points")
                    .unwrap_or("")
                    .split_whitespace()
                    .filter_map(|p| {
                        let (x, y) = p.split_once(',')?;
                        Some((x.parse().ok()?, y.parse().ok()?))
                    })
                    .collect(),
            );
        } else if l.starts_with("<line") && l.contains("stroke-width=\"1.2\"") {
            lines.push(vec![
                (num(l, "x1"), num(l, "y1")),
                (num(l, "x2"), num(l, "y2")),
            ]);
        }
    }
    let inside_a_frame = |t: &Text| {
        frames
            .iter()
            .any(|f| t.left >= f.0 && t.right <= f.2 && t.top >= f.1 && t.bottom <= f.3)
    };
    for t in all.iter().filter(|t| inside_a_frame(t)) {
        for line in &lines {
            for w in line.windows(2) {
                let ((x0, y0), (x1, y1)) = (w[0], w[1]);
                let steps = ((x1 - x0).hypot(y1 - y0) / 0.5).ceil().max(1.0) as usize;
                let on = (0..=steps).any(|k| {
                    let f = k as f64 / steps as f64;
                    let (x, y) = (x0 + f * (x1 - x0), y0 + f * (y1 - y0));
                    x > t.left && x < t.right && y > t.top && y < t.bottom
                });
                assert!(!on, "{name}: the label {:?} lies on a line", t.content);
            }
        }
    }
}

/// The document's width and height.
fn size(svg: &str) -> (f64, f64) {
    let head = svg.split('>').next().unwrap();
    (num(head, "width"), num(head, "height"))
}

fn out_dir(name: &str) -> String {
    let dir = common::scratch(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir.to_str().unwrap().to_string()
}

/// Tuning curve: the max bias's label clear of the legend, the tunable range's clear of the
/// limit's; no label over another anywhere.
#[test]
fn tuning_curve_labels_do_not_overlap() {
    let dir = out_dir("plots-curve");
    ran(&["curve", "--target-hz", "44", "--out", &dir, "--json"]);
    let svg = read(&Path::new(&dir).join("curve.svg"));
    no_overlaps("curve.svg", &svg);
    for label in ["max bias", "tunable range", "limit (emi)", "target 44"] {
        assert!(svg.contains(label), "{label}");
    }
}

/// A family of tuning curves: each curve has a label naming its λ1p, in its colour.
#[test]
fn each_family_curve_says_its_prestretch() {
    let dir = out_dir("plots-family");
    let v = ran(&[
        "curve",
        "--prestretch-1",
        "1.5:3:7",
        "--prestretch-2",
        "1.5:2.5:3",
        "--out",
        &dir,
        "--json",
    ]);
    let svg = read(&Path::new(&dir).join("curve.svg"));
    no_overlaps("curve family", &svg);
    let labels = texts(&svg);
    let curves = v["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 21);
    // Each λ2p group's first and last curve says its λ1p, in the group's colour (one colour
    // a group); the ones between are the legend's range (more labels would pile up).
    let ends = |l1: f64| {
        curves
            .iter()
            .filter(|c| c["prestretch_1"].as_f64() == Some(l1))
            .filter(|c| {
                let group: Vec<f64> = curves
                    .iter()
                    .filter(|d| d["prestretch_2"] == c["prestretch_2"])
                    .filter_map(|d| d["prestretch_1"].as_f64())
                    .collect();
                group.first() == Some(&l1) || group.last() == Some(&l1)
            })
            .count()
    };
    for c in curves {
        let l1 = c["prestretch_1"].as_f64().unwrap();
        let named: Vec<&Text> = labels
            .iter()
            .filter(|t| {
                t.content
                    .strip_prefix("λ1p ")
                    .and_then(|v| v.parse::<f64>().ok())
                    .is_some_and(|v| (v - l1).abs() < 1e-9)
            })
            .collect();
        assert_eq!(named.len(), ends(l1), "λ1p {l1}: {named:?}");
        let mut colours: Vec<&str> = named.iter().map(|t| t.fill.as_str()).collect();
        colours.sort();
        colours.dedup();
        assert_eq!(colours.len(), named.len(), "λ1p {l1}: {colours:?}");
    }
    // Each group's edge in the legend, by its λ2p.
    for l2 in ["1.5", "2", "2.5"] {
        let edge = format!("λ2p {l2}: the safe region's edge (limits)");
        assert!(labels.iter().any(|t| t.content == edge), "{edge}");
    }
}

/// The run's plot: beside each whole-run panel, the last 5 periods of the drive ("at the end") (the default
/// scene's AC of 40 Hz over 10 s: 9.875 to 10 s); the cap's and limit's labels and the events'
/// labels distinct and clear of each other.
#[test]
fn run_plot_has_a_zoom_of_the_last_periods() {
    let dir = out_dir("plots-run");
    ran(&["run", "--out", &dir, "--json"]);
    let svg = read(&Path::new(&dir).join("reference/run.svg"));
    no_overlaps("run.svg", &svg);
    let all = texts(&svg);
    let zooms: Vec<&Text> = all
        .iter()
        .filter(|t| t.content.starts_with("5 periods of 40 Hz at the end"))
        .collect();
    assert_eq!(zooms.len(), 2, "a zoom of the stretch and of the voltage");
    for zoom in zooms {
        // The zoom panel's frame: on the title's row, the plot the title stands over (or
        // starts left of, when wider than it); its x ticks under it.
        let frame = svg
            .lines()
            .filter(|l| l.starts_with("<rect x=") && l.contains("fill=\"none\""))
            .find(|l| {
                let (x, w) = (num(l, "x"), num(l, "width"));
                (num(l, "y") - (zoom.y - 20.0 + 36.0)).abs() < 0.5
                    && zoom.x >= x - 70.0
                    && zoom.x <= x + w
            })
            .expect("the zoom's frame");
        let (x, w, y) = (num(frame, "x"), num(frame, "width"), num(frame, "y"));
        let ticks: Vec<f64> = all
            .iter()
            .filter(|t| (t.y - (y + num(frame, "height") + 15.0)).abs() < 0.5)
            .filter(|t| t.x >= x - 0.5 && t.x <= x + w + 0.5)
            .filter_map(|t| t.content.parse().ok())
            .collect();
        let (low, high) = (10.0 - 5.0 / 40.0, 10.0);
        assert!(
            ticks.iter().all(|&t| t >= low - 1e-9 && t <= high + 1e-9),
            "{ticks:?} not within the last 5 periods"
        );
        assert!(ticks.iter().any(|&t| t < low + 0.05) && ticks.iter().any(|&t| t > high - 0.05));
    }
    // The cap and the limit: two lines told apart (each its own dash pattern, or each
    // label beside only its own line).
    let dashes: Vec<&str> = svg
        .lines()
        .filter(|l| l.starts_with("<line") && l.contains("stroke-width=\"1.2\""))
        .filter_map(|l| attr(l, "stroke-dasharray"))
        .collect();
    assert!(svg.contains("controller's cap") && svg.contains("static limit (emi)"));
    let mut distinct = dashes.clone();
    distinct.sort();
    distinct.dedup();
    assert!(distinct.len() >= 2, "{dashes:?}");
}

/// A scene with many events: their labels do not pile up.
#[test]
fn many_events_labels_do_not_overlap() {
    let dir = out_dir("plots-vhb");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/viscoelastic-vhb.toml"
    );
    ran(&["run", scene, "--out", &dir, "--json"]);
    let svg = read(&Path::new(&dir).join("viscoelastic-vhb/run.svg"));
    no_overlaps("viscoelastic-vhb run.svg", &svg);
    for event in ["at bias", "trim", "AC drive on"] {
        assert!(svg.contains(event), "{event}");
    }
}

/// The sweep: stopped runs measured nothing, so they sit on the frequency axis as their own
/// symbol, never at an amplitude.
#[test]
fn stopped_sweep_points_are_not_drawn_as_data() {
    let dir = out_dir("plots-sweep");
    let v = ran(&["sweep", "--out", &dir, "--json"]);
    let stopped = v["stopped"].as_u64().unwrap();
    assert!(stopped > 0, "the default sweep has stopped runs");
    let svg = read(&Path::new(&dir).join("sweep.svg"));
    no_overlaps("sweep.svg", &svg);
    // The legend names the stopped runs by whether they crossed a limit first (the JSON's
    // points say which there are).
    let points = v["points"].as_array().unwrap();
    let crossed_then_stopped = points
        .iter()
        .filter(|p| p["stopped"] == true && !p["first_limit_mode"].is_null())
        .count() as u64;
    assert_eq!(
        svg.contains(">stopped after crossing a limit<"),
        crossed_then_stopped > 0
    );
    assert_eq!(
        svg.contains(">stopped: nothing measured<"),
        stopped > crossed_then_stopped
    );
    let frame = svg
        .lines()
        .find(|l| l.starts_with("<rect x=") && l.contains("fill=\"none\""))
        .unwrap();
    let bottom = num(frame, "y") + num(frame, "height");
    // Nothing grey is a dot (a value); the stopped runs' symbols (grey, or red after a
    // crossing) stand on the axis.
    let grey: Vec<&str> = svg
        .lines()
        .filter(|l| l.contains("#888888") && !l.starts_with("<line"))
        .collect();
    assert!(grey.iter().all(|l| !l.starts_with("<circle")), "{grey:?}");
    let on_axis: Vec<&str> = svg
        .lines()
        .filter(|l| l.contains("#888888") || l.contains(RED))
        .filter(|l| l.starts_with("<path") && num(l, "stroke-width") > 0.0)
        .collect();
    assert!(
        on_axis.len() as u64 > stopped,
        "one a stopped run, and the legend's"
    );
    for l in on_axis {
        let d = attr(l, "d").unwrap();
        let ys: Vec<f64> = d
            .split(['M', 'L', 'Z'])
            .filter_map(|p| p.split_whitespace().nth(1)?.parse().ok())
            .collect();
        let lowest = ys.iter().fold(f64::MIN, |a, &b| a.max(b));
        assert!(
            (lowest - bottom).abs() < 2.0 || lowest < 120.0,
            "{l}: not on the axis at {bottom}"
        );
    }
}

/// The work-precision study: a page of a normal width, its step labels clear of each other.
#[test]
fn work_precision_plot_is_a_normal_width() {
    let dir = out_dir("plots-report");
    ran(&["report", "--out", &dir, "--json"]);
    let svg = read(&Path::new(&dir).join("work-precision.svg"));
    let (width, _) = size(&svg);
    assert!(width <= 1200.0, "{width} px wide");
    no_overlaps("work-precision.svg", &svg);
}

/// `simulate` with no AC says so, and its ✕ is where the curve crosses the dashed level the
/// check failed at (interpolated between the samples).
#[test]
fn simulate_marks_the_crossing_where_the_curve_crosses_the_level() {
    let dir = out_dir("plots-simulate");
    let plot = format!("{dir}/crossing.svg");
    std::fs::create_dir_all(&dir).unwrap();
    ran(&[
        "simulate",
        "--bias-volts",
        "9400",
        "--start",
        "prestretch",
        "--duration-seconds",
        "0.05",
        "--plot",
        &plot,
        "--json",
    ]);
    let svg = read(Path::new(&plot));
    no_overlaps("simulate", &svg);
    let title = &texts(&svg)[0].content;
    assert!(
        title.contains("no AC") && !title.contains("0 Hz"),
        "{title}"
    );
    let cross = svg
        .lines()
        .find(|l| l.starts_with("<path d=\"M") && l.contains("#d62728"))
        .expect("a ✕");
    let d: Vec<f64> = attr(cross, "d")
        .unwrap()
        .split(['M', 'L', ' '])
        .filter_map(|p| p.parse().ok())
        .collect();
    let (cx, cy) = (d[0] + 5.0, d[1] + 5.0);
    let line = svg
        .lines()
        .find(|l| l.starts_with("<polyline"))
        .expect("the curve");
    let points: Vec<(f64, f64)> = attr(line, "points")
        .unwrap()
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    let levels: Vec<f64> = svg
        .lines()
        // The levels' lines (drawn 1.2 px wide, in one of the limits' reds).
        .filter(|l| l.starts_with("<line") && l.contains("stroke-width=\"1.2\""))
        .filter(|l| num(l, "y1") == num(l, "y2"))
        .map(|l| num(l, "y1"))
        .collect();
    // The curve's first crossing of the level the ✕ is on.
    let level = levels
        .iter()
        .copied()
        .find(|y| (y - cy).abs() < 1.0)
        .unwrap_or_else(|| panic!("✕ at y {cy} on no level of {levels:?}"));
    let crossing = points
        .windows(2)
        .find_map(|w| {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            ((y0 - level) * (y1 - level) <= 0.0 && y0 != y1)
                .then(|| x0 + (x1 - x0) * (level - y0) / (y1 - y0))
        })
        .expect("the curve crosses the level");
    assert!(
        (crossing - cx).abs() < 1.5,
        "✕ at x {cx}, the curve crosses at {crossing}"
    );
}
