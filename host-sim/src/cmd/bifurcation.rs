//! `bifurcation`: a bifurcation diagram by continuation (model.md §7): the Poincaré stretches
//! at each value of the AC amplitude, the drive frequency or the bias, each value started
//! from the previous one's end state, walked up and down so that hysteresis and jumps show;
//! bifurcation.csv and bifurcation.svg (the values where a limit was crossed in red, the
//! first such value marked).

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::poincare::{self, DrivenArgs};
use super::{prepare_dir, short, sig, write_csv_and_plot, Crossing, DeviceInfo, Report};
use crate::plot::{Panel, Series, Style, COLOURS, RED};
use crate::study::stroboscopic::{self, Direction, Driven, Parameter, Row as Walked};

/// The most values of a diagram.
pub const MAX_VALUES: usize = 100_000;

#[derive(Args, Debug)]
pub struct BifurcationArgs {
    #[command(flatten)]
    pub drive: DrivenArgs,
    /// The parameter varied: its own drive flag is not used but for --quality-factor's
    /// rest state (Q at --bias-volts).
    #[arg(long, value_enum, default_value_t = Parameter::AcVolts)]
    pub vary: Parameter,
    /// Its values, increasing: `a,b,c` or `from:to:count`.
    #[arg(long, value_name = "VALUES", allow_hyphen_values = true)]
    pub values: String,
    /// Which way to walk the values: each walk from its own start.
    #[arg(long, value_enum, default_value_t = Direction::Both)]
    pub direction: Direction,
    /// Section points per value.
    #[arg(long, value_name = "N", default_value_t = 50)]
    pub periods: usize,
    /// Drive periods before the first point of each value.
    #[arg(long, value_name = "N", default_value_t = 100)]
    pub transient_periods: usize,
    /// The start state of each walk, `S,V` (stretch and dλ/dt in 1/s).
    ///
    /// Default: at rest at the equilibrium of the walk's first value's bias.
    #[arg(long, value_name = "S,V", allow_hyphen_values = true)]
    pub y0: Option<String>,
    /// Folder for bifurcation.csv and bifurcation.svg (created if needed, checked before the
    /// work).
    #[arg(long, value_name = "DIR", default_value = "out/bifurcation")]
    pub out: PathBuf,
}

/// One section point of one value: a CSV row.
#[derive(Serialize, Debug)]
pub struct Row {
    pub direction: Direction,
    pub value: f64,
    /// The point's drive period: t = k/f, from k = --transient-periods.
    pub k: usize,
    pub stretch: f64,
    pub velocity_per_second: f64,
}

/// One value of a walk.
#[derive(Serialize, Debug)]
pub struct Value {
    pub direction: Direction,
    pub value: f64,
    pub points: usize,
    /// Distinct section stretches (to 1e-6 of the value's spread; a period-n orbit shows n).
    pub distinct: usize,
    pub first_limit: Option<Crossing>,
    pub stopped: Option<String>,
}

/// What `bifurcation` reports.
#[derive(Serialize, Debug)]
pub struct BifurcationReport {
    pub device: DeviceInfo,
    pub varied: Parameter,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: f64,
    /// The drive in words, the parameter varied as its range.
    #[serde(skip)]
    drive: String,
    pub damping: f64,
    pub periods: usize,
    pub transient_periods: usize,
    /// The first value of each walk at which the motion crossed a limit of model.md §6.
    pub first_crossing_up: Option<f64>,
    pub first_crossing_down: Option<f64>,
    pub values: Vec<Value>,
    pub rows: Vec<Row>,
    pub files: Vec<String>,
}

/// The drive in words, the parameter varied as its range: `7450 V + 100..400 V AC at 88 Hz`.
fn drive_words(
    d: &Driven,
    varied: Parameter,
    range: (f64, f64),
    number: fn(f64) -> String,
) -> String {
    let say = |p: Parameter, value: f64| {
        if p == varied {
            format!("{}..{}", number(range.0), number(range.1))
        } else {
            number(value)
        }
    };
    format!(
        "{} V + {} V AC at {} Hz",
        say(Parameter::BiasVolts, d.bias_volts),
        say(Parameter::AcVolts, d.ac_volts),
        say(Parameter::AcHz, d.ac_hz)
    )
}

impl fmt::Display for BifurcationReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let say = |v: Option<f64>| v.map_or("none".to_string(), sig);
        let walks = |d: Direction| self.values.iter().filter(|v| v.direction == d).count();
        write!(
            f,
            "device          {}\n\
             drive           {}, c = {} N·s\n\
             walks           {} values up, {} down; {} points each after {} periods\n\
             first crossing  up: {}, down: {}\n\
             wrote           {}",
            self.device,
            self.drive,
            sig(self.damping),
            walks(Direction::Up),
            walks(Direction::Down),
            self.periods,
            self.transient_periods,
            say(self.first_crossing_up),
            say(self.first_crossing_down),
            self.files.join(", ")
        )
    }
}

impl Report for BifurcationReport {
    fn failure(&self) -> Option<String> {
        poincare::failure(
            self.values.iter().map(|v| (&v.first_limit, &v.stopped)),
            "values",
        )
    }
}

pub fn bifurcation(args: &BifurcationArgs) -> Result<BifurcationReport, String> {
    let (driven, device) = args.drive.driven()?;
    let values = super::values("--values", &args.values, MAX_VALUES)?;
    let from = args
        .y0
        .as_deref()
        .map(|text| super::state("--y0", text))
        .transpose()?
        .map(|[stretch, velocity_per_second]| stroboscopic::Point {
            stretch,
            velocity_per_second,
        });
    // Checked before the work: every value, the work's size, where the files go.
    if args.vary != Parameter::AcHz && !(driven.ac_hz > 0.0) {
        return Err(format!(
            "--ac-hz {}: a section is taken once a drive period; need a drive frequency > 0",
            sig(driven.ac_hz)
        ));
    }
    let total = values.len() as f64 * (args.transient_periods as f64 + args.periods as f64);
    if total > stroboscopic::MAX_SECTION_POINTS {
        return Err(format!(
            "{} drive periods a walk, more than {}: fewer values or periods",
            sig(total),
            sig(stroboscopic::MAX_SECTION_POINTS)
        ));
    }
    prepare_dir(&args.out)?;
    let walked = stroboscopic::bifurcation(
        &driven,
        args.vary,
        &values,
        args.direction,
        from,
        args.transient_periods,
        args.periods,
    )?;
    let mut rows = Vec::new();
    let mut summary = Vec::new();
    for w in &walked {
        for (j, p) in w.section.points.iter().enumerate() {
            rows.push(Row {
                direction: w.direction,
                value: w.value,
                k: args.transient_periods + j,
                stretch: p.stretch,
                velocity_per_second: p.velocity_per_second,
            });
        }
        summary.push(Value {
            direction: w.direction,
            value: w.value,
            points: w.section.points.len(),
            distinct: distinct(&w.section.points),
            first_limit: Crossing::of(w.section.first_limit),
            stopped: w.section.stopped.clone(),
        });
    }
    let first = |d: Direction| {
        walked
            .iter()
            .find(|w| w.direction == d && w.section.first_limit.is_some())
            .map(|w| w.value)
    };
    let range = (values[0], values[values.len() - 1]);
    let panel = plot(&device, &driven, args.vary, range, &walked);
    let files = write_csv_and_plot(&args.out, "bifurcation", &rows, &[panel])?;
    Ok(BifurcationReport {
        device,
        varied: args.vary,
        bias_volts: driven.bias_volts,
        ac_volts: driven.ac_volts,
        ac_hz: driven.ac_hz,
        drive: drive_words(&driven, args.vary, range, sig),
        damping: driven.params.damping,
        periods: args.periods,
        transient_periods: args.transient_periods,
        first_crossing_up: first(Direction::Up),
        first_crossing_down: first(Direction::Down),
        values: summary,
        rows,
        files,
    })
}

/// Distinct stretches among a section's points, to 1e-6 of their spread (at least 1e-12).
fn distinct(points: &[stroboscopic::Point]) -> usize {
    let mut s: Vec<f64> = points.iter().map(|p| p.stretch).collect();
    s.sort_by(f64::total_cmp);
    let spread = s.last().zip(s.first()).map_or(0.0, |(a, b)| a - b);
    let tol = (1e-6 * spread).max(1e-12);
    s.windows(2).filter(|w| w[1] - w[0] > tol).count() + usize::from(!s.is_empty())
}

/// The Poincaré stretches against the value: up in blue, down in orange, the values whose
/// run crossed a limit in red, the first crossing of each walk as a guide.
fn plot(
    device: &DeviceInfo,
    driven: &Driven,
    varied: Parameter,
    range: (f64, f64),
    walked: &[Walked],
) -> Panel {
    let mut series = Vec::new();
    for (direction, colour, name) in [
        (Direction::Up, COLOURS[0], "walked up"),
        (Direction::Down, COLOURS[1], "walked down"),
    ] {
        for crossed in [false, true] {
            let points: Vec<(f64, f64)> = walked
                .iter()
                .filter(|w| w.direction == direction)
                .filter(|w| w.section.first_limit.is_some() == crossed)
                .flat_map(|w| w.section.points.iter().map(|p| (w.value, p.stretch)))
                .collect();
            if points.is_empty() {
                continue;
            }
            series.push(Series {
                name: if crossed {
                    format!("{name}, crossed a limit")
                } else {
                    name.into()
                },
                points,
                style: Style {
                    colour: Some(if crossed { RED } else { colour }),
                    dots_only: true,
                    mark: if direction == Direction::Up {
                        crate::plot::Mark::Circle
                    } else {
                        crate::plot::Mark::Diamond
                    },
                    ..Style::default()
                },
                label: String::new(),
            });
        }
    }
    let guides = [Direction::Up, Direction::Down]
        .into_iter()
        .filter_map(|d| {
            let w = walked
                .iter()
                .find(|w| w.direction == d && w.section.first_limit.is_some())?;
            let (mode, _) = w.section.first_limit?;
            Some((
                w.value,
                format!(
                    "first crossing {}: {}",
                    if d == Direction::Up { "up" } else { "down" },
                    mode.name()
                ),
            ))
        })
        .collect();
    let unit = match varied {
        Parameter::AcVolts => "AC amplitude, V",
        Parameter::AcHz => "drive frequency, Hz",
        Parameter::BiasVolts => "bias, V",
    };
    let stretch = poincare::limit_stretch(driven);
    Panel {
        title: format!(
            "{}: bifurcation, {}",
            device.title(),
            drive_words(driven, varied, range, short)
        ),
        x_label: unit.into(),
        y_label: "stretch at t = k/f".into(),
        series,
        guides,
        levels: stretch.into_iter().collect(),
        ..Panel::default()
    }
}
