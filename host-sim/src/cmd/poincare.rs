//! `poincare`: the driven membrane's Poincaré section at the drive's phase 0 (model.md §7),
//! from one or many start states; poincare.csv and poincare.svg (velocity against stretch,
//! the loading branch's limit stretch marked, runs that crossed a limit in red). Also the drive
//! and start arguments `bifurcation` and `lyapunov` share.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::{
    prepare_dir, short, sig, write_csv_and_plot, Crossing, DeviceArgs, DeviceInfo, Report,
};
use crate::engine::solver::Tolerance;
use crate::plot::{Panel, Series, Style, COLOURS, RED};
use crate::study::stroboscopic::{self, Driven, Point, Section, STUDY_TOLERANCE};

/// The drive, the damping and the start state of a study.
#[derive(Args, Debug, Clone)]
pub struct DrivenArgs {
    /// Static bias, V.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub bias_volts: f64,
    /// AC amplitude, V.
    #[arg(
        long,
        value_name = "V",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub ac_volts: f64,
    /// AC drive frequency, Hz: Φ(t) = bias + ac·sin(2π·f·t).
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub ac_hz: f64,
    /// Viscous damping c, N·s (overrides the device's).
    #[arg(
        long,
        value_name = "C",
        allow_negative_numbers = true,
        conflicts_with = "quality_factor"
    )]
    pub damping: Option<f64>,
    /// Quality factor Q of the small oscillation at the bias: sets c = M·ω0/Q (M the effective
    /// mass of model.md §4), over the device's damping.
    #[arg(
        long,
        visible_alias = "quality",
        value_name = "Q",
        allow_negative_numbers = true
    )]
    pub quality_factor: Option<f64>,
    /// The solver's tolerance (DOP853's rtol = atol).
    #[arg(long, value_name = "R", default_value_t = STUDY_TOLERANCE, allow_negative_numbers = true)]
    pub rtol: f64,
    #[command(flatten)]
    pub device: DeviceArgs,
}

impl DrivenArgs {
    /// The drive on the device, its damping as asked, and the device as the report names it.
    pub fn driven(&self) -> Result<(Driven, DeviceInfo), String> {
        let (mut params, info) = self.device.source().params()?;
        if let Some(c) = self.damping {
            params.damping = c;
        }
        let driven = Driven {
            params,
            bias_volts: self.bias_volts,
            ac_volts: self.ac_volts,
            ac_hz: self.ac_hz,
            tolerance: Tolerance::both(self.rtol),
        };
        driven.device().map_err(|e| format!("{info}: {e}"))?;
        match self.quality_factor {
            Some(q) => Ok((driven.with_quality(q)?, info)),
            None => Ok((driven, info)),
        }
    }
}

/// `S,V` start states, `;` between them (`super::states`).
pub fn starts(text: &str) -> Result<Vec<Point>, String> {
    Ok(super::states("--y0", text)?
        .into_iter()
        .map(|[stretch, velocity_per_second]| Point {
            stretch,
            velocity_per_second,
        })
        .collect())
}

#[derive(Args, Debug)]
pub struct PoincareArgs {
    #[command(flatten)]
    pub drive: DrivenArgs,
    /// Section points per start: the state at t = k/f for k = transient, transient + 1, ….
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub periods: usize,
    /// Drive periods before the first point.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub transient_periods: usize,
    /// Start states, `S,V` (stretch and dλ/dt in 1/s), `;` between several (run on all
    /// cores).
    ///
    /// Default: at rest at the bias's equilibrium.
    #[arg(long, value_name = "S,V;…", allow_hyphen_values = true)]
    pub y0: Option<String>,
    /// Folder for poincare.csv and poincare.svg (created if needed, checked before the work).
    #[arg(long, value_name = "DIR", default_value = "out/poincare")]
    pub out: PathBuf,
}

/// One section point: a CSV row.
#[derive(Serialize, Debug)]
pub struct Row {
    /// Which start (0, 1, …).
    pub start: usize,
    /// The drive period: t = k/f.
    pub k: usize,
    pub time_seconds: f64,
    pub stretch: f64,
    pub velocity_per_second: f64,
}

/// One start's run.
#[derive(Serialize, Debug)]
pub struct Run {
    pub y0: Point,
    pub points: usize,
    /// The first check of model.md §6 the motion failed (transient included).
    pub first_limit: Option<Crossing>,
    pub stopped: Option<String>,
}

/// What `poincare` reports.
#[derive(Serialize, Debug)]
pub struct PoincareReport {
    pub device: DeviceInfo,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: f64,
    /// c in force, N·s.
    pub damping: f64,
    pub transient_periods: usize,
    pub runs: Vec<Run>,
    pub rows: Vec<Row>,
    pub files: Vec<String>,
}

impl fmt::Display for PoincareReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "device          {}\n\
             drive           {} V + {} V AC at {} Hz, c = {} N·s\n\
             section         t = k/{} Hz from k = {}",
            self.device,
            sig(self.bias_volts),
            sig(self.ac_volts),
            sig(self.ac_hz),
            sig(self.damping),
            sig(self.ac_hz),
            self.transient_periods
        )?;
        for (i, run) in self.runs.iter().enumerate() {
            writeln!(
                f,
                "start {i:<9} λ {}, {} 1/s: {} points{}{}",
                sig(run.y0.stretch),
                sig(run.y0.velocity_per_second),
                run.points,
                run.first_limit.map_or(String::new(), |c| format!(
                    ", crossed {} at {} s",
                    c.mode,
                    sig(c.time_seconds)
                )),
                run.stopped
                    .as_ref()
                    .map_or(String::new(), |why| format!(", stopped: {why}"))
            )?;
        }
        write!(f, "wrote           {}", self.files.join(", "))
    }
}

impl Report for PoincareReport {
    /// A run crossed a limit of model.md §6, or stopped early.
    fn failure(&self) -> Option<String> {
        failure(
            self.runs.iter().map(|r| (&r.first_limit, &r.stopped)),
            "starts",
        )
    }
}

/// How many of the runs crossed a limit or stopped, said once (`None`: none did).
pub fn failure<'a>(
    runs: impl Iterator<Item = (&'a Option<Crossing>, &'a Option<String>)>,
    what: &str,
) -> Option<String> {
    let (mut crossed, mut stopped, mut all) = (0, 0, 0);
    for (c, s) in runs {
        all += 1;
        crossed += usize::from(c.is_some());
        stopped += usize::from(s.is_some());
    }
    match (crossed, stopped) {
        (0, 0) => None,
        (c, 0) => Some(format!(
            "{c} of {all} {what} crossed a limit of model.md §6"
        )),
        (c, s) => Some(format!(
            "{c} of {all} {what} crossed a limit of model.md §6, {s} stopped early"
        )),
    }
}

pub fn poincare(args: &PoincareArgs) -> Result<PoincareReport, String> {
    let (driven, device) = args.drive.driven()?;
    if args.periods == 0 {
        return Err("--periods 0: need at least 1".into());
    }
    let starts = match &args.y0 {
        Some(text) => starts(text)?,
        None => vec![driven.rest()?],
    };
    let work = starts.len() as f64 * (args.periods as f64 + args.transient_periods as f64);
    if work > stroboscopic::MAX_SECTION_POINTS {
        return Err(format!(
            "{} drive periods in all, more than {}: fewer starts or periods",
            sig(work),
            sig(stroboscopic::MAX_SECTION_POINTS)
        ));
    }
    if !(driven.ac_hz > 0.0) {
        return Err(format!(
            "--ac-hz {}: a section is taken once a drive period; need a drive frequency > 0",
            sig(driven.ac_hz)
        ));
    }
    prepare_dir(&args.out)?;
    let sections = crate::progress::map("poincare", &starts, |&from| {
        stroboscopic::section(&driven, from, args.transient_periods, args.periods)
    })
    .into_iter()
    .collect::<Result<Vec<Section>, _>>()?;
    crate::progress::interrupted(sections.iter().map(|s| s.stopped.as_deref()))?;
    let mut rows = Vec::new();
    for (i, s) in sections.iter().enumerate() {
        for (j, p) in s.points.iter().enumerate() {
            let k = args.transient_periods + j;
            rows.push(Row {
                start: i,
                k,
                time_seconds: k as f64 / driven.ac_hz,
                stretch: p.stretch,
                velocity_per_second: p.velocity_per_second,
            });
        }
    }
    let runs: Vec<Run> = starts
        .iter()
        .zip(&sections)
        .map(|(&y0, s)| Run {
            y0,
            points: s.points.len(),
            first_limit: Crossing::of(s.first_limit),
            stopped: s.stopped.clone(),
        })
        .collect();
    let panel = plot(&device, &driven, &sections, args.transient_periods);
    let files = write_csv_and_plot(&args.out, "poincare", &rows, &[panel])?;
    Ok(PoincareReport {
        device,
        bias_volts: driven.bias_volts,
        ac_volts: driven.ac_volts,
        ac_hz: driven.ac_hz,
        damping: driven.params.damping,
        transient_periods: args.transient_periods,
        runs,
        rows,
        files,
    })
}

/// The loading branch's limit stretch of the device driven, as a guide line's place.
pub fn limit_stretch(driven: &Driven) -> Option<(f64, String)> {
    let device = driven.device().ok()?;
    let limit = de_resonator::Limit::of(&device);
    Some((
        limit.at.stretch,
        format!("static limit ({})", limit.mode.name()),
    ))
}

/// Velocity against stretch, a colour per start (red: the run crossed a limit).
fn plot(device: &DeviceInfo, driven: &Driven, sections: &[Section], transient: usize) -> Panel {
    let series = sections
        .iter()
        .enumerate()
        .map(|(i, s)| Series {
            name: if s.first_limit.is_some() {
                format!("start {i} (crossed a limit)")
            } else {
                format!("start {i}")
            },
            points: s
                .points
                .iter()
                .map(|p| (p.stretch, p.velocity_per_second))
                .collect(),
            style: Style {
                colour: Some(if s.first_limit.is_some() {
                    RED
                } else {
                    COLOURS[i % COLOURS.len()]
                }),
                dots_only: true,
                ..Style::default()
            },
            label: String::new(),
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    Panel {
        title: format!(
            "{}: Poincaré section, {} V + {} V AC at {} Hz",
            device.title(),
            short(driven.bias_volts),
            short(driven.ac_volts),
            short(driven.ac_hz)
        ),
        x_label: "stretch at t = k/f".into(),
        y_label: "dλ/dt at t = k/f, 1/s".into(),
        series,
        guides: limit_stretch(driven).into_iter().collect(),
        notes: vec![format!("from k = {transient}")],
        ..Panel::default()
    }
}
