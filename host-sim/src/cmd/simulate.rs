//! `simulate`: the motion from rest under Φ(t) = bias + ac·sin(2π·f·t), watched by the
//! dynamic safety monitor (the six checks of MODEL.md §6 at every step).

use std::fmt;

use clap::Args;
use de_resonator::Device;
use serde::Serialize;

use super::{sig, Crossing, DeviceArgs, Report};
use crate::simulate::{self, Choice, Scene, Solver, Start, Tolerance};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Static bias, V.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub bias_volts: f64,
    /// AC amplitude, V.
    #[arg(
        long,
        value_name = "A",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub ac_volts: f64,
    /// AC drive frequency, Hz.
    #[arg(long, value_name = "F", default_value_t = 0.0)]
    pub drive_hz: f64,
    /// Viscous damping c, N·s (overrides the device's).
    #[arg(long, value_name = "C")]
    pub damping: Option<f64>,
    /// Simulated time, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: f64,
    /// Start at rest at the bias's equilibrium, or at the pre-stretch with the voltage
    /// switched on at t = 0.
    #[arg(long, value_enum, default_value_t = Start::Equilibrium)]
    pub start: Start,
    /// `reference` (adaptive DOP853, rtol = atol = 1e-12, f64), `reference-bdf` (adaptive
    /// BDF at 1e-10, for stiff scenes) or a core fixed-step method: rk4, verlet,
    /// implicit-midpoint, each with -f32 (as on the target) or -f64.
    #[arg(long, value_name = "M", value_enum, default_value_t = Choice::Reference)]
    pub method: Choice,
    /// Step, s (the reference's output spacing), shortened if need be so that a whole number
    /// of steps ends at the duration exactly. Default: 1/64 of the small-oscillation period
    /// at zero bias.
    #[arg(long, value_name = "H", allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// The reference's relative tolerance. Default: 1e-12 (`reference`), 1e-10
    /// (`reference-bdf`).
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// The reference's absolute tolerance (on the stretch, and on its rate in the model's
    /// time unit). Default: the relative tolerance.
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub atol: Option<f64>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The final state of a run.
#[derive(Serialize, Debug)]
pub struct Final {
    pub stretch: f64,
    /// dλ/dt, 1/s.
    pub velocity: f64,
}

/// What `simulate` reports.
#[derive(Serialize, Debug)]
pub struct SimulateReport {
    #[serde(skip)]
    pub device: String,
    pub method: &'static str,
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
    pub run_seconds: f64,
    #[serde(skip)]
    first_limit_description: Option<&'static str>,
}

impl fmt::Display for SimulateReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let limit = match (self.first_limit, self.first_limit_description) {
            (Some(c), Some(what)) => format!("{what} at t = {} s", sig(c.time)),
            _ => "none crossed".into(),
        };
        write!(
            f,
            "device          {}\n\
             method          {}{}, step {} s, {} steps in {} ms\n\
             final           stretch {}, velocity {} 1/s\n\
             stretch range   {} .. {}\n\
             first limit     {limit}",
            self.device,
            self.method,
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
        )
    }
}

impl Report for SimulateReport {}

pub fn simulate(args: &SimulateArgs) -> Result<SimulateReport, String> {
    let (mut params, name) = args.device.params()?;
    if let Some(c) = args.damping {
        params.damping = c;
    }
    let checked = Device::new(params).map_err(|e| format!("{name}: {e}"))?;
    let step = args
        .step
        .unwrap_or(1.0 / (64.0 * checked.natural_frequency_hz(checked.prestretch_1())));
    let tolerance = match (args.rtol, args.atol) {
        (None, None) => None,
        (rtol, atol) => {
            let default = args.method.solver().unwrap_or(Solver::Dop853);
            let rtol = rtol.unwrap_or(default.default_tolerance().rtol);
            Some(Tolerance {
                rtol,
                atol: atol.unwrap_or(rtol),
            })
        }
    };
    let scene = Scene {
        params,
        bias_volts: args.bias_volts,
        ac_volts: args.ac_volts,
        drive_hz: args.drive_hz,
        duration_seconds: args.duration,
        start: args.start,
        tolerance,
    };
    let out = simulate::simulate(&scene, args.method, step).map_err(|e| e.to_string())?;
    Ok(SimulateReport {
        device: name,
        method: args.method.name(),
        tolerance: args
            .method
            .solver()
            .map(|solver| tolerance.unwrap_or(solver.default_tolerance())),
        step_seconds: out.step_seconds,
        steps: out.samples.len().saturating_sub(1),
        end: Final {
            stretch: out.final_stretch,
            velocity: out.final_velocity_per_second,
        },
        min_stretch: out.min_stretch,
        max_stretch: out.max_stretch,
        first_limit: Crossing::of(out.first_limit),
        run_seconds: out.run_seconds,
        first_limit_description: out.first_limit.map(|(mode, _)| mode.description()),
    })
}
