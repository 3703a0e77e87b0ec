//! `host-sim simulate`: integrate the resonator from rest with a core fixed-step method (f32
//! or f64, the code the firmware runs) or the reference (adaptive DOP853, f64), under the
//! dynamic safety monitor.

use std::time::Instant;

use de_resonator::{
    Device, DeviceParams, Drive, FailureMode, Integrator, Method, Monitor, Real, State, StepError,
};
use differential_equations::prelude::*;

/// Relative and absolute tolerance of the reference integrator.
pub const REFERENCE_TOLERANCE: f64 = 1e-12;

/// Tolerance of the stiff reference (BDF, orders 1 to 5): tighter costs many tiny steps.
pub const STIFF_REFERENCE_TOLERANCE: f64 = 1e-10;

/// An adaptive f64 solver from `differential-equations` (in scenes: `dop853` or `bdf`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Solver {
    /// Dormand–Prince 8(5,3), explicit: the reference for non-stiff scenes.
    Dop853,
    /// Backward differentiation formulas, implicit: for stiff scenes (a very light bar,
    /// a membrane near slack), where DOP853's step is bound by stability, not accuracy.
    Bdf,
}

/// How the simulation starts, from rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Start {
    /// At the bias's static equilibrium.
    Equilibrium,
    /// At the pre-stretch, with the voltage switched on at t = 0 (a voltage step).
    Prestretch,
}

/// Which integrator runs the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// Adaptive DOP853 at rtol = atol = 1e-12, f64.
    Reference,
    /// Adaptive BDF at rtol = atol = 1e-10, f64: the stiff reference.
    ReferenceBdf,
    /// A core fixed-step method, in f32 (as on the target) or f64.
    Core { method: Method, single: bool },
}

impl Choice {
    /// Every method: the references, then each core method in f32 and f64.
    pub const ALL: [Choice; 8] = [
        Choice::Reference,
        Choice::ReferenceBdf,
        Choice::Core {
            method: Method::Rk4,
            single: true,
        },
        Choice::Core {
            method: Method::Rk4,
            single: false,
        },
        Choice::Core {
            method: Method::Verlet,
            single: true,
        },
        Choice::Core {
            method: Method::Verlet,
            single: false,
        },
        Choice::Core {
            method: Method::ImplicitMidpoint,
            single: true,
        },
        Choice::Core {
            method: Method::ImplicitMidpoint,
            single: false,
        },
    ];

    /// The core's fixed-step methods only, f32 then f64 for each.
    pub fn core() -> Vec<Choice> {
        Choice::ALL
            .into_iter()
            .filter(|c| matches!(c, Choice::Core { .. }))
            .collect()
    }

    /// Its name: `reference`, `reference-bdf`, and `rk4`, `verlet`, `implicit-midpoint` with
    /// `-f32` or `-f64`.
    pub fn name(&self) -> &'static str {
        match self {
            Choice::Reference => "reference",
            Choice::ReferenceBdf => "reference-bdf",
            Choice::Core { method, single } => match (method, single) {
                (Method::Rk4, true) => "rk4-f32",
                (Method::Rk4, false) => "rk4-f64",
                (Method::Verlet, true) => "verlet-f32",
                (Method::Verlet, false) => "verlet-f64",
                (Method::ImplicitMidpoint, true) => "implicit-midpoint-f32",
                (Method::ImplicitMidpoint, false) => "implicit-midpoint-f64",
            },
        }
    }
}

impl clap::ValueEnum for Choice {
    fn value_variants<'a>() -> &'a [Self] {
        &Choice::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// What to simulate.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    pub params: DeviceParams<f64>,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub drive_hz: f64,
    pub duration_seconds: f64,
    pub start: Start,
}

/// What a run gives.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub final_stretch: f64,
    /// dλ/dt, 1/s.
    pub final_velocity_per_second: f64,
    pub min_stretch: f64,
    pub max_stretch: f64,
    /// The first failing check along the trajectory, and when (s).
    pub first_limit: Option<(FailureMode, f64)>,
    /// Stretch at t = k·step, k = 0, 1, ...
    pub samples: Vec<f64>,
    /// dλ/dt at the same times, 1/s.
    pub velocities: Vec<f64>,
    /// Why the run ended before its duration (after a crossing the monitor reported).
    pub stopped: Option<String>,
    pub run_seconds: f64,
}

impl Scene {
    /// The starting stretch, from rest.
    fn start_stretch(&self, device: &Device<f64>) -> Result<f64, String> {
        match self.start {
            Start::Prestretch => Ok(device.prestretch_1()),
            Start::Equilibrium => device
                .stretch_for_bias(self.bias_volts, device.scan_end_stretch())
                .ok_or_else(|| {
                    format!(
                        "no equilibrium holds {} V on the loading branch; try --start prestretch",
                        self.bias_volts
                    )
                }),
        }
    }
}

/// Why a run gave no outcome.
#[derive(Clone, Debug, PartialEq)]
pub enum RunError {
    /// The stability guard refused the step.
    Refused(String),
    /// Bad settings, or the integration stopped with a typed error before any crossing.
    Failed(String),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Refused(why) | RunError::Failed(why) => f.write_str(why),
        }
    }
}

impl From<String> for RunError {
    fn from(why: String) -> Self {
        RunError::Failed(why)
    }
}

/// Run a scene with a method and a step (seconds; the reference samples at this spacing).
pub fn simulate(scene: &Scene, choice: Choice, step_seconds: f64) -> Result<Outcome, RunError> {
    if !(scene.duration_seconds.is_finite() && scene.duration_seconds > 0.0) {
        let why = format!("duration {} s must be positive", scene.duration_seconds);
        return Err(why.into());
    }
    if !(step_seconds.is_finite() && step_seconds > 0.0) {
        return Err(format!("step {step_seconds} s must be positive").into());
    }
    let steps = (scene.duration_seconds / step_seconds).round().max(1.0) as u64;
    let device = Device::new(scene.params).map_err(|e| e.to_string())?;
    let start = scene.start_stretch(&device)?;
    let started = Instant::now();
    let mut outcome = match choice {
        Choice::Reference => reference(scene, &device, start, step_seconds, steps, Solver::Dop853)?,
        Choice::ReferenceBdf => reference(scene, &device, start, step_seconds, steps, Solver::Bdf)?,
        Choice::Core {
            method,
            single: true,
        } => core::<f32>(scene, method, start, step_seconds, steps)?,
        Choice::Core {
            method,
            single: false,
        } => core::<f64>(scene, method, start, step_seconds, steps)?,
    };
    outcome.run_seconds = started.elapsed().as_secs_f64();
    Ok(outcome)
}

/// The samples' min, max and last state into an outcome.
fn outcome(samples: Vec<f64>, velocities: Vec<f64>) -> Outcome {
    let min = samples.iter().copied().fold(f64::INFINITY, f64::min);
    let max = samples.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Outcome {
        final_stretch: *samples.last().unwrap_or(&f64::NAN),
        final_velocity_per_second: *velocities.last().unwrap_or(&f64::NAN),
        min_stretch: min,
        max_stretch: max,
        first_limit: None,
        samples,
        velocities,
        stopped: None,
        run_seconds: 0.0,
    }
}

fn core<T: Real>(
    scene: &Scene,
    method: Method,
    start: f64,
    step_seconds: f64,
    steps: u64,
) -> Result<Outcome, RunError> {
    let params = scene.params.cast::<T>();
    let device = Device::new(params).map_err(|e| e.to_string())?;
    let range = Device::new(scene.params)
        .map_err(|e| e.to_string())?
        .model_range();
    let drive = Drive::from_volts(
        &device,
        T::of(scene.bias_volts),
        T::of(scene.ac_volts),
        T::of(scene.drive_hz),
    );
    let mut it = Integrator::new(
        device,
        drive,
        method,
        T::of(step_seconds),
        (T::of(range.0), T::of(range.1)),
        State {
            stretch: T::of(start),
            velocity: T::zero(),
        },
        false,
    )
    .map_err(|e| match e {
        StepError::Unstable { .. } => RunError::Refused(e.to_string()),
        _ => RunError::Failed(e.to_string()),
    })?;
    let mut stopped = None;
    let mut monitor = Monitor::new();
    let scale = device.rad_per_s_per_unit().to_f64();
    let mut samples = Vec::with_capacity(steps as usize + 1);
    let mut velocities = Vec::with_capacity(steps as usize + 1);
    samples.push(start);
    velocities.push(0.0);
    monitor.observe(&device, 0, T::of(start), it.bias_dimless_squared());
    for _ in 0..steps {
        if let Err(e) = it.step() {
            // Past the guarded range the model is no longer trusted: stop, say why.
            if monitor.first_crossing().is_none() {
                return Err(RunError::Failed(e.to_string()));
            }
            stopped = Some(e.to_string());
            break;
        }
        let s = it.state();
        samples.push(s.stretch.to_f64());
        velocities.push(s.velocity.to_f64() * scale);
        monitor.observe(&device, it.tick(), s.stretch, it.bias_dimless_squared());
    }
    let mut out = outcome(samples, velocities);
    out.stopped = stopped;
    out.first_limit = monitor
        .first_crossing()
        .map(|c| (c.mode, c.tick as f64 * step_seconds));
    Ok(out)
}

/// The equation of motion for the reference integrator, dimensionless time.
struct Motion<'a> {
    device: &'a Device<f64>,
    drive: Drive<f64>,
}

impl ODE<f64, [f64; 2]> for Motion<'_> {
    fn diff(&self, tau: f64, y: &[f64; 2], dydt: &mut [f64; 2]) {
        let state = State {
            stretch: y[0],
            velocity: y[1],
        };
        dydt[0] = y[1];
        dydt[1] = self
            .device
            .acceleration(state, self.drive.bias_dimless_squared_at(tau));
    }

    /// ∂(λ', λ'')/∂(λ, λ'): the local stiffness of MODEL.md §5 and the damping, exact.
    fn jacobian(&self, tau: f64, y: &[f64; 2], j: &mut Matrix<f64>) {
        let p2 = self.drive.bias_dimless_squared_at(tau);
        j[(0, 0)] = 0.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -self.device.stiffness_dimless(y[0], p2);
        j[(1, 1)] = -self.device.damping_dimless();
    }
}

/// Integrate `device` under `drive` from `y0` over dimensionless `[0, tau_end]`, output every
/// `dtau`, with `solver` at `tolerance`. Each output interval is a solve of its own: the
/// crate's dense output (`even`) was measured 5.6e-8 off between steps, far above the
/// 1e-12 tolerance, so no sample comes from interpolation.
pub fn solve(
    solver: Solver,
    device: &Device<f64>,
    drive: Drive<f64>,
    y0: [f64; 2],
    tau_end: f64,
    dtau: f64,
    tolerance: f64,
) -> Result<Vec<[f64; 2]>, String> {
    let motion = Motion { device, drive };
    let intervals = (tau_end / dtau).round().max(1.0) as usize;
    let mut ys = Vec::with_capacity(intervals + 1);
    ys.push(y0);
    let mut y = y0;
    for k in 0..intervals {
        let (t0, t1) = (k as f64 * dtau, (k + 1) as f64 * dtau);
        y = solver
            .advance(&motion, t0, t1, y, tolerance)
            .map_err(|e| format!("reference integrator at τ = {t0}: {e}"))?;
        ys.push(y);
    }
    Ok(ys)
}

impl Solver {
    /// Advance `y` of `ode` from `t0` to `t1` at `tolerance` (relative and absolute): the
    /// state at `t1`.
    pub fn advance<Y: differential_equations::traits::State<f64>, F: ODE<f64, Y>>(
        self,
        ode: &F,
        t0: f64,
        t1: f64,
        y: Y,
        tolerance: f64,
    ) -> Result<Y, String> {
        let problem = IVP::ode(ode, t0, t1, y);
        let solution = match self {
            Solver::Dop853 => problem
                .method(ExplicitRungeKutta::dop853().rtol(tolerance).atol(tolerance))
                .solve(),
            Solver::Bdf => problem
                .method(
                    BackwardDifferentiationFormula::adaptive()
                        .rtol(tolerance)
                        .atol(tolerance)
                        .max_steps(10_000_000),
                )
                .solve(),
        }
        .map_err(|e| format!("failed: {e:?}"))?;
        solution
            .y
            .last()
            .cloned()
            .ok_or_else(|| "no state returned".to_string())
    }
}

fn reference(
    scene: &Scene,
    device: &Device<f64>,
    start: f64,
    step_seconds: f64,
    steps: u64,
    solver: Solver,
) -> Result<Outcome, String> {
    let drive = Drive::from_volts(device, scene.bias_volts, scene.ac_volts, scene.drive_hz);
    let scale = device.rad_per_s_per_unit();
    let dtau = step_seconds * scale;
    let tolerance = match solver {
        Solver::Dop853 => REFERENCE_TOLERANCE,
        Solver::Bdf => STIFF_REFERENCE_TOLERANCE,
    };
    let ys = solve(
        solver,
        device,
        drive,
        [start, 0.0],
        steps as f64 * dtau,
        dtau,
        tolerance,
    )?;
    let mut monitor = Monitor::new();
    for (k, y) in ys.iter().enumerate() {
        let tau = k as f64 * dtau;
        monitor.observe(device, k as u64, y[0], drive.bias_dimless_squared_at(tau));
    }
    let mut out = outcome(
        ys.iter().map(|y| y[0]).collect(),
        ys.iter().map(|y| y[1] * scale).collect(),
    );
    out.first_limit = monitor
        .first_crossing()
        .map(|c| (c.mode, c.tick as f64 * step_seconds));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use de_resonator::REFERENCE_DEVICE;

    /// Closed form first: at zero bias, small amplitude, the reference follows
    /// λ* + a·cos(ωt) with ω from MODEL.md §5, to the level of the neglected nonlinearity.
    #[test]
    fn reference_matches_the_small_oscillation_closed_form() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let omega = device.omega_squared(2.0).sqrt();
        let scale = device.rad_per_s_per_unit();
        let a = 1e-7;
        let period = std::f64::consts::TAU / omega;
        let dt = period / 50.0;
        let drive = Drive::constant(&device, 0.0);
        let ys = solve(
            Solver::Dop853,
            &device,
            drive,
            [2.0 + a, 0.0],
            10.0 * period * scale,
            dt * scale,
            1e-13,
        )
        .unwrap();
        for (k, y) in ys.iter().enumerate() {
            let expected = 2.0 + a * (omega * k as f64 * dt).cos();
            // Nonlinear terms shift the frequency by O(a): 1e-7 relative over 10 periods.
            assert!(
                (y[0] - expected).abs() < 1e-5 * a,
                "k {k}: {} vs {expected}",
                y[0]
            );
        }
    }

    /// The reference's own error floor: tolerance 1e-12 against 1e-13 on a driven scene.
    #[test]
    fn reference_tolerances_agree() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let scale = device.rad_per_s_per_unit();
        let drive = Drive::from_volts(&device, 7000.0, 1500.0, 30.0);
        let run = |tol| {
            let (y0, end, every) = ([2.1, 0.0], 0.5 * scale, 0.01 * scale);
            solve(Solver::Dop853, &device, drive, y0, end, every, tol).unwrap()
        };
        let (a, b) = (run(1e-12), run(1e-13));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x[0] - y[0]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10, "{worst}");
    }

    /// The stiff reference (BDF at 1e-10) against DOP853 at 1e-12 on a driven scene and on a
    /// light bar (ω 30 times the reference's): a second method agreeing to its tolerance.
    #[test]
    fn bdf_agrees_with_dop853() {
        let light = DeviceParams {
            bar_mass: 0.0,
            density: 9.6,
            ..REFERENCE_DEVICE
        };
        for (params, bias, ac, hz, seconds) in [
            (REFERENCE_DEVICE, 7000.0, 1500.0, 30.0, 0.5),
            (light, 5000.0, 500.0, 1000.0, 0.02),
        ] {
            let device = Device::new(params).unwrap();
            let scale = device.rad_per_s_per_unit();
            let drive = Drive::from_volts(&device, bias, ac, hz);
            let y0 = [device.stretch_for_bias(bias, 3.0).unwrap(), 0.0];
            let (end, every) = (seconds * scale, seconds / 50.0 * scale);
            let stiff = solve(Solver::Bdf, &device, drive, y0, end, every, 1e-10).unwrap();
            let accurate = solve(Solver::Dop853, &device, drive, y0, end, every, 1e-12).unwrap();
            let swing = accurate.iter().map(|y| y[0]).fold(0.0, f64::max)
                - accurate.iter().map(|y| y[0]).fold(f64::INFINITY, f64::min);
            assert!(swing > 1e-3, "the scene moves: {swing}");
            for (a, b) in stiff.iter().zip(&accurate) {
                assert!((a[0] - b[0]).abs() < 1e-6 * swing, "{} vs {}", a[0], b[0]);
            }
        }
    }

    #[test]
    fn method_names_round_trip() {
        use clap::ValueEnum;
        for choice in Choice::ALL {
            assert_eq!(Choice::from_str(choice.name(), false), Ok(choice));
        }
        assert!(Choice::from_str("euler", false).is_err());
        let names: Vec<&str> = Choice::value_variants().iter().map(Choice::name).collect();
        assert!(names.contains(&"rk4-f32") && names.len() == 8);
    }
}
