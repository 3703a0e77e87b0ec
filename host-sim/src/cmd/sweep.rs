//! `sweep`: the frequency response under parametric drive (model.md §7), its peaks, and
//! which drive frequencies crossed a limit or stopped; sweep.csv and sweep.svg.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use de_resonator::{Device, Tuner};
use serde::Serialize;

use super::{
    prepare_dir, short, sig, write_csv_and_plot, DeviceArgs, DeviceInfo, DeviceSource, Report,
};
use crate::plot::{Panel, Series, Style, GREY, RED};
use crate::study::frequency_response::{self, Sweep};

/// The default bias and AC amplitude, as fractions of the device's limit voltage: a drive
/// that means the same on every device (6000 V and 2000 V on the reference device).
pub const DEFAULT_BIAS_OF_LIMIT: f64 = 0.6;
pub const DEFAULT_AC_OF_LIMIT: f64 = 0.2;

/// The most drive frequencies, and the most RK4 steps over all of them (about 20 s of
/// work on 2 cores at ~20 ns a step).
pub const MAX_POINTS: usize = 100_000;
pub const MAX_STEPS: f64 = 2e9;

#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Static bias, V.
    ///
    /// Default: 0.6 of the device's limit voltage.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub bias_volts: Option<f64>,
    /// AC amplitude, V.
    ///
    /// Default: 0.2 of the device's limit voltage.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub ac_volts: Option<f64>,
    /// Quality factor Q of the small oscillation at the bias: sets the damping c = M·ω0/Q (M the
    /// effective mass of model.md §4).
    ///
    /// 0 keeps the device's damping.
    #[arg(
        long,
        visible_alias = "quality",
        value_name = "Q",
        default_value_t = 200.0,
        allow_negative_numbers = true
    )]
    pub quality_factor: f64,
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
    /// Drive frequencies, evenly spaced (3 to 100,000).
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
    /// Folder for sweep.csv and sweep.svg (created if needed, checked before the work).
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    pub out: PathBuf,
    #[command(flatten)]
    pub device: DeviceArgs,
}

impl SweepArgs {
    /// The sweep the flags ask for.
    pub fn asked(&self) -> Asked {
        Asked {
            bias_volts: self.bias_volts,
            ac_volts: self.ac_volts,
            quality_factor: self.quality_factor,
            from_ratio: self.from_ratio,
            to_ratio: self.to_ratio,
            points: self.points,
            periods: self.periods,
            steps_per_period: self.steps_per_period,
        }
    }
}

/// What a sweep is asked, whoever asks (the CLI, the Python package): the fields of
/// `SweepArgs` but the device and the folder, checked by `measure`.
#[derive(Clone, Copy, Debug)]
pub struct Asked {
    /// V; `None`: 0.6 of the device's limit voltage.
    pub bias_volts: Option<f64>,
    /// V; `None`: 0.2 of the device's limit voltage.
    pub ac_volts: Option<f64>,
    /// 0 keeps the device's damping.
    pub quality_factor: f64,
    /// The drive frequencies' range, as multiples of f0.
    pub from_ratio: f64,
    pub to_ratio: f64,
    pub points: usize,
    /// Each run's length, in periods of f0.
    pub periods: f64,
    /// RK4 steps per period of the faster of the drive and f0.
    pub steps_per_period: f64,
}

/// One drive frequency: a JSON point and a CSV row alike (the crossing flattened, an empty
/// cell where JSON has null).
#[derive(Serialize, Debug)]
pub struct Point {
    pub drive_hz: f64,
    /// drive_hz / f0.
    pub ratio: f64,
    /// Half the peak-to-peak stretch once settled; null when the run stopped.
    pub amplitude: Option<f64>,
    /// The first check of model.md §6 the motion failed (`null`: none).
    pub first_limit_mode: Option<&'static str>,
    pub first_limit_time_seconds: Option<f64>,
    /// The motion left the range in which the model is defined: nothing measured.
    pub stopped: bool,
}

/// A peak of the response (among the measured points).
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
    pub device: DeviceInfo,
    /// The device's limit on the loading branch, V (the defaults are fractions of it).
    pub limit_volts: f64,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub quality_factor: f64,
    /// c, N·s.
    pub damping: f64,
    /// Small oscillation at the bias, Hz.
    pub natural_frequency_hz: f64,
    pub peaks: Vec<Peak>,
    pub points: Vec<Point>,
    /// How many points crossed a limit of model.md §6 (exit status 1 if any).
    pub crossed_limit: usize,
    /// How many points stopped (no amplitude; never a peak).
    pub stopped: usize,
    pub files: Vec<String>,
}

impl fmt::Display for SweepReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "device          {}\n\
             drive           {} V bias + {} V AC ({:.0}% and {:.0}% of the limit {} V), \
             Q {} (c = {} N·s)\n\
             f0 at the bias  {} Hz\n\
             peaks           drive Hz    ratio   amplitude",
            self.device,
            sig(self.bias_volts),
            sig(self.ac_volts),
            100.0 * self.bias_volts / self.limit_volts,
            100.0 * self.ac_volts / self.limit_volts,
            sig(self.limit_volts),
            short(self.quality_factor),
            sig(self.damping),
            sig(self.natural_frequency_hz),
        )?;
        if self.bias_volts > self.limit_volts {
            writeln!(
                f,
                "note            the bias is above the limit: every run starts past it"
            )?;
        }
        if self.peaks.is_empty() {
            writeln!(f, "                none among the measured points")?;
        }
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
            "limits          {} of {} drive frequencies crossed a limit of model.md §6\n\
             stopped         {} of {} runs left the model's range (no amplitude, never a peak)\n\
             wrote           {}",
            self.crossed_limit,
            self.points.len(),
            self.stopped,
            self.points.len(),
            self.files.join(", ")
        )
    }
}

impl Report for SweepReport {
    /// Done, but the drive crossed a limit at some frequency, or no run gave an amplitude
    /// (every one stopped: nothing was measured).
    fn failure(&self) -> Option<String> {
        if self.crossed_limit > 0 {
            return Some(format!(
                "{} of {} drive frequencies crossed a limit of model.md §6",
                self.crossed_limit,
                self.points.len()
            ));
        }
        (!self.points.is_empty() && self.stopped == self.points.len()).then(|| {
            format!(
                "all {} runs stopped before settling: nothing was measured",
                self.stopped
            )
        })
    }
}

pub fn sweep(args: &SweepArgs) -> Result<SweepReport, String> {
    let (mut report, panel) = measure(&args.asked(), &args.device.source(), || {
        prepare_dir(&args.out)
    })?;
    report.files = write_csv_and_plot(&args.out, "sweep", &report.points, &[panel])?;
    Ok(report)
}

/// The sweep's report (no files) and its plot; `ready` runs once the arguments are checked,
/// before the work (where the files go, for the CLI).
pub fn measure(
    args: &Asked,
    device: &DeviceSource,
    ready: impl FnOnce() -> Result<(), String>,
) -> Result<(SweepReport, Panel), String> {
    let (mut params, device) = device.params()?;
    let quality = args.quality_factor;
    if !(quality.is_finite() && quality >= 0.0) {
        return Err(format!(
            "--quality-factor {quality}: need Q > 0 (or 0 for the device's damping)"
        ));
    }
    let limit_volts = Tuner::new(Device::new(params).map_err(|e| format!("{device}: {e}"))?)
        .limit()
        .at
        .volts;
    let bias_volts = args
        .bias_volts
        .unwrap_or(DEFAULT_BIAS_OF_LIMIT * limit_volts);
    let ac_volts = args.ac_volts.unwrap_or(DEFAULT_AC_OF_LIMIT * limit_volts);
    for (flag, v) in [("--bias-volts", bias_volts), ("--ac-volts", ac_volts)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!("{flag} {v}: need a finite voltage ≥ 0"));
        }
    }
    if args.points > MAX_POINTS {
        return Err(format!("--points {}: at most {MAX_POINTS}", args.points));
    }
    let mut s = Sweep {
        params,
        bias_volts,
        ac_volts,
        ratios: (args.from_ratio, args.to_ratio),
        points: args.points,
        periods: args.periods,
        steps_per_period: args.steps_per_period,
    };
    let (_, _, natural_hz) =
        frequency_response::operating_point(&s).map_err(|e| format!("{device}: {e}"))?;
    frequency_response::drive_frequencies(&s, natural_hz)?;
    // RK4 steps of the whole sweep: each point runs `periods` of f0 at `steps_per_period`
    // of the faster of drive and f0.
    let faster = (0.5 * (s.ratios.0 + s.ratios.1)).max(1.0);
    let steps = s.points as f64 * s.periods * s.steps_per_period * faster;
    if steps > MAX_STEPS {
        return Err(format!(
            "{} RK4 steps in all, more than {}: about {} s of work; fewer --points, \
             --periods or --steps-per-period",
            sig(steps),
            sig(MAX_STEPS),
            sig((steps * 2e-8 / 2.0).round())
        ));
    }
    ready()?;
    if quality > 0.0 {
        params.damping = params.damping_for_quality(natural_hz, quality);
        s.params = params;
    }
    let response = frequency_response::run(&s)?;
    let f0 = response.natural_frequency_hz;
    let points: Vec<Point> = response
        .points
        .iter()
        .map(|p| Point {
            drive_hz: p.drive_hz,
            ratio: p.drive_hz / f0,
            amplitude: p.amplitude,
            first_limit_mode: p.first_limit.map(|(m, _)| m.name()),
            first_limit_time_seconds: p.first_limit.map(|(_, t)| t),
            stopped: p.stopped.is_some(),
        })
        .collect();
    let crossed_limit = points
        .iter()
        .filter(|p| p.first_limit_mode.is_some())
        .count();
    let stopped = points.iter().filter(|p| p.stopped).count();
    let panel = plot(&device, &s, f0, quality, &points, stopped);
    let report = SweepReport {
        device,
        limit_volts,
        bias_volts,
        ac_volts,
        quality_factor: quality,
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
        points,
        crossed_limit,
        stopped,
        files: Vec::new(),
    };
    Ok((report, panel))
}

/// The response against drive frequency in Hz: measured points as a line (broken where runs
/// stopped), those that crossed a limit in red, stopped ones as triangles along the
/// frequency axis (nothing measured, so at no amplitude), red if they crossed a limit first.
fn plot(
    device: &DeviceInfo,
    s: &Sweep,
    f0: f64,
    quality: f64,
    points: &[Point],
    stopped: usize,
) -> Panel {
    let measured = |p: &Point| p.amplitude.map(|a| (p.drive_hz, a));
    let mut series: Vec<Series> = points
        .split(|p| p.stopped)
        .filter(|run| !run.is_empty())
        .enumerate()
        .map(|(k, run)| Series {
            name: if k == 0 {
                "amplitude".into()
            } else {
                String::new()
            },
            points: run.iter().filter_map(measured).collect(),
            style: Style {
                colour: Some(crate::plot::COLOURS[0]),
                ..Style::default()
            },
            label: String::new(),
        })
        .collect();
    series.push(Series {
        name: "crossed a limit".into(),
        points: points
            .iter()
            .filter(|p| p.first_limit_mode.is_some())
            .filter_map(measured)
            .collect(),
        style: Style {
            colour: Some(RED),
            dots_only: true,
            ..Style::default()
        },
        label: String::new(),
    });
    // No amplitude: marked along the frequency axis, at no value; red where the run crossed
    // a limit before it stopped (a crossing is a crossing, measured or not).
    for (name, colour, crossed) in [
        ("stopped after crossing a limit", RED, true),
        ("stopped: nothing measured", GREY, false),
    ] {
        series.push(Series {
            name: name.into(),
            points: points
                .iter()
                .filter(|p| p.stopped && p.first_limit_mode.is_some() == crossed)
                .map(|p| (p.drive_hz, f64::NAN))
                .collect(),
            style: Style {
                colour: Some(colour),
                on_axis: true,
                ..Style::default()
            },
            label: String::new(),
        });
    }
    series.retain(|s| !s.points.is_empty());
    Panel {
        title: format!(
            "{}: {} V + {} V AC, Q {}, f0 {} Hz",
            device.title(),
            short(s.bias_volts),
            short(s.ac_volts),
            short(quality),
            short(f0)
        ),
        x_label: "drive frequency, Hz".into(),
        y_label: "amplitude (stretch)".into(),
        log_y: true,
        series,
        guides: vec![
            (0.5 * f0, "f0/2".into()),
            (f0, "f0".into()),
            (2.0 * f0, "2 f0".into()),
        ],
        notes: vec![format!("{} of {} points stopped", stopped, points.len())],
        ..Panel::default()
    }
}
