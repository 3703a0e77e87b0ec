//! `sweep`: the frequency response under parametric drive (MODEL.md §7), its peaks, and
//! which drive frequencies crossed a limit; sweep.csv and sweep.svg.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::{sig, write_file, Crossing, DeviceArgs, Report};
use crate::plot::{svg, Panel, Series};
use crate::sweep::{self, Sweep};

#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Static bias, V.
    #[arg(
        long,
        value_name = "V",
        default_value_t = 6000.0,
        allow_negative_numbers = true
    )]
    pub bias_volts: f64,
    /// AC amplitude, V.
    #[arg(
        long,
        value_name = "A",
        default_value_t = 2000.0,
        allow_negative_numbers = true
    )]
    pub ac_volts: f64,
    /// Quality factor Q of the small oscillation at the bias: sets the damping
    /// c = M·ω0/Q (M the effective mass of MODEL.md §4). 0 keeps the device's damping.
    #[arg(
        long,
        value_name = "Q",
        default_value_t = 200.0,
        allow_negative_numbers = true
    )]
    pub quality: f64,
    /// Lowest drive frequency, as a multiple of f0.
    #[arg(
        long,
        value_name = "R",
        default_value_t = 0.3,
        allow_negative_numbers = true
    )]
    pub from_ratio: f64,
    /// Highest drive frequency, as a multiple of f0.
    #[arg(
        long,
        value_name = "R",
        default_value_t = 2.4,
        allow_negative_numbers = true
    )]
    pub to_ratio: f64,
    /// Drive frequencies, evenly spaced.
    #[arg(long, value_name = "N", default_value_t = 211)]
    pub points: usize,
    /// Run length per drive frequency, in periods of f0 (the last quarter is measured).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 400.0,
        allow_negative_numbers = true
    )]
    pub periods: f64,
    /// RK4 steps (f64) per period of the faster of the drive and f0.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 48.0,
        allow_negative_numbers = true
    )]
    pub steps_per_period: f64,
    /// Folder for sweep.csv and sweep.svg (created if needed).
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// One drive frequency.
#[derive(Serialize, Debug)]
pub struct Point {
    pub drive_hz: f64,
    pub amplitude: f64,
    pub first_limit: Option<Crossing>,
    /// Why the run ended early (the motion left the model's range), if it did.
    pub stopped: Option<String>,
}

/// The same point as a CSV row.
#[derive(Serialize, Debug)]
struct Row {
    drive_hz: f64,
    ratio: f64,
    amplitude: f64,
    first_limit: &'static str,
    first_limit_time: Option<f64>,
    stopped: bool,
}

/// A peak of the response.
#[derive(Serialize, Debug)]
pub struct Peak {
    pub drive_hz: f64,
    pub amplitude: f64,
    /// drive_hz / f0.
    pub ratio: f64,
    pub prominence: f64,
}

/// What `sweep` reports.
#[derive(Serialize, Debug)]
pub struct SweepReport {
    #[serde(skip)]
    pub device: String,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub quality: f64,
    pub damping: f64,
    /// Small oscillation at the bias, Hz.
    pub natural_frequency_hz: f64,
    pub peaks: Vec<Peak>,
    pub points: Vec<Point>,
    /// How many points crossed a limit.
    pub crossed_limit: usize,
    pub csv: String,
    pub plot: String,
}

impl fmt::Display for SweepReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "device          {}\n\
             drive           {} V bias + {} V AC, Q {} (c = {} N·s)\n\
             f0 at the bias  {} Hz\n\
             peaks           drive Hz    ratio   amplitude",
            self.device,
            sig(self.bias_volts),
            sig(self.ac_volts),
            sig(self.quality),
            sig(self.damping),
            sig(self.natural_frequency_hz),
        )?;
        for p in &self.peaks {
            writeln!(
                f,
                "                {:>9}  {:>7}   {}",
                sig(p.drive_hz),
                format!("{:.3}", p.ratio),
                sig(p.amplitude)
            )?;
        }
        write!(
            f,
            "limits          {} of {} drive frequencies crossed a limit of MODEL.md §6\n\
             wrote           {}, {}",
            self.crossed_limit,
            self.points.len(),
            self.csv,
            self.plot
        )
    }
}

impl Report for SweepReport {}

pub fn sweep(args: &SweepArgs) -> Result<SweepReport, String> {
    let (mut params, name) = args.device.params()?;
    let quality = args.quality;
    if !(quality.is_finite() && quality >= 0.0) {
        return Err(format!(
            "quality {quality}: need Q > 0 (or 0 for the device's damping)"
        ));
    }
    let mut s = Sweep {
        params,
        bias_volts: args.bias_volts,
        ac_volts: args.ac_volts,
        ratios: (args.from_ratio, args.to_ratio),
        points: args.points,
        periods: args.periods,
        steps_per_period: args.steps_per_period,
    };
    let (_, _, natural_hz) = sweep::operating_point(&s).map_err(|e| format!("{name}: {e}"))?;
    if quality > 0.0 {
        params.damping = params.effective_mass() * std::f64::consts::TAU * natural_hz / quality;
        s.params = params;
    }
    let response = sweep::run(&s)?;
    let f0 = response.natural_frequency_hz;
    let rows: Vec<Row> = response
        .points
        .iter()
        .map(|p| Row {
            drive_hz: p.drive_hz,
            ratio: p.drive_hz / f0,
            amplitude: p.amplitude,
            first_limit: p.first_limit.map_or("", |(m, _)| m.name()),
            first_limit_time: p.first_limit.map(|(_, t)| t),
            stopped: p.stopped.is_some(),
        })
        .collect();
    let panel = Panel {
        title: format!(
            "Response: {:.0} V bias, {:.0} V AC, Q {quality}",
            s.bias_volts, s.ac_volts
        ),
        x_label: "drive frequency / f0".into(),
        y_label: "amplitude (stretch)".into(),
        log_y: true,
        series: vec![Series {
            name: format!("f0 = {} Hz", sig(f0)),
            points: rows.iter().map(|r| (r.ratio, r.amplitude)).collect(),
        }],
        guides: vec![
            (0.5, "f0/2".into()),
            (1.0, "f0".into()),
            (2.0, "2 f0".into()),
        ],
        ..Panel::default()
    };
    let csv = write_file(&args.out, "sweep.csv", &super::csv(&rows)?)?;
    let plot = write_file(&args.out, "sweep.svg", svg(&[panel]).as_bytes())?;
    let crossed_limit = rows.iter().filter(|r| r.first_limit_time.is_some()).count();
    Ok(SweepReport {
        device: name,
        bias_volts: s.bias_volts,
        ac_volts: s.ac_volts,
        quality,
        damping: s.params.damping,
        natural_frequency_hz: f0,
        peaks: response
            .peaks
            .iter()
            .map(|p| Peak {
                drive_hz: p.drive_hz,
                amplitude: p.amplitude,
                ratio: p.drive_hz / f0,
                prominence: p.prominence,
            })
            .collect(),
        points: response
            .points
            .into_iter()
            .map(|p| Point {
                drive_hz: p.drive_hz,
                amplitude: p.amplitude,
                first_limit: Crossing::of(p.first_limit),
                stopped: p.stopped,
            })
            .collect(),
        crossed_limit,
        csv,
        plot,
    })
}
