//! `report`: the work-precision study (error against run time of every core method in f32
//! and f64, against the reference); work-precision.csv and .svg, a table per scene.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::{prepare_dir, write_csv_and_plot, DeviceArgs, DeviceInfo, Report};
use crate::engine::open_loop::Choice;
use crate::plot::{Mark, Marker, Panel, Series, Style, COLOURS};
use crate::study::work_precision::{reference, rows, studies, Row, ToleranceRow};

#[derive(Args, Debug)]
pub struct PrecisionArgs {
    /// Folder for the CSV and the plot (created if needed).
    #[arg(long, value_name = "DIR", default_value = "out/report")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The reference and its error floor.
#[derive(Serialize, Debug)]
pub struct ReferenceReport {
    pub method: &'static str,
    pub tolerance: f64,
    /// Largest stretch difference against tolerance 1e-13.
    pub floor: f64,
    pub floor_is: &'static str,
}

/// One scene of the study.
#[derive(Serialize, Debug)]
pub struct SceneReport {
    pub name: &'static str,
    pub what: String,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub drive_hz: f64,
    pub base_hz: f64,
    pub duration_seconds: f64,
    pub reference_floor: f64,
    /// The reference (DOP853) at several tolerances against 1e-13.
    pub reference_tolerances: Vec<ToleranceRow>,
}

/// What `report` reports.
#[derive(Serialize, Debug)]
pub struct PrecisionReport {
    pub device: DeviceInfo,
    pub reference: ReferenceReport,
    pub scenes: Vec<SceneReport>,
    pub rows: Vec<Row>,
    /// The files written: the CSV and the plot.
    pub files: Vec<String>,
}

impl fmt::Display for PrecisionReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "device  {}\n\
             reference: DOP853 at 1e-12; its error floor (against 1e-13) is {:.1e} in stretch\n\
             max error in stretch at 16 / 64 / 256 steps a period; run time per simulated second at 64\n",
            self.device, self.reference.floor
        )?;
        for scene in &self.scenes {
            write!(
                f,
                "\n{}: {}\n  {:<24}{:>10}{:>10}{:>10}{:>13}\n",
                scene.name, scene.what, "method", "16", "64", "256", "s/sim s"
            )?;
            let mut methods: Vec<&str> = Vec::new();
            for r in self.rows.iter().filter(|r| r.scene == scene.name) {
                if !methods.contains(&r.method) {
                    methods.push(r.method);
                }
            }
            for method in methods {
                let at = |n: u32| {
                    self.rows.iter().find(|r| {
                        r.scene == scene.name && r.method == method && r.steps_per_period == n
                    })
                };
                let cell = |n: u32| match at(n) {
                    Some(r) if r.status == "ok" => {
                        r.max_error.map_or("-".into(), |e| format!("{e:.1e}"))
                    }
                    Some(r) => r.status.to_string(),
                    None => "-".into(),
                };
                let time = at(64)
                    .and_then(|r| r.run_seconds_per_simulated_second)
                    .map_or("-".into(), |t| format!("{t:.1e}"));
                writeln!(
                    f,
                    "  {method:<24}{:>10}{:>10}{:>10}{time:>13}",
                    cell(16),
                    cell(64),
                    cell(256)
                )?;
            }
            write!(
                f,
                "  reference DOP853 against 1e-13, tolerance: max error, s/sim s:"
            )?;
            for t in &scene.reference_tolerances {
                write!(
                    f,
                    "  {:.0e}: {:.1e}, {:.1e}",
                    t.tolerance, t.max_error, t.run_seconds_per_simulated_second
                )?;
            }
            writeln!(f)?;
        }
        write!(f, "\nwrote {}", self.files.join(", "))
    }
}

impl Report for PrecisionReport {}

pub fn precision(args: &PrecisionArgs) -> Result<PrecisionReport, String> {
    let (params, name) = args.device.source().params()?;
    // The folder made ready before the work (minutes of it), as every command does.
    prepare_dir(&args.out)?;
    let studies = studies(params).map_err(|e| format!("{name}: {e}"))?;
    let references = crate::progress::map("reference", &studies, reference)
        .into_iter()
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("{name}: {e}"))?;
    // Timed runs one at a time: run times measured side by side must not share the cores.
    let methods = Choice::core();
    let bar = crate::progress::bar("timing", studies.len() * methods.len());
    let mut all: Vec<Row> = Vec::new();
    for (study, reference) in studies.iter().zip(&references) {
        for &choice in &methods {
            all.extend(rows(study, reference, choice));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let panels: Vec<Panel> = studies
        .iter()
        .map(|study| panel(study.name, &all))
        .collect();
    let files = write_csv_and_plot(&args.out, "work-precision", &all, &panels)?;
    let floor = references.iter().map(|r| r.floor).fold(0.0, f64::max);
    Ok(PrecisionReport {
        device: name,
        reference: ReferenceReport {
            method: "dop853",
            tolerance: 1e-12,
            floor,
            floor_is: "largest stretch difference against tolerance 1e-13",
        },
        scenes: studies
            .iter()
            .zip(&references)
            .map(|(s, r)| SceneReport {
                name: s.name,
                what: s.what.clone(),
                bias_volts: s.scene.bias_volts,
                ac_volts: s.scene.ac_volts,
                drive_hz: s.scene.drive_hz,
                base_hz: s.base_hz,
                duration_seconds: s.scene.duration_seconds,
                reference_floor: r.floor,
                reference_tolerances: r.tolerances.clone(),
            })
            .collect(),
        rows: all,
        files,
    })
}

/// One scene's work-precision panel: a colour per method, solid in f64 and dashed in f32,
/// the steps a period written at 8, 64 and 512, and the runs that have no point listed.
fn panel(scene: &str, rows: &[Row]) -> Panel {
    let mut panel = Panel {
        title: scene.into(),
        x_label: "run time per simulated second, s".into(),
        y_label: "max stretch error".into(),
        log_x: true,
        log_y: true,
        ..Panel::default()
    };
    let mut bases: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.scene == scene) {
        let (base, f32_) = match r.method.rsplit_once('-') {
            Some((base, precision)) => (base, precision == "f32"),
            None => (r.method, false),
        };
        if !bases.contains(&base) {
            bases.push(base);
        }
        // A method: a colour and a mark; its f32 build dashed.
        let which = bases.iter().position(|b| *b == base).unwrap_or(0);
        let colour = COLOURS[which % COLOURS.len()];
        let mark = Mark::ALL[which % Mark::ALL.len()];
        let (Some(time), Some(error)) = (r.run_seconds_per_simulated_second, r.max_error) else {
            panel.notes.push(format!(
                "{} at {}/period: {}",
                r.method, r.steps_per_period, r.status
            ));
            continue;
        };
        match panel.series.iter_mut().find(|s| s.name == r.method) {
            Some(s) => s.points.push((time, error)),
            None => panel.series.push(Series {
                name: r.method.into(),
                points: vec![(time, error)],
                style: Style {
                    colour: Some(colour),
                    dashed: f32_,
                    mark,
                    ..Style::default()
                },
                label: String::new(),
            }),
        }
        if matches!(r.steps_per_period, 8 | 64 | 512) {
            panel.markers.push(Marker {
                x: time,
                y: error,
                label: format!("{}", r.steps_per_period),
                colour,
            });
        }
    }
    if !panel.notes.is_empty() {
        panel
            .notes
            .insert(0, "no point (refused or stopped):".into());
    }
    panel
}
