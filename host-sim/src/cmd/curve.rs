//! `curve`: the tuning curve, natural frequency against bias on the loading branch (model.md
//! §5), with the limit (§6), the margin's highest bias, the tunable range and a target; over
//! ranges of pre-stretch, a family of curves and the safe region's boundary through their
//! limits (the paper's figures). curve.csv and curve.svg. For a device file with tolerances
//! (model.md §10), the batch's band of frequencies below its guaranteed cap too (band.csv).

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use de_resonator::{Device, Field, Tuner};
use serde::Serialize;

use super::safe::{search_leaves, targets_margin, Guaranteed};
use super::{
    prepare_dir, short, sig, write_csv_and_plot, DeviceArgs, DeviceInfo, MarginArgs, Report,
};
use crate::plot::{Mark, Marker, Panel, Series, Style, COLOURS, RED};

/// The most curves in a family, and the most points a curve.
pub const MAX_CURVES: usize = 400;
pub const MAX_POINTS: usize = 100_000;

#[derive(Args, Debug)]
pub struct CurveArgs {
    /// Pre-stretch of the active membrane: one value, or `low:high:count` for a family.
    ///
    /// Default: the device's.
    #[arg(long, value_name = "A[:B:N]")]
    pub prestretch_1: Option<String>,
    /// Pre-stretch of the passive membrane: one value, or `low:high:count`.
    ///
    /// Default: the device's.
    #[arg(long, value_name = "A[:B:N]")]
    pub prestretch_2: Option<String>,
    /// Mark the smallest bias for this frequency, Hz (on every curve that reaches it).
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub target_hz: Option<f64>,
    /// Points a curve, from 0 V to its limit.
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub points: usize,
    /// Folder for curve.csv and curve.svg (created if needed, checked before the work).
    #[arg(long, value_name = "DIR", default_value = "out/curve")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
    #[command(flatten)]
    pub margin: MarginArgs,
}

/// One point of a curve: a CSV row, and in the JSON.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Point {
    pub prestretch_1: f64,
    pub prestretch_2: f64,
    pub bias_volts: f64,
    pub natural_frequency_hz: f64,
    pub stretch: f64,
    /// Above (1 − margin)·limit: not allowed to be commanded.
    pub beyond_margin: bool,
}

/// Where a curve ends: the first check of §6 to fail on the loading branch.
#[derive(Serialize, Debug)]
pub struct CurveLimit {
    pub mode: &'static str,
    pub volts: f64,
    pub stretch: f64,
    pub natural_frequency_hz: f64,
}

/// The target on one curve.
#[derive(Serialize, Debug)]
pub struct Target {
    pub target_hz: f64,
    /// The smallest bias within the margin; null when the curve does not reach it.
    pub bias_volts: Option<f64>,
    /// Why not, when it does not.
    pub refused: Option<String>,
}

/// One pre-stretch pair's curve.
#[derive(Serialize, Debug)]
pub struct Curve {
    pub prestretch_1: f64,
    pub prestretch_2: f64,
    /// `null` when this pre-stretch makes no valid device (`problem` says why).
    pub limit: Option<CurveLimit>,
    pub max_bias_volts: Option<f64>,
    pub tunable_range_hz: Option<[f64; 2]>,
    pub target: Option<Target>,
    pub problem: Option<String>,
    pub points: Vec<Point>,
}

/// What `curve` reports.
#[derive(Serialize, Debug)]
pub struct CurveReport {
    pub device: DeviceInfo,
    pub margin: f64,
    pub curves: Vec<Curve>,
    /// With tolerances: what holds for every device of the batch (as `safe`'s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guaranteed: Option<Guaranteed>,
    /// With tolerances: the batch's natural frequencies from 0 V to its guaranteed cap
    /// (band.csv's rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band: Option<Vec<BandPoint>>,
    pub files: Vec<String>,
}

/// The batch's band at one bias: no device of it lies outside [low, high] (model.md §10).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct BandPoint {
    pub bias_volts: f64,
    pub low_hz: f64,
    pub high_hz: f64,
}

/// Biases the band is found at, from 0 V to the guaranteed cap evenly in Φ².
const BAND_POINTS: usize = 41;

impl fmt::Display for CurveReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The limit column as wide as its longest entry and two spaces.
        let limit_of = |c: &Curve| {
            c.limit
                .as_ref()
                .map(|l| format!("{} at {} V", l.mode, sig(l.volts)))
        };
        let width = self
            .curves
            .iter()
            .filter_map(limit_of)
            .map(|t| t.chars().count() + 2)
            .max()
            .unwrap_or(0)
            .max(31);
        writeln!(
            f,
            "device          {}\nmargin          {}\n\
             λ1p      λ2p      {:<width$}{:<13}tunable range Hz{}",
            self.device,
            short(self.margin),
            "limit",
            "max bias V",
            if self.curves.iter().any(|c| c.target.is_some()) {
                "        target bias V"
            } else {
                ""
            }
        )?;
        for c in &self.curves {
            write!(
                f,
                "{:<9}{:<9}",
                short(c.prestretch_1),
                short(c.prestretch_2)
            )?;
            match (&c.limit, c.max_bias_volts, c.tunable_range_hz) {
                (Some(_), Some(max), Some([low, high])) => {
                    write!(
                        f,
                        "{:<width$}{:<13}{} .. {}",
                        limit_of(c).unwrap_or_default(),
                        sig(max),
                        sig(low),
                        sig(high)
                    )?;
                    if let Some(t) = &c.target {
                        match (t.bias_volts, &t.refused) {
                            (Some(v), _) => write!(f, "   {}", sig(v))?,
                            (None, Some(_)) => write!(f, "   none (out of range)")?,
                            (None, None) => {}
                        }
                    }
                }
                _ => write!(f, "no curve: {}", c.problem.as_deref().unwrap_or("?"))?,
            }
            writeln!(f)?;
        }
        if let Some(g) = &self.guaranteed {
            writeln!(f, "{g}")?;
        }
        write!(f, "wrote           {}", self.files.join(", "))
    }
}

impl Report for CurveReport {}

/// `A` or `low:high:count` ([`super::values`], at most `MAX_CURVES`); the default without.
fn values(flag: &str, text: Option<&str>, default: f64) -> Result<Vec<f64>, String> {
    text.map_or(Ok(vec![default]), |text| {
        super::values(flag, text, MAX_CURVES)
    })
}

pub fn curve(args: &CurveArgs) -> Result<CurveReport, String> {
    let (batch, device) = args.device.source().batch()?;
    let params = batch.nominal;
    let margin = args.margin.margin;
    if !(0.0..1.0).contains(&margin) {
        return Err(format!("--margin {margin}: need 0 ≤ margin < 1"));
    }
    if let Some(hz) = args.target_hz.filter(|hz| !(hz.is_finite() && *hz > 0.0)) {
        return Err(format!("--target-hz {hz}: need a finite frequency > 0"));
    }
    if !(2..=MAX_POINTS).contains(&args.points) {
        return Err(format!("--points {}: need 2 to {MAX_POINTS}", args.points));
    }
    let ones = values(
        "--prestretch-1",
        args.prestretch_1.as_deref(),
        params.prestretch_1,
    )?;
    let twos = values(
        "--prestretch-2",
        args.prestretch_2.as_deref(),
        params.prestretch_2,
    )?;
    if ones.len() * twos.len() > MAX_CURVES {
        return Err(format!(
            "{} curves: at most {MAX_CURVES}",
            ones.len() * twos.len()
        ));
    }
    if !batch.is_exact() && ones.len() * twos.len() > 1 {
        return Err(
            "a family of pre-stretches with a device file's tolerances: each curve would be \
             another batch; give the pre-stretches' spread in [tolerance] instead"
                .into(),
        );
    }
    // A single device must be valid: its errors are the user's to fix.
    if ones.len() * twos.len() == 1 {
        let mut one = params;
        one.set(Field::Prestretch1, ones[0]);
        one.set(Field::Prestretch2, twos[0]);
        Device::new(one).map_err(|e| format!("{device}: {e}"))?;
    }
    prepare_dir(&args.out)?;
    let mut curves = Vec::new();
    for &l1 in &ones {
        for &l2 in &twos {
            let mut p = params;
            p.set(Field::Prestretch1, l1);
            p.set(Field::Prestretch2, l2);
            curves.push(one_curve(p, margin, args.target_hz, args.points));
        }
    }
    let rows: Vec<Point> = curves
        .iter()
        .flat_map(|c| c.points.iter().copied())
        .collect();
    let guaranteed = Guaranteed::of(&batch, margin)?;
    let band = match &guaranteed {
        Some(g) => Some(band_below(&batch, g.max_bias_volts)?),
        None => None,
    };
    let mut panel = plot(&device, &curves, ones.len() * twos.len() > 1);
    if let (Some(g), Some(band)) = (&guaranteed, &band) {
        draw_batch(&mut panel, g, band);
    }
    let mut files = write_csv_and_plot(&args.out, "curve", &rows, &[panel])?;
    if let Some(band) = &band {
        files.push(super::write_file(
            &args.out,
            "band.csv",
            &super::csv(band)?,
        )?);
    }
    Ok(CurveReport {
        device,
        margin,
        curves,
        guaranteed,
        band,
        files,
    })
}

/// The batch's band at `BAND_POINTS` biases from 0 V to `top_volts`, evenly in Φ².
fn band_below(
    batch: &de_resonator::model::tolerance::DeviceBox,
    top_volts: f64,
) -> Result<Vec<BandPoint>, String> {
    let mut leaves = search_leaves();
    (0..BAND_POINTS)
        .map(|k| {
            let bias_volts = top_volts * (k as f64 / (BAND_POINTS - 1) as f64).sqrt();
            let band = batch
                .band_hz(bias_volts, &mut leaves)
                .map_err(|e| e.to_string())?;
            Ok(BandPoint {
                bias_volts,
                low_hz: band.low_hz,
                high_hz: band.high_hz,
            })
        })
        .collect()
}

/// The batch on the plot: its band's two edges, dashed, and the guaranteed limit and cap.
fn draw_batch(panel: &mut Panel, g: &Guaranteed, band: &[BandPoint]) {
    let colour = COLOURS[3];
    for (name, edge) in [("every device of the batch: between these", 0), ("", 1)] {
        panel.series.push(Series {
            name: name.into(),
            points: band
                .iter()
                .map(|b| (b.bias_volts, if edge == 0 { b.low_hz } else { b.high_hz }))
                .collect(),
            style: Style {
                colour: Some(colour),
                dashed: true,
                ..Style::default()
            },
            label: String::new(),
        });
    }
    panel.guides.push((
        g.max_bias_volts,
        format!("batch's max bias {} V", short(g.max_bias_volts)),
    ));
    panel.guides.push((
        g.limit.volts,
        format!("batch's guaranteed limit {} V", short(g.limit.volts)),
    ));
}

/// The loading branch of one device from 0 V to its limit, at offsets evenly spaced in √δ
/// (so evenly spaced in bias near 0 V, where Φ ∝ √δ, model.md §5).
pub fn one_curve(
    p: de_resonator::DeviceParams<f64>,
    margin: f64,
    target_hz: Option<f64>,
    points: usize,
) -> Curve {
    let mut curve = Curve {
        prestretch_1: p.prestretch_1,
        prestretch_2: p.prestretch_2,
        limit: None,
        max_bias_volts: None,
        tunable_range_hz: None,
        target: None,
        problem: None,
        points: Vec::new(),
    };
    let device = match Device::new(p) {
        Ok(d) => d,
        Err(e) => {
            curve.problem = Some(e.to_string());
            return curve;
        }
    };
    let tuner = Tuner::new(device);
    let limit = *tuner.limit();
    let ranges = tuner.max_bias(margin).and_then(|max_bias| {
        tuner
            .tunable_range(targets_margin(margin))
            .map(|range| (max_bias, range))
    });
    let (max_bias, range) = match ranges {
        Ok(r) => r,
        Err(e) => {
            curve.problem = Some(e.to_string());
            return curve;
        }
    };
    let end = limit.at.offset;
    curve.points = (0..points)
        .map(|k| {
            let s = k as f64 / (points - 1) as f64;
            let at = device.equilibrium_at(end * s * s);
            Point {
                prestretch_1: p.prestretch_1,
                prestretch_2: p.prestretch_2,
                bias_volts: at.volts,
                natural_frequency_hz: at.natural_frequency_hz,
                stretch: at.stretch,
                beyond_margin: at.volts > max_bias.volts,
            }
        })
        .collect();
    curve.limit = Some(CurveLimit {
        mode: limit.mode.name(),
        volts: limit.at.volts,
        stretch: limit.at.stretch,
        natural_frequency_hz: limit.at.natural_frequency_hz,
    });
    curve.max_bias_volts = Some(max_bias.volts);
    curve.tunable_range_hz = Some([range.low_hz, range.high_hz]);
    curve.target = target_hz.map(|hz| match tuner.tune(hz, targets_margin(margin)) {
        Ok(at) => Target {
            target_hz: hz,
            bias_volts: Some(at.volts),
            refused: None,
        },
        Err(e) => Target {
            target_hz: hz,
            bias_volts: None,
            refused: Some(e.to_string()),
        },
    });
    curve
}

/// f against bias. One device: the curve, its limit (red ×), the margin's highest bias, the
/// tunable range as two levels, the target. A family: a colour per λ2p, a curve per λ1p (the
/// group's first and last labelled with their λ1p), and through each group's limits its part
/// of the safe region's edge, dashed in the group's colour.
fn plot(device: &DeviceInfo, curves: &[Curve], family: bool) -> Panel {
    let mut panel = Panel {
        title: format!("Tuning curve: {}", device.title()),
        x_label: "bias, V".into(),
        y_label: "natural frequency, Hz".into(),
        ..Panel::default()
    };
    let mut groups: Vec<f64> = Vec::new();
    for c in curves {
        if !groups.contains(&c.prestretch_2) {
            groups.push(c.prestretch_2);
        }
    }
    for (g, &l2) in groups.iter().enumerate() {
        // The palette without its red, which is the limits'.
        let palette: Vec<&str> = COLOURS.iter().copied().filter(|c| *c != RED).collect();
        let colour = palette[g % palette.len()];
        // The group's second cue beside its colour: its edge's mark.
        let mark = Mark::ALL[g % Mark::ALL.len()];
        let members: Vec<&Curve> = curves.iter().filter(|c| c.prestretch_2 == l2).collect();
        let ones: Vec<String> = members.iter().map(|c| short(c.prestretch_1)).collect();
        for (k, c) in members.iter().enumerate() {
            if let Some(why) = &c.problem {
                let name = format!("λ1p {}, λ2p {}", short(c.prestretch_1), short(l2));
                panel.notes.push(format!("{name}: no curve ({why})"));
                continue;
            }
            let name = match (family, k) {
                (false, _) => "f(bias)".into(),
                (true, 0) if ones.len() > 1 => {
                    format!(
                        "λ2p {}, λ1p {} .. {}",
                        short(l2),
                        ones[0],
                        ones[ones.len() - 1]
                    )
                }
                (true, 0) => format!("λ2p {}, λ1p {}", short(l2), ones[0]),
                (true, _) => String::new(),
            };
            panel.series.push(Series {
                name,
                points: c
                    .points
                    .iter()
                    .map(|p| (p.bias_volts, p.natural_frequency_hz))
                    .collect(),
                style: Style {
                    colour: Some(colour),
                    ..Style::default()
                },
                label: String::new(),
            });
        }
        if family {
            // The edge's two ends say which λ1p they are (the colour says the λ2p, the legend
            // the range between): along the curves, where they crowd, labels would pile up.
            let limits: Vec<(f64, &Curve)> = members
                .iter()
                .filter_map(|c| Some((c.limit.as_ref()?.volts, *c)))
                .collect();
            let ends = match limits.len() {
                0 => &limits[..],
                1 => &limits[..1],
                n => &[limits[0], limits[n - 1]][..],
            };
            for end in ends {
                let at = end
                    .1
                    .limit
                    .as_ref()
                    .map(|l| (l.volts, l.natural_frequency_hz));
                panel.series.push(Series {
                    points: at.into_iter().collect(),
                    style: Style {
                        colour: Some(colour),
                        dots_only: true,
                        mark,
                        ..Style::default()
                    },
                    label: format!("λ1p {}", short(end.1.prestretch_1)),
                    ..Series::default()
                });
            }
            panel.series.push(Series {
                name: format!("λ2p {}: the safe region's edge (limits)", short(l2)),
                points: members
                    .iter()
                    .filter_map(|c| c.limit.as_ref())
                    .map(|l| (l.volts, l.natural_frequency_hz))
                    .collect(),
                style: Style {
                    colour: Some(colour),
                    dashed: true,
                    mark,
                    ..Style::default()
                },
                label: String::new(),
            });
        }
    }
    for c in curves {
        if let Some(t) = &c.target {
            if let Some(v) = t.bias_volts {
                panel.markers.push(Marker {
                    x: v,
                    y: t.target_hz,
                    label: format!("target {} Hz", short(t.target_hz)),
                    colour: crate::plot::COLOURS[2],
                });
            }
        }
    }
    if let (false, Some(c)) = (family, curves.first()) {
        if let Some(l) = &c.limit {
            panel.markers.push(Marker {
                x: l.volts,
                y: l.natural_frequency_hz,
                label: format!("limit ({}) {} V", l.mode, short(l.volts)),
                colour: RED,
            });
        }
        if let Some(max) = c.max_bias_volts {
            panel
                .guides
                .push((max, format!("max bias {} V", short(max))));
        }
        if let Some([low, high]) = c.tunable_range_hz {
            panel
                .levels
                .push((low, format!("tunable range from {} Hz", short(low))));
            panel
                .levels
                .push((high, format!("tunable range to {} Hz", short(high))));
        }
    }
    panel
}
