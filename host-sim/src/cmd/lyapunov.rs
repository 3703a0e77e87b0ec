//! `lyapunov`: the largest Lyapunov exponent of the driven membrane (model.md §4), from the
//! variational equation along the motion, with its convergence; lyapunov.csv and
//! lyapunov.svg (the running estimate against time).

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::poincare::{self, DrivenArgs};
use super::{prepare_dir, short, sig, write_csv_and_plot, Crossing, DeviceInfo, Report};
use crate::plot::{Panel, Series};
use crate::study::lyapunov;

#[derive(Args, Debug)]
pub struct LyapunovArgs {
    #[command(flatten)]
    pub drive: DrivenArgs,
    /// Renormalisation intervals measured: drive periods (without a drive, periods of the
    /// small oscillation at the start).
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub periods: usize,
    /// Intervals before the measurement.
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub transient_periods: usize,
    /// The start state, `S,V` (stretch and dλ/dt in 1/s).
    ///
    /// Default: at rest at the bias's equilibrium.
    #[arg(long, value_name = "S,V", allow_hyphen_values = true)]
    pub y0: Option<String>,
    /// Folder for lyapunov.csv and lyapunov.svg (created if needed, checked before the work).
    #[arg(long, value_name = "DIR", default_value = "out/lyapunov")]
    pub out: PathBuf,
}

/// The estimate after one interval: a CSV row.
#[derive(Serialize, Debug)]
pub struct Row {
    /// Time since the transient ended, s.
    pub time_seconds: f64,
    /// The exponent over that time, 1/s.
    pub estimate_per_second: f64,
}

/// What `lyapunov` reports.
#[derive(Serialize, Debug)]
pub struct LyapunovReport {
    pub device: DeviceInfo,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: f64,
    pub damping: f64,
    /// The largest exponent, 1/s (NaN: nothing measured).
    pub exponent_per_second: f64,
    /// How much the estimate moved over the last tenth of the run, 1/s.
    pub last_tenth_change_per_second: f64,
    pub interval_seconds: f64,
    pub first_limit: Option<Crossing>,
    pub stopped: Option<String>,
    pub rows: Vec<Row>,
    pub files: Vec<String>,
}

impl fmt::Display for LyapunovReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "device          {}\n\
             drive           {} V + {} V AC at {} Hz, c = {} N·s\n\
             exponent        {} 1/s (moved {} 1/s over the last tenth of {} intervals of {} s)\n\
             first limit     {}{}\n\
             wrote           {}",
            self.device,
            sig(self.bias_volts),
            sig(self.ac_volts),
            sig(self.ac_hz),
            sig(self.damping),
            sig(self.exponent_per_second),
            sig(self.last_tenth_change_per_second),
            self.rows.len(),
            sig(self.interval_seconds),
            self.first_limit.map_or("none crossed".into(), |c| format!(
                "{} at {} s",
                c.mode,
                sig(c.time_seconds)
            )),
            self.stopped
                .as_ref()
                .map_or(String::new(), |why| format!("\nstopped         {why}")),
            self.files.join(", ")
        )
    }
}

impl Report for LyapunovReport {
    fn failure(&self) -> Option<String> {
        poincare::failure(std::iter::once((&self.first_limit, &self.stopped)), "runs")
    }
}

pub fn lyapunov(args: &LyapunovArgs) -> Result<LyapunovReport, String> {
    let (driven, device) = args.drive.driven()?;
    let from = match &args.y0 {
        Some(text) => {
            let [stretch, velocity_per_second] = super::state("--y0", text)?;
            crate::study::stroboscopic::Point {
                stretch,
                velocity_per_second,
            }
        }
        None => driven.rest()?,
    };
    if args.periods == 0 {
        return Err("--periods 0: need at least 1".into());
    }
    prepare_dir(&args.out)?;
    let out = lyapunov::lyapunov(&driven, from, args.transient_periods, args.periods)?;
    crate::progress::interrupted([out.stopped.as_deref()])?;
    let rows: Vec<Row> = out
        .convergence
        .iter()
        .map(|&(time_seconds, estimate_per_second)| Row {
            time_seconds,
            estimate_per_second,
        })
        .collect();
    let tenth = rows.len() - rows.len() * 9 / 10;
    let last_tenth_change_per_second = match (rows.len().checked_sub(tenth + 1), rows.last()) {
        (Some(k), Some(last)) => (last.estimate_per_second - rows[k].estimate_per_second).abs(),
        _ => f64::NAN,
    };
    let panel = Panel {
        title: format!(
            "{}: largest Lyapunov exponent, {} V + {} V AC at {} Hz",
            device.title(),
            short(driven.bias_volts),
            short(driven.ac_volts),
            short(driven.ac_hz)
        ),
        x_label: "time after the transient, s".into(),
        y_label: "estimate, 1/s".into(),
        series: vec![Series {
            name: "running estimate".into(),
            points: rows
                .iter()
                .map(|r| (r.time_seconds, r.estimate_per_second))
                .collect(),
            ..Series::default()
        }],
        ..Panel::default()
    };
    let files = write_csv_and_plot(&args.out, "lyapunov", &rows, &[panel])?;
    Ok(LyapunovReport {
        device,
        bias_volts: driven.bias_volts,
        ac_volts: driven.ac_volts,
        ac_hz: driven.ac_hz,
        damping: driven.params.damping,
        exponent_per_second: out.per_second,
        last_tenth_change_per_second,
        interval_seconds: out.interval_seconds,
        first_limit: Crossing::of(out.first_limit),
        stopped: out.stopped,
        rows,
        files,
    })
}
