//! `simulate`: the motion from rest under Φ(t) = bias + ac·sin(2π·f·t), watched by the
//! dynamic safety monitor (the six checks of model.md §6 at every step).

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use de_resonator::{Device, DeviceParams};
use serde::Serialize;

use super::{prepare_file, short, sig, write_path, Crossing, DeviceArgs, DeviceInfo, Report};
use crate::engine::open_loop::{self, Choice, OpenLoop, Start};
use crate::engine::solver::{Solver, Tolerance};
use crate::plot::{svg, Marker, Panel, Series, RED};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Static bias, V.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub bias_volts: f64,
    /// AC amplitude, V (needs --ac-hz).
    #[arg(
        long,
        value_name = "V",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub ac_volts: f64,
    /// AC drive frequency, Hz (the settings' `ac_hz`).
    #[arg(
        long,
        visible_alias = "drive-hz",
        value_name = "HZ",
        allow_negative_numbers = true
    )]
    pub ac_hz: Option<f64>,
    /// Viscous damping c, N·s (overrides the device's).
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub damping: Option<f64>,
    /// Simulated time, s.
    #[arg(
        long,
        visible_alias = "duration",
        value_name = "S",
        allow_negative_numbers = true
    )]
    pub duration_seconds: f64,
    /// Where the motion starts from rest.
    ///
    /// At the bias's equilibrium, or at the pre-stretch with the voltage switched on at
    /// t = 0.
    #[arg(long, value_enum, default_value_t = Start::Equilibrium)]
    pub start: Start,
    /// A start state of one's own, over --start: the stretch and dλ/dt (1/s), `S,V`.
    #[arg(long, value_name = "S,V", allow_hyphen_values = true)]
    pub y0: Option<String>,
    /// The times to give the trajectory at (`--csv`, `--trajectory`), s, as SciPy's `t_eval`:
    /// `a,b,c` or `from:to:count`, increasing, within the run.
    #[arg(long, value_name = "TIMES", allow_hyphen_values = true)]
    pub t_eval: Option<String>,
    /// The integrator: a reference (adaptive, f64) or a core fixed-step method.
    ///
    /// `reference` (adaptive DOP853, rtol = atol = 1e-12, f64), `reference-radau` (adaptive
    /// Radau IIA 5 at 1e-10, for stiff scenes), `reference-bdf` (adaptive BDF at 1e-10, with
    /// `--features bdf`) or a core fixed-step method: rk4, verlet,
    /// implicit-midpoint, each with -f32 (as on the target) or -f64.
    #[arg(long, value_name = "M", value_enum, default_value_t = Choice::Reference, hide_possible_values = true)]
    pub method: Choice,
    /// Step, s (the reference's output spacing), shortened if need be so that a whole number of
    /// steps ends at the duration exactly.
    ///
    /// Default: 1/64 of the small-oscillation period at zero bias.
    #[arg(
        long,
        visible_alias = "step",
        value_name = "S",
        allow_negative_numbers = true
    )]
    pub step_seconds: Option<f64>,
    /// The reference's relative tolerance.
    ///
    /// Default: 1e-12 (`reference`), 1e-10 (`reference-radau`, `reference-bdf`). Radau keeps
    /// 1.59e-11 at least (RADAU5's floor): below it the report's solver note says so.
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// The reference's absolute tolerance (on the stretch, and on its rate in the model's time
    /// unit).
    ///
    /// Default: the relative tolerance.
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub atol: Option<f64>,
    /// Write the trajectory as CSV (time_seconds, stretch, velocity_per_second, volts); `-`:
    /// to stdout (the report then goes to stderr).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Put the trajectory in the report (`--json`: `trajectory` with the columns of `--csv`).
    #[arg(long)]
    pub trajectory: bool,
    /// Plot the trajectory as SVG.
    ///
    /// The stretch against time, with the loading branch's limit stretch and the first
    /// crossing marked.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// One sample of `--csv` and `--trajectory`.
#[derive(Serialize, Debug)]
pub struct Sample {
    time_seconds: f64,
    stretch: f64,
    velocity_per_second: f64,
    volts: f64,
}

/// The final state of a run.
#[derive(Serialize, Debug)]
pub struct Final {
    pub stretch: f64,
    /// dλ/dt, 1/s.
    pub velocity: f64,
}

/// What `simulate` was asked, echoed in its report.
#[derive(Serialize, Debug)]
pub struct Inputs {
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: f64,
    /// c in force (the device's, or `--damping`), N·s.
    pub damping: f64,
    pub duration_seconds: f64,
    pub start: Start,
    /// The start state asked for (stretch, dλ/dt in 1/s), over `start`.
    pub y0: Option<[f64; 2]>,
    /// The times the trajectory is given at (`--t-eval`; `null`: every step).
    pub t_eval_points: Option<usize>,
    /// The step asked for (`null`: the default, 1/64 of the period at zero bias).
    pub step_seconds: Option<f64>,
}

/// What `simulate` reports.
#[derive(Serialize, Debug)]
pub struct SimulateReport {
    pub device: DeviceInfo,
    pub inputs: Inputs,
    pub method: &'static str,
    /// The adaptive solver that ran (`null` for a core method): `radau` when the reference
    /// found the scene stiff for DOP853, with `solver_note` saying so.
    pub solver: Option<&'static str>,
    /// Why the solver differs from the one asked, or solved at another tolerance (Radau's
    /// floor), in words; `null` where neither.
    pub solver_note: Option<String>,
    /// The reference's tolerance (`null` for the core's fixed-step methods).
    pub tolerance: Option<Tolerance>,
    pub step_seconds: f64,
    pub steps: usize,
    #[serde(rename = "final")]
    pub end: Final,
    pub min_stretch: f64,
    pub max_stretch: f64,
    /// The first check the trajectory failed, and when.
    pub first_limit: Option<Crossing>,
    /// Why the run ended before its duration (a core method's step left the range it was
    /// checked for): the samples up to there are the report's.
    pub stopped: Option<String>,
    pub run_seconds: f64,
    /// What `--csv` and `--plot` wrote.
    pub files: Vec<String>,
    /// The samples, with `--trajectory`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<Vec<Sample>>,
    #[serde(skip)]
    first_limit_description: Option<&'static str>,
}

impl fmt::Display for SimulateReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let limit = match (self.first_limit, self.first_limit_description) {
            (Some(c), Some(what)) => format!("{what} at t = {} s", sig(c.time_seconds)),
            _ => "none crossed".into(),
        };
        write!(
            f,
            "device          {}\n\
             method          {}{}{}, step {} s, {} steps in {} ms\n\
             final           stretch {}, velocity {} 1/s\n\
             stretch range   {} .. {}\n\
             first limit     {limit}{}{}",
            self.device,
            self.method,
            self.solver_note
                .as_ref()
                .map_or(String::new(), |n| format!(" ({n})")),
            self.tolerance.map_or(String::new(), |t| format!(
                " (rtol {}, atol {})",
                sig(t.rtol),
                sig(t.atol)
            )),
            sig(self.step_seconds),
            self.steps,
            sig(self.run_seconds * 1e3),
            sig(self.end.stretch),
            sig(self.end.velocity),
            sig(self.min_stretch),
            sig(self.max_stretch),
            self.stopped
                .as_ref()
                .map_or(String::new(), |why| format!("\nstopped         {why}")),
            self.files
                .iter()
                .map(|f| format!("\nwrote           {f}"))
                .collect::<String>(),
        )
    }
}

impl Report for SimulateReport {
    fn data_on_stdout(&self) -> bool {
        self.files.iter().any(|f| f == "-")
    }

    /// Done, but the trajectory crossed a limit, or the method stopped before the end
    /// (exit status 1: a result, not bad input).
    fn failure(&self) -> Option<String> {
        let crossed = self.first_limit.map(|c| {
            format!(
                "the trajectory crossed {} at {} s",
                c.mode,
                sig(c.time_seconds)
            )
        });
        let stopped = self
            .stopped
            .as_ref()
            .map(|why| format!("the method stopped before the end: {why}"));
        match (crossed, stopped) {
            (Some(c), Some(s)) => Some(format!("{c}; {s}")),
            (c, s) => c.or(s),
        }
    }
}

/// What a run of the motion is asked, whoever asks (the CLI, the Python package): checked
/// into the open-loop scene and its output step.
#[derive(Clone, Copy, Debug)]
pub struct Asked {
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: Option<f64>,
    /// c, N·s, over the device's.
    pub damping: Option<f64>,
    pub duration_seconds: f64,
    pub start: Start,
    /// A start state of one's own (stretch, dλ/dt in 1/s), over `start`.
    pub y0: Option<[f64; 2]>,
    pub method: Choice,
    pub step_seconds: Option<f64>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
}

impl Asked {
    /// The scene on `params` (its damping replaced if asked) and the output step (the
    /// default: 1/64 of the period at 0 V); errors name the device as `device` says it.
    pub fn scene(
        &self,
        mut params: DeviceParams<f64>,
        device: &DeviceInfo,
    ) -> Result<(OpenLoop, f64), String> {
        if let Some(c) = self.damping {
            params.damping = c;
        }
        let checked = Device::new(params).map_err(|e| format!("{device}: {e}"))?;
        let ac_hz = match self.ac_hz {
            Some(hz) if !(hz.is_finite() && hz >= 0.0) => {
                return Err(format!("ac_hz (--ac-hz) {hz}: need a finite frequency ≥ 0"))
            }
            Some(hz) => hz,
            None if self.ac_volts != 0.0 => {
                return Err(format!(
                    "ac_volts {} needs ac_hz (--ac-hz): the drive's frequency",
                    sig(self.ac_volts)
                ))
            }
            None => 0.0,
        };
        let step = self
            .step_seconds
            .unwrap_or(1.0 / (64.0 * checked.natural_frequency_hz(checked.prestretch_1())));
        let tolerance = match (self.rtol, self.atol) {
            (None, None) => None,
            (rtol, atol) => {
                let default = self.method.solver().unwrap_or(Solver::Dop853);
                let rtol = rtol.unwrap_or(default.default_tolerance().rtol);
                Some(Tolerance {
                    rtol,
                    atol: atol.unwrap_or(rtol),
                })
            }
        };
        let scene = OpenLoop {
            params,
            bias_volts: self.bias_volts,
            ac_volts: self.ac_volts,
            drive_hz: ac_hz,
            duration_seconds: self.duration_seconds,
            start: self.start,
            y0: self.y0,
            tolerance,
        };
        Ok((scene, step))
    }
}

/// The most `--t-eval` times.
pub const MAX_T_EVAL: usize = 10_000_000;

pub fn simulate(args: &SimulateArgs) -> Result<SimulateReport, String> {
    let (params, device) = args.device.source().params()?;
    let asked = Asked {
        bias_volts: args.bias_volts,
        ac_volts: args.ac_volts,
        ac_hz: args.ac_hz,
        damping: args.damping,
        duration_seconds: args.duration_seconds,
        start: args.start,
        y0: args
            .y0
            .as_deref()
            .map(|t| super::state("--y0", t))
            .transpose()?,
        method: args.method,
        step_seconds: args.step_seconds,
        rtol: args.rtol,
        atol: args.atol,
    };
    let t_eval = args
        .t_eval
        .as_deref()
        .map(|text| super::values("--t-eval", text, MAX_T_EVAL))
        .transpose()?;
    let (scene, step) = asked.scene(params, &device)?;
    let checked = Device::new(scene.params).map_err(|e| format!("{device}: {e}"))?;
    let ac_hz = scene.drive_hz;
    // Where the files go, checked before the work.
    for path in [&args.csv, &args.plot].into_iter().flatten() {
        prepare_file(path)?;
    }
    let out = open_loop::simulate_at(&scene, args.method, step, t_eval.as_deref())
        .map_err(|e| e.to_string())?;
    let volts_at =
        |t: f64| args.bias_volts + args.ac_volts * (std::f64::consts::TAU * ac_hz * t).sin();
    let mut files = Vec::new();
    // The samples: at the times asked for, or every step.
    let sample = |time_seconds: f64, stretch: f64, velocity_per_second: f64| Sample {
        time_seconds,
        stretch,
        velocity_per_second,
        volts: volts_at(time_seconds),
    };
    let rows = (args.csv.is_some() || args.trajectory).then(|| match &out.evaluated {
        Some(at) => (0..at.times_seconds.len())
            .map(|k| {
                sample(
                    at.times_seconds[k],
                    at.stretch[k],
                    at.velocity_per_second[k],
                )
            })
            .collect::<Vec<Sample>>(),
        None => (0..out.samples.len())
            .map(|k| {
                sample(
                    k as f64 * out.step_seconds,
                    out.samples[k],
                    out.velocities[k],
                )
            })
            .collect(),
    });
    if let (Some(path), Some(rows)) = (&args.csv, &rows) {
        files.push(write_path(path, &super::csv(rows)?)?);
    }
    if let Some(path) = &args.plot {
        let panel = plot(&device, &checked, &scene, &out, args.method.name());
        files.push(write_path(path, svg(&[panel]).as_bytes())?);
    }
    Ok(SimulateReport {
        device,
        inputs: Inputs {
            bias_volts: args.bias_volts,
            ac_volts: args.ac_volts,
            ac_hz,
            damping: scene.params.damping,
            duration_seconds: args.duration_seconds,
            start: args.start,
            y0: asked.y0,
            t_eval_points: t_eval.as_ref().map(Vec::len),
            step_seconds: args.step_seconds,
        },
        method: args.method.name(),
        solver: out.solver.map(Solver::name),
        solver_note: out.switched.clone(),
        tolerance: out.solver.map(|solver| scene.tolerance_of(solver)),
        step_seconds: out.step_seconds,
        steps: out.samples.len().saturating_sub(1),
        end: Final {
            stretch: out.final_stretch,
            velocity: out.final_velocity_per_second,
        },
        min_stretch: out.min_stretch,
        max_stretch: out.max_stretch,
        first_limit: Crossing::with_state(out.first_limit, out.first_limit_state),
        stopped: out.stopped.clone(),
        run_seconds: out.run_seconds,
        files,
        trajectory: args.trajectory.then_some(rows).flatten(),
        first_limit_description: out.first_limit.map(|(mode, _)| mode.description()),
    })
}

/// The stretch against time, the limit's stretch on the loading branch as a level, the
/// first crossing marked where the run located it. With no AC the bias is constant and so is
/// the stretch at which the check that fired fails: that stretch is a level too.
fn plot(
    device: &DeviceInfo,
    checked: &Device<f64>,
    scene: &OpenLoop,
    out: &open_loop::Outcome,
    method: &str,
) -> Panel {
    let limit = de_resonator::Limit::of(checked);
    let dt = out.step_seconds;
    let points: Vec<(f64, f64)> = out
        .samples
        .iter()
        .enumerate()
        .map(|(k, &x)| (k as f64 * dt, x))
        .collect();
    let no_ac = scene.ac_volts == 0.0 || scene.drive_hz <= 0.0;
    let mut levels = vec![(
        limit.at.stretch,
        format!("static limit ({}) stretch", limit.mode.name()),
    )];
    let mut markers = Vec::new();
    // The crossing where the run located it (between samples). With no AC the bias is
    // constant and so is the stretch at which the check that fired fails: a level too.
    if let (Some((mode, t)), Some((stretch, _))) = (out.first_limit, out.first_limit_state) {
        if no_ac {
            levels.push((
                stretch,
                format!(
                    "{} at {} V: stretch {}",
                    mode.name(),
                    sig(scene.bias_volts),
                    sig(stretch)
                ),
            ));
        }
        markers.push(Marker {
            x: t,
            y: stretch,
            label: format!("{} at {} s", mode.name(), short(t)),
            colour: RED,
        });
    }
    let ac = if no_ac {
        "no AC".to_string()
    } else {
        format!("{} V AC at {} Hz", sig(scene.ac_volts), sig(scene.drive_hz))
    };
    Panel {
        title: format!("{}: {} V, {ac}", device.title(), short(scene.bias_volts)),
        x_label: "time, s".into(),
        y_label: "stretch λ".into(),
        series: vec![Series {
            name: method.into(),
            points,
            ..Series::default()
        }],
        levels,
        markers,
        ..Panel::default()
    }
}
