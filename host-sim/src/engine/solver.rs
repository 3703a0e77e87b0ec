//! The solvers: integrate the resonator from rest with a core fixed-step method (f32 or f64,
//! the code the firmware runs) or a reference (adaptive DOP853, Radau, BDF; f64), under the
//! dynamic safety monitor. `host-sim simulate` (`cmd::simulate`), the plant, the closed loop
//! and the studies run on it.

use std::cell::Cell;
use std::time::Instant;

use crate::engine::erk::{self, StepEnds, Stop, DOP853, DOPRI5};
use crate::engine::events::{self, Extremes, Hermite, Jet, Watch};
use crate::text::sig;

use de_resonator::{
    Device, DeviceParams, Drive, FailureMode, Integrator, Limit, Method, Monitor, Real, State,
    StepError,
};
use differential_equations::error::Error as SolveError;
use differential_equations::interpolate::Interpolation;
use differential_equations::ode::{solve_ode, OrdinaryNumericalMethod};
use differential_equations::prelude::*;
use differential_equations::solout::Solout;

/// Relative and absolute tolerance of the reference integrator.
pub const REFERENCE_TOLERANCE: f64 = 1e-12;

/// Tolerance of the stiff references (Radau IIA 5; BDF, orders 1 to 5): tighter costs many
/// tiny steps.
pub const STIFF_REFERENCE_TOLERANCE: f64 = 1e-10;

/// Events (the first crossing of a check) are located to this, s.
pub const EVENT_RESOLUTION_SECONDS: f64 = 1e-11;

/// BDF's path between output samples is a quintic through its own samples at this many
/// times the output's rate: at the default 1/64 period, (ωh)⁶/46080 is then 1e-16 of the
/// swing.
const BDF_EVENT_SUBDIVISION: usize = 8;

/// The most samples a run keeps (two f64 each, and as many monitor checks): 16 M, 256 MB.
pub const MAX_SAMPLES: f64 = 16.0 * 1024.0 * 1024.0;

/// An adaptive f64 solver (in scenes: `dop853`, `radau` or `bdf`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Solver {
    /// Dormand–Prince 8(5,3), explicit: the reference for non-stiff scenes.
    Dop853,
    /// Radau IIA of order 5 (Hairer's RADAU5, `differential-equations`), implicit: the stiff
    /// reference in every build, for scenes (a very light bar, a membrane near slack, a fast
    /// viscous branch) where DOP853's step is bound by stability, not accuracy.
    Radau,
    /// Backward differentiation formulas (diffsol, the `bdf` feature), implicit: a second
    /// stiff method to compare.
    Bdf,
}

/// How the simulation starts, from rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
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
    /// Adaptive Radau IIA 5 at rtol = atol = 1e-10, f64: the stiff reference.
    ReferenceRadau,
    /// Adaptive BDF at rtol = atol = 1e-10, f64 (the `bdf` feature).
    ReferenceBdf,
    /// A core fixed-step method, in f32 (as on the target) or f64.
    Core { method: Method, single: bool },
}

impl Choice {
    /// Every method: the references, then each core method in f32 and f64.
    pub const ALL: [Choice; 9] = [
        Choice::Reference,
        Choice::ReferenceRadau,
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

    /// Its name: `reference`, `reference-radau`, `reference-bdf`, and `rk4`, `verlet`,
    /// `implicit-midpoint` with `-f32` or `-f64`.
    pub fn name(&self) -> &'static str {
        match self {
            Choice::Reference => "reference",
            Choice::ReferenceRadau => "reference-radau",
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

impl Choice {
    /// The adaptive solver of a reference method (`None` for the core's fixed-step ones).
    pub fn solver(self) -> Option<Solver> {
        match self {
            Choice::Reference => Some(Solver::Dop853),
            Choice::ReferenceRadau => Some(Solver::Radau),
            Choice::ReferenceBdf => Some(Solver::Bdf),
            Choice::Core { .. } => None,
        }
    }
}

impl Solver {
    /// The solver's name in scenes and reports.
    pub fn name(self) -> &'static str {
        match self {
            Solver::Dop853 => "dop853",
            Solver::Radau => "radau",
            Solver::Bdf => "bdf",
        }
    }

    /// The reference's tolerance with this solver unless one is asked for.
    pub fn default_tolerance(self) -> Tolerance {
        Tolerance::both(match self {
            Solver::Dop853 => REFERENCE_TOLERANCE,
            Solver::Radau | Solver::Bdf => STIFF_REFERENCE_TOLERANCE,
        })
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

/// An open-loop simulation: a device under a fixed drive from a start, for a duration (the
/// closed loop with the controller is `crate::scene::Scene`).
#[derive(Clone, Copy, Debug)]
pub struct OpenLoop {
    pub params: DeviceParams<f64>,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub drive_hz: f64,
    pub duration_seconds: f64,
    pub start: Start,
    /// A start state of one's own, (stretch, dλ/dt in 1/s), over `start`.
    pub y0: Option<[f64; 2]>,
    /// The reference's tolerance (`None`: `REFERENCE_TOLERANCE` for DOP853,
    /// `STIFF_REFERENCE_TOLERANCE` for Radau and BDF); the core's methods have none.
    pub tolerance: Option<Tolerance>,
}

/// What a run gives.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub final_stretch: f64,
    /// dλ/dt, 1/s.
    pub final_velocity_per_second: f64,
    /// The stretch's true extremes: turns located between samples on the method's path (the
    /// reference's dense output; a quintic through the core's step ends).
    pub min_stretch: f64,
    pub max_stretch: f64,
    /// The first failing check along the trajectory, and when (s), located between samples
    /// to `EVENT_RESOLUTION_SECONDS`.
    pub first_limit: Option<(FailureMode, f64)>,
    /// The state where it first failed: stretch, and dλ/dt in 1/s.
    pub first_limit_state: Option<(f64, f64)>,
    /// Stretch at t = k·step, k = 0, 1, ...
    pub samples: Vec<f64>,
    /// dλ/dt at the same times, 1/s.
    pub velocities: Vec<f64>,
    /// Why the run ended before its duration: a core method's step left the range it was
    /// checked for (after a crossing the monitor reported, or before any).
    pub stopped: Option<String>,
    pub run_seconds: f64,
    /// The sample spacing: the step asked for, shortened so that a whole number of them ends
    /// at the duration exactly, s.
    pub step_seconds: f64,
    /// The adaptive solver that ran (`None` for a core method), and why the reference left
    /// DOP853 for Radau when it did.
    pub solver: Option<Solver>,
    pub switched: Option<String>,
    /// The right-hand sides the adaptive solver evaluated (`None` for a core method).
    pub evaluations: Option<u64>,
    /// The states at the times asked for ([`simulate_at`]), up to where the run ended.
    pub evaluated: Option<Evaluated>,
}

/// A run's states at times asked for (SciPy's `t_eval`): the reference's dense output there,
/// or the quintic through a core method's step ends.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Evaluated {
    pub times_seconds: Vec<f64>,
    pub stretch: Vec<f64>,
    pub velocity_per_second: Vec<f64>,
}

impl OpenLoop {
    /// The starting state: stretch and dλ/dτ (the model's time).
    fn start_state(&self, device: &Device<f64>) -> Result<[f64; 2], String> {
        if let Some([stretch, velocity]) = self.y0 {
            if !(stretch.is_finite() && velocity.is_finite()) {
                return Err(format!("y0 ({stretch}, {velocity}) must be finite numbers"));
            }
            return Ok([stretch, velocity / device.rad_per_s_per_unit()]);
        }
        self.start_stretch(device).map(|stretch| [stretch, 0.0])
    }

    /// The starting stretch of `start`, from rest.
    fn start_stretch(&self, device: &Device<f64>) -> Result<f64, String> {
        match self.start {
            Start::Prestretch => Ok(device.prestretch_1()),
            Start::Equilibrium => Limit::of(device)
                .stretch_for_bias(device, self.bias_volts)
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
pub fn simulate(scene: &OpenLoop, choice: Choice, step_seconds: f64) -> Result<Outcome, RunError> {
    simulate_at(scene, choice, step_seconds, None)
}

/// `simulate`, and the states at `t_eval` (s, increasing, within the run) too, as SciPy's
/// `t_eval` gives them: `Outcome::evaluated`.
pub fn simulate_at(
    scene: &OpenLoop,
    choice: Choice,
    step_seconds: f64,
    t_eval: Option<&[f64]>,
) -> Result<Outcome, RunError> {
    if let Some(times) = t_eval {
        let duration = scene.duration_seconds;
        if let Some(t) = times.iter().find(|t| !(**t >= 0.0 && **t <= duration)) {
            return Err(format!(
                "t_eval's {} s is outside the run, [0, {}] s",
                sig(*t),
                sig(duration)
            )
            .into());
        }
        if !times.windows(2).all(|w| w[0] <= w[1]) {
            return Err("t_eval's times must be in increasing order"
                .to_string()
                .into());
        }
    }
    if !(scene.duration_seconds.is_finite() && scene.duration_seconds > 0.0) {
        let why = format!("duration {} s must be positive", scene.duration_seconds);
        return Err(why.into());
    }
    if !(step_seconds.is_finite() && step_seconds > 0.0) {
        return Err(format!("step {step_seconds} s must be positive").into());
    }
    // (A drive that is not a number would have the solvers reject every step, forever.)
    for (what, value) in [
        ("bias", scene.bias_volts),
        ("AC amplitude", scene.ac_volts),
        ("AC frequency", scene.drive_hz),
    ] {
        if !value.is_finite() {
            return Err(format!("the {what} {value} must be a finite number").into());
        }
    }
    if scene.tolerance.is_some() && matches!(choice, Choice::Core { .. }) {
        let why = "a tolerance applies to the reference methods only (the core's are fixed-step)";
        return Err(why.to_string().into());
    }
    // A whole number of steps (a hair's float excess is not one more), ending at the
    // duration exactly.
    let steps = ((scene.duration_seconds / step_seconds) * (1.0 - 1e-12))
        .ceil()
        .max(1.0);
    if steps > MAX_SAMPLES {
        return Err(format!(
            "{} steps of {} s over {} s: more than {} (about {} GB of samples); use a longer \
             step or a shorter duration",
            sig(steps),
            sig(step_seconds),
            sig(scene.duration_seconds),
            sig(MAX_SAMPLES),
            sig((steps * 16.0 / 1e9).round())
        )
        .into());
    }
    let steps = steps as u64;
    let step_seconds = scene.duration_seconds / steps as f64;
    let device = Device::new(scene.params).map_err(|e| e.to_string())?;
    let start = scene.start_state(&device)?;
    let started = Instant::now();
    let mut outcome = match choice {
        // DOP853's stiffness test (Hairer's) hands a stiff scene to Radau, as LSODA would to
        // its BDF.
        Choice::Reference => {
            match reference(scene, &device, start, step_seconds, t_eval, Solver::Dop853) {
                Err(why) if why.starts_with(STIFF_FOR_DOP853) => {
                    let mut out =
                        reference(scene, &device, start, step_seconds, t_eval, Solver::Radau)
                            .map_err(|e| format!("{why}; {e}"))?;
                    out.switched = Some("DOP853 found the scene stiff; solved by Radau".into());
                    out
                }
                done => done?,
            }
        }
        Choice::ReferenceRadau => {
            reference(scene, &device, start, step_seconds, t_eval, Solver::Radau)?
        }
        Choice::ReferenceBdf => {
            reference(scene, &device, start, step_seconds, t_eval, Solver::Bdf)?
        }
        Choice::Core {
            method,
            single: true,
        } => core::<f32>(scene, method, start, step_seconds, steps)?,
        Choice::Core {
            method,
            single: false,
        } => core::<f64>(scene, method, start, step_seconds, steps)?,
    };
    if let (Some(times), Choice::Core { .. }) = (t_eval, choice) {
        outcome.evaluated = Some(between_steps(scene, &device, &outcome, step_seconds, times));
    }
    outcome.run_seconds = started.elapsed().as_secs_f64();
    outcome.step_seconds = step_seconds;
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
        first_limit_state: None,
        samples,
        velocities,
        stopped: None,
        run_seconds: 0.0,
        step_seconds: f64::NAN,
        solver: None,
        switched: None,
        evaluations: None,
        evaluated: None,
    }
}

/// The states at `times` on the quintic through a core method's step ends (its own states,
/// the model's acceleration at each), up to the last step it took.
fn between_steps(
    scene: &OpenLoop,
    device: &Device<f64>,
    out: &Outcome,
    step_seconds: f64,
    times: &[f64],
) -> Evaluated {
    let scale = device.rad_per_s_per_unit();
    let drive = Drive::from_volts(device, scene.bias_volts, scene.ac_volts, scene.drive_hz);
    let jet = |k: usize| {
        let state = State {
            stretch: out.samples[k],
            velocity: out.velocities[k] / scale,
        };
        Jet::of_model(device, &drive, k as f64 * step_seconds, state)
    };
    let last = out.samples.len().saturating_sub(1);
    let mut evaluated = Evaluated::default();
    for &t in times {
        if t > last as f64 * step_seconds * (1.0 + 1e-12) {
            break;
        }
        let (stretch, velocity) = if last == 0 {
            // No step taken: only t = 0 is reached.
            (out.samples[0], out.velocities[0])
        } else {
            let k = ((t / step_seconds).floor() as usize).min(last - 1);
            Hermite::new(jet(k), jet(k + 1)).at(t)
        };
        evaluated.times_seconds.push(t);
        evaluated.stretch.push(stretch);
        evaluated.velocity_per_second.push(velocity);
    }
    evaluated
}

/// The grid's times and the asked ones, merged without repeats (times within 1e-12 of each
/// other, relative, are one): the merged times, where each grid time is in it, where each
/// asked time is.
fn merge(grid: &[f64], asked: &[f64]) -> (Vec<f64>, Vec<usize>, Vec<usize>) {
    let mut merged: Vec<f64> = Vec::with_capacity(grid.len() + asked.len());
    let (mut at_grid, mut at_asked) = (Vec::with_capacity(grid.len()), Vec::new());
    let (mut i, mut j) = (0, 0);
    while i < grid.len() || j < asked.len() {
        let take_grid = j == asked.len() || (i < grid.len() && grid[i] <= asked[j]);
        let t = if take_grid { grid[i] } else { asked[j] };
        // A time a rounding from the last one is that one (an asked time one ulp off a grid
        // time would make an interval of nothing).
        if !merged
            .last()
            .is_some_and(|&last| t - last <= 1e-12 * last.abs().max(f64::MIN_POSITIVE))
        {
            merged.push(t);
        }
        if take_grid {
            at_grid.push(merged.len() - 1);
            i += 1;
        } else {
            at_asked.push(merged.len() - 1);
            j += 1;
        }
    }
    (merged, at_grid, at_asked)
}

fn core<T: Real>(
    scene: &OpenLoop,
    method: Method,
    [start, start_velocity]: [f64; 2],
    step_seconds: f64,
    steps: u64,
) -> Result<Outcome, RunError> {
    let params = scene.params.cast::<T>();
    let device = Device::new(params).map_err(|e| e.to_string())?;
    // The checks and the path between steps in f64, on the method's own states.
    let exact = Device::new(scene.params).map_err(|e| e.to_string())?;
    let range = exact.model_range();
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
            velocity: T::of(start_velocity),
        },
        false,
    )
    .map_err(|e| match e {
        StepError::Unstable { .. } => RunError::Refused(e.to_string()),
        _ => RunError::Failed(e.to_string()),
    })?;
    let mut stopped = None;
    // The crossing as the target's monitor sees it (its own checks, in T, at step ends); the
    // range is the path's true extremes, turns located on a quintic through the step ends.
    let mut monitor = Monitor::new();
    let mut extremes = Extremes::default();
    let scale = exact.rad_per_s_per_unit();
    let drive = Drive::from_volts(&exact, scene.bias_volts, scene.ac_volts, scene.drive_hz);
    let jet = |k: u64, s: State<T>| {
        let state = State {
            stretch: s.stretch.to_f64(),
            velocity: s.velocity.to_f64(),
        };
        Jet::of_model(&exact, &drive, k as f64 * step_seconds, state)
    };
    let mut samples = Vec::with_capacity(steps as usize + 1);
    let mut velocities = Vec::with_capacity(steps as usize + 1);
    samples.push(start);
    velocities.push(start_velocity * scale);
    monitor.observe(&device, 0, T::of(start), it.bias_dimless_squared());
    let mut last = it.state();
    for k in 1..=steps {
        if k % 4096 == 0 && crate::progress::stopped() {
            return Err(RunError::Failed(crate::progress::INTERRUPTED.into()));
        }
        if let Err(e) = it.step() {
            // Past the guarded range the model is no longer trusted: stop there and say why,
            // the samples so far kept (as SciPy's solvers return them when a step fails).
            stopped = Some(e.to_string());
            break;
        }
        let s = it.state();
        samples.push(s.stretch.to_f64());
        velocities.push(s.velocity.to_f64() * scale);
        monitor.observe(&device, k, s.stretch, it.bias_dimless_squared());
        if events::turns(last.velocity.to_f64(), s.velocity.to_f64()) {
            extremes.include(events::turn_stretch(jet(k - 1, last), jet(k, s)));
        }
        last = s;
    }
    let mut out = outcome(samples, velocities);
    out.stopped = stopped;
    out.min_stretch = out.min_stretch.min(extremes.min);
    out.max_stretch = out.max_stretch.max(extremes.max);
    let first = monitor.first_crossing();
    out.first_limit = first.map(|c| (c.mode, c.tick as f64 * step_seconds));
    // The state at the step the monitor first saw failing (the method's own samples).
    out.first_limit_state = first.and_then(|c| {
        let k = usize::try_from(c.tick).ok()?;
        Some((*out.samples.get(k)?, *out.velocities.get(k)?))
    });
    Ok(out)
}

/// The equation of motion for the reference integrator, dimensionless time.
pub struct Motion<'a> {
    pub device: &'a Device<f64>,
    pub drive: Drive<f64>,
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

    /// ∂(λ', λ'')/∂(λ, λ'): the local stiffness of model.md §5 and the damping, exact.
    fn jacobian(&self, tau: f64, y: &[f64; 2], j: &mut Matrix<f64>) {
        let p2 = self.drive.bias_dimless_squared_at(tau);
        j[(0, 0)] = 0.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -self.device.stiffness_dimless(y[0], p2);
        j[(1, 1)] = -self.device.damping_dimless();
    }
}

/// Relative and absolute tolerance of an adaptive solve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Tolerance {
    pub rtol: f64,
    pub atol: f64,
}

impl Tolerance {
    /// The same relative and absolute tolerance.
    pub fn both(tolerance: f64) -> Self {
        Self {
            rtol: tolerance,
            atol: tolerance,
        }
    }

    /// Both positive and finite, and not below what f64 can hold (1e-15).
    pub fn check(&self) -> Result<(), String> {
        for (name, value) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(value.is_finite() && (1e-15..1.0).contains(&value)) {
                return Err(format!("{name} = {value} must be in [1e-15, 1)"));
            }
        }
        Ok(())
    }
}

/// The sample times of one solve: τ_k = k·dτ, and the last at τ_end exactly.
fn sample_times(dtau: f64, tau_end: f64) -> Vec<f64> {
    // The grid's points before the end (a hair's float excess is not one more), then the end.
    let intervals = ((tau_end / dtau) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
    (0..intervals)
        .map(|k| k as f64 * dtau)
        .chain([tau_end])
        .collect()
}

/// DOP853's samples of one solve from its dense output between its own steps (Hairer's
/// 7th-order interpolant, as patched in host-sim/vendor/PATCH.md).
struct Samples<'a, const N: usize> {
    times: &'a [f64],
    ys: Vec<[f64; N]>,
    failed: Option<String>,
    on_step: Option<OnStep<'a, N>>,
}

/// What sees each step of a dense solve: its ends (time, state) and its path between them.
pub type OnStep<'a, const N: usize> =
    &'a mut dyn FnMut((f64, [f64; N]), (f64, [f64; N]), &mut dyn FnMut(f64) -> [f64; N]);

impl<const N: usize> Solout<f64, [f64; N]> for Samples<'_, N> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &[f64; N],
        y_prev: &[f64; N],
        interpolator: &mut I,
        _solution: &mut Solution<f64, [f64; N]>,
    ) -> ControlFlag<f64, [f64; N]>
    where
        I: Interpolation<f64, [f64; N]> + ?Sized,
    {
        if crate::progress::stopped() {
            self.failed = Some(crate::progress::INTERRUPTED.into());
            return ControlFlag::Terminate;
        }
        if let Some(hook) = self.on_step.as_mut().filter(|_| t_curr > t_prev) {
            let mut failed = None;
            let mut at = |t: f64| {
                interpolator.interpolate(t).unwrap_or_else(|e| {
                    failed = Some(format!("the reference's dense output failed: {e:?}"));
                    [f64::NAN; N]
                })
            };
            hook((t_prev, *y_prev), (t_curr, *y_curr), &mut at);
            if failed.is_some() {
                self.failed = failed;
                return ControlFlag::Terminate;
            }
        }
        while let Some(&tau) = self.times.get(self.ys.len()) {
            if tau > t_curr {
                break;
            }
            let y = if tau == t_curr {
                *y_curr
            } else if tau <= t_prev {
                *y_prev
            } else {
                match interpolator.interpolate(tau) {
                    Ok(y) => y,
                    Err(e) => {
                        self.failed = Some(format!("the reference's dense output failed: {e:?}"));
                        return ControlFlag::Terminate;
                    }
                }
            };
            self.ys.push(y);
        }
        ControlFlag::Continue
    }
}

/// Integrate `device` under `drive` from `y0` over dimensionless `[0, tau_end]` in one solve,
/// sampled every `dtau` and at `tau_end` exactly (the last sample).
pub fn solve(
    solver: Solver,
    device: &Device<f64>,
    drive: Drive<f64>,
    y0: [f64; 2],
    tau_end: f64,
    dtau: f64,
    tolerance: Tolerance,
) -> Result<Vec<[f64; 2]>, String> {
    if !(dtau.is_finite() && dtau > 0.0 && tau_end.is_finite() && tau_end > 0.0) {
        return Err(format!(
            "the output step {dtau} and the end {tau_end} must be positive"
        ));
    }
    let motion = Motion { device, drive };
    solver.sample(&motion, y0, &sample_times(dtau, tau_end), tolerance, None)
}

impl Solver {
    /// One solve of `ode` from `times[0]` with `y` there, sampled at `times` (increasing; the
    /// first sample is `y`). `on_step` sees each of DOP853's steps with its dense output (BDF
    /// has none to give: its caller walks the samples).
    pub fn sample<'a, const N: usize, F: ODE<f64, [f64; N]>>(
        self,
        ode: &F,
        y: [f64; N],
        times: &'a [f64],
        tolerance: Tolerance,
        on_step: Option<OnStep<'a, N>>,
    ) -> Result<Vec<[f64; N]>, String> {
        tolerance.check()?;
        let (&t0, &t1) = match (times.first(), times.last()) {
            (Some(t0), Some(t1)) if t1 > t0 => (t0, t1),
            _ => return Err("a solve needs an end after its start".into()),
        };
        let ys = match self {
            Solver::Dop853 | Solver::Radau => {
                let mut samples = Samples {
                    times,
                    ys: Vec::with_capacity(times.len()),
                    failed: None,
                    on_step,
                };
                let (end, _) = if self == Solver::Radau {
                    radau(ode, t0, t1, y, tolerance, 0.0, &mut samples)?
                } else {
                    dop853(ode, t0, t1, y, tolerance, 0.0, true, &mut samples)?
                };
                if let Some(why) = samples.failed {
                    return Err(why);
                }
                // The solver ends within a rounding of the end (its last step is cut to it).
                if samples.ys.len() + 1 == times.len() {
                    samples.ys.push(end);
                }
                samples.ys
            }
            Solver::Bdf => {
                let (later, _) = bdf(ode, y, times, tolerance, 0.0)?;
                std::iter::once(y).chain(later).collect()
            }
        };
        if ys.len() != times.len() {
            let why = format!("{} samples where {} were due", ys.len(), times.len());
            return Err(why);
        }
        Ok(ys)
    }

    /// Advance `y` of `ode` from `t0` to `t1`: the state at `t1` and the first step the solver
    /// took. `first_step`: the step to start with (a like solve's first step, so that a solve
    /// of the next tick does not estimate its step again, nor start too long after the
    /// drive's jump and have it rejected); `None` estimates it.
    pub fn advance<const N: usize, F: ODE<f64, [f64; N]>>(
        self,
        ode: &F,
        t0: f64,
        t1: f64,
        y: [f64; N],
        tolerance: Tolerance,
        first_step: Option<f64>,
    ) -> Result<([f64; N], f64), String> {
        let span = Span {
            from: t0,
            to: t1,
            short: false,
        };
        let start = erk::Start { y, rate: None };
        let end = self.advance_watched(ode, span, start, tolerance, first_step, &mut |_, _| {})?;
        Ok((end.y, end.first_step))
    }

    /// `advance` from `start` (its derivative, if known, saves the first stage), with
    /// `on_step` seeing the ends (time, state) of each of DOP853's steps (no dense output: a
    /// step's ends only), or of the whole interval with BDF.
    pub fn advance_watched<const N: usize, F: ODE<f64, [f64; N]>>(
        self,
        ode: &F,
        Span {
            from: t0,
            to: t1,
            short,
        }: Span,
        start: erk::Start<N>,
        tolerance: Tolerance,
        first_step: Option<f64>,
        on_step: &mut StepEnds<'_, N>,
    ) -> Result<Advanced<N>, String> {
        let y = start.y;
        tolerance.check()?;
        let h0 = first_step
            .filter(|h| h.is_finite() && *h > 0.0)
            .map_or(0.0, |h| h.min(t1 - t0));
        match self {
            Solver::Dop853 if h0 > 0.0 => {
                // A step known: the tick's own steps (`erk`), DOPRI5 over a short span.
                let mut first = None;
                let mut watch = |a: (f64, [f64; N]), b: (f64, [f64; N])| {
                    first.get_or_insert(b.0 - a.0);
                    on_step(a, b);
                };
                let Tolerance { rtol, atol } = tolerance;
                let (span, tolerance) = ((t0, t1), (rtol, atol));
                let solved = if short {
                    DOPRI5.solve(ode, span, start, tolerance, h0, &mut watch)
                } else {
                    DOP853.solve(ode, span, start, tolerance, h0, &mut watch)
                };
                let end = solved.map_err(|stop| match stop {
                    Stop::StepSize => STEP_SIZE_FELL.to_string(),
                    Stop::Stiff => STIFF.to_string(),
                })?;
                Ok(Advanced {
                    y: end.y,
                    first_step: first.map_or(end.next_step, |h| 1.25 * h),
                    rate: Some(end.rate),
                })
            }
            Solver::Dop853 => {
                // The first solve: the library's DOP853 estimates the first step.
                let mut first = FirstStep(None, on_step);
                let (end, next) = dop853(ode, t0, t1, y, tolerance, h0, false, &mut first)?;
                Ok(Advanced {
                    y: end,
                    first_step: first.0.map_or(next, |h| 1.25 * h),
                    rate: None,
                })
            }
            Solver::Radau => {
                let mut first = FirstStep(None, on_step);
                let (end, next) = radau(ode, t0, t1, y, tolerance, h0, &mut first)?;
                Ok(Advanced {
                    y: end,
                    first_step: first.0.map_or(next, |h| 1.25 * h),
                    rate: None,
                })
            }
            Solver::Bdf => {
                let (ys, h) = bdf(ode, y, &[t0, t1], tolerance, h0)?;
                let end = ys.last().copied().ok_or("no state returned")?;
                on_step((t0, y), (t1, end));
                Ok(Advanced {
                    y: end,
                    first_step: h,
                    rate: None,
                })
            }
        }
    }
}

/// An interval to solve over; `short`: a step long (the amplifier's ramp, tens of µs), where
/// DOP853's twelve stages buy nothing: DOPRI5's six (first same as last) at the same
/// tolerance.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    pub from: f64,
    pub to: f64,
    pub short: bool,
}

/// A solve's end ([`Solver::advance_watched`]): the state, the first step it took, and the
/// derivative there where the tick's own steps worked it out (the next solve's first stage).
#[derive(Clone, Copy, Debug)]
pub struct Advanced<const N: usize> {
    pub y: [f64; N],
    pub first_step: f64,
    pub rate: Option<[f64; N]>,
}

/// The first step a solve took; and what sees each step's ends.
struct FirstStep<'a, 'b, const N: usize>(Option<f64>, &'a mut StepEnds<'b, N>);

impl<const N: usize> Solout<f64, [f64; N]> for FirstStep<'_, '_, N> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &[f64; N],
        y_prev: &[f64; N],
        _: &mut I,
        _: &mut Solution<f64, [f64; N]>,
    ) -> ControlFlag<f64, [f64; N]>
    where
        I: Interpolation<f64, [f64; N]> + ?Sized,
    {
        if t_curr > t_prev {
            self.0.get_or_insert(t_curr - t_prev);
            (self.1)((t_prev, *y_prev), (t_curr, *y_curr));
        }
        ControlFlag::Continue
    }
}

/// How DOP853's refusal of a stiff problem begins (the reference switches on it).
pub const STIFF_FOR_DOP853: &str = "stiff for DOP853";

/// DOP853's refusal of a stiff problem.
const STIFF: &str = "stiff for DOP853 (Hairer's test): use Radau (`--method reference-radau`, \
                     or `solver = \"radau\"` in a scene's [plant])";

/// A solve whose step fell to nothing.
const STEP_SIZE_FELL: &str =
    "the step size fell to nothing (a singularity, or too tight a tolerance)";

/// DOP853 (differential-equations) from `t0` to `t1`, `solout` seeing every step: the state
/// at the end and the next step. `h0` 0 estimates the first step. `dense`: whether `solout`
/// interpolates (its three extra stages a step are left out otherwise: PATCH.md).
#[allow(clippy::too_many_arguments)]
fn dop853<const N: usize, F: ODE<f64, [f64; N]>, O: Solout<f64, [f64; N]>>(
    ode: &F,
    t0: f64,
    t1: f64,
    y: [f64; N],
    Tolerance { rtol, atol }: Tolerance,
    h0: f64,
    dense: bool,
    solout: &mut O,
) -> Result<([f64; N], f64), String> {
    let mut method = ExplicitRungeKutta::dop853()
        .rtol(rtol)
        .atol(atol)
        .h0(h0)
        .max_steps(usize::MAX);
    if !dense {
        method = method.without_dense_output();
    }
    solve_ode(&mut method, ode, t0, t1, &y, solout).map_err(stopped)?;
    Ok((*method.y(), method.h()))
}

/// Why a solve of the library's stopped, in words.
fn stopped<const N: usize>(e: SolveError<f64, [f64; N]>) -> String {
    match e {
        SolveError::StepSize { .. } => STEP_SIZE_FELL.to_string(),
        SolveError::Stiffness { .. } => STIFF.to_string(),
        SolveError::BadInput { msg } => msg,
        e => format!("the reference solver stopped: {e:?}"),
    }
}

/// Radau IIA 5 (differential-equations' RADAU5: three stages, simplified Newton on a
/// finite-difference Jacobian, Hairer's step control) from `t0` to `t1`, `solout` seeing every
/// step with its dense output (the collocation polynomial): the state at the end and the next
/// step. `h0` 0 estimates the first step.
fn radau<const N: usize, F: ODE<f64, [f64; N]>, O: Solout<f64, [f64; N]>>(
    ode: &F,
    t0: f64,
    t1: f64,
    y: [f64; N],
    Tolerance { rtol, atol }: Tolerance,
    h0: f64,
    solout: &mut O,
) -> Result<([f64; N], f64), String> {
    // RADAU5 controls its error at rtol' = 0.1·rtol^(2/3), atol' = atol·rtol'/rtol (Hairer's
    // code, and this one): the tolerances asked for are handed over so that rtol' and atol'
    // are them, down to its floor (rtol above 10 ulp: rtol' 1.6e-11). Newton's tolerance from
    // them, as RADAU5 sets FNEWT (0 asks for it; the library's fixed 3e-3 stops Newton short).
    // One per component: the crate transforms a scalar tolerance once per component (a
    // scalar indexes to itself), so a scalar of a state of N would be transformed N times.
    let handed = |rtol: f64| (10.0 * rtol).powf(1.5).max(RADAU_RTOL_FLOOR);
    let (inner_rtol, inner_atol) = (handed(rtol), atol * handed(rtol) / rtol);
    let mut method = ImplicitRungeKutta::radau5()
        .rtol([inner_rtol; N])
        .atol([inner_atol; N])
        .h0(h0)
        .newton_tol(0.0)
        .max_steps(usize::MAX);
    solve_ode(&mut method, ode, t0, t1, &y, solout).map_err(stopped)?;
    Ok((*method.y(), method.h()))
}

/// The least relative tolerance RADAU5 takes (more than 10 × its unit roundoff, 1e-16).
const RADAU_RTOL_FLOOR: f64 = 2e-15;

/// diffsol's BDF (variable order 1 to 5, as SciPy's `BDF` and MATLAB's ode15s) over `times`
/// (from `times[0]`, where the state is `y`): the states at `times[1..]` from its dense
/// output, and its next step. `h0` 0 lets it choose the first step.
///
/// The Jacobian–vector product Newton's iteration needs is a directional difference (one
/// right-hand side more): Newton converges with it; the error control does not use it.
/// differential-equations' own BDF (0.7.0) was not used: it takes no Newton step, and its
/// one solve of the reference scene ended 8e-3 off at rtol 1e-10 (BENCHMARKS.md).
#[cfg(feature = "bdf")]
fn bdf<const N: usize, F: ODE<f64, [f64; N]>>(
    ode: &F,
    y: [f64; N],
    times: &[f64],
    Tolerance { rtol, atol }: Tolerance,
    h0: f64,
) -> Result<(Vec<[f64; N]>, f64), String> {
    use diffsol::matrix::MatrixCommon;
    use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
    let rhs = |x: &[f64], t: f64, out: &mut [f64]| {
        let (mut state, mut rate) = ([0.0; N], [0.0; N]);
        state.copy_from_slice(x);
        ode.diff(t, &state, &mut rate);
        out.copy_from_slice(&rate);
    };
    let jacobian_times = |x: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
        let norm = |a: &[f64]| a.iter().map(|z| z * z).sum::<f64>().sqrt();
        let size = norm(v);
        if size == 0.0 {
            out.fill(0.0);
            return;
        }
        let eps = f64::EPSILON.sqrt() * (1.0 + norm(x)) / size;
        let (mut moved, mut at, mut there) = ([0.0; N], [0.0; N], [0.0; N]);
        for ((m, a), b) in moved.iter_mut().zip(x).zip(v) {
            *m = a + eps * b;
        }
        rhs(x, t, &mut at);
        rhs(&moved, t, &mut there);
        for ((o, a), b) in out.iter_mut().zip(at).zip(there) {
            *o = (b - a) / eps;
        }
    };
    let start = times[0];
    let mut builder = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(start)
        .rtol(rtol)
        .atol([atol]);
    if h0 > 0.0 {
        builder = builder.h0(h0);
    }
    let problem = builder
        .rhs_implicit(
            |x, _p, t, out| rhs(x, t, out),
            |x, _p, t, v, out| jacobian_times(x, t, v, out),
        )
        .init(move |_p, _t, out| out.copy_from_slice(&y), N)
        .build()
        .map_err(|e| format!("BDF: {e}"))?;
    let mut solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| format!("BDF: {e}"))?;
    let (dense, _) = solver
        .solve_dense(&times[1..])
        .map_err(|e| format!("BDF: {e}"))?;
    let ys = (0..dense.ncols())
        .map(|k| std::array::from_fn(|i| dense[(i, k)]))
        .collect();
    Ok((ys, solver.state().h))
}

/// Without the `bdf` feature: why not, and how to have it.
#[cfg(not(feature = "bdf"))]
fn bdf<const N: usize, F: ODE<f64, [f64; N]>>(
    _: &F,
    _: [f64; N],
    _: &[f64],
    _: Tolerance,
    _: f64,
) -> Result<(Vec<[f64; N]>, f64), String> {
    Err(BDF_NOT_BUILT.into())
}

/// What a BDF solve says in a build without the `bdf` feature.
pub const BDF_NOT_BUILT: &str = "BDF is not in this build (Radau, `reference-radau` or \
     `solver = \"radau\"`, is the stiff method in every build): build host-sim with \
     `--features bdf` (cargo run --release -p host-sim --features bdf -- ...)";

fn reference(
    scene: &OpenLoop,
    device: &Device<f64>,
    start: [f64; 2],
    step_seconds: f64,
    t_eval: Option<&[f64]>,
    solver: Solver,
) -> Result<Outcome, String> {
    let drive = Drive::from_volts(device, scene.bias_volts, scene.ac_volts, scene.drive_hz);
    let scale = device.rad_per_s_per_unit();
    let tolerance = scene.tolerance.unwrap_or(solver.default_tolerance());
    let grid = sample_times(step_seconds * scale, scene.duration_seconds * scale);
    // The asked times (SciPy's t_eval) among the grid's: one solve samples both.
    let asked: Vec<f64> = t_eval.unwrap_or(&[]).iter().map(|t| t * scale).collect();
    let (times, at_grid, at_asked) = merge(&grid, &asked);
    let motion = Motion { device, drive };
    let counted = Counted {
        ode: &motion,
        evaluations: Cell::new(0),
    };
    // The events on the solver's path, in dimensionless time.
    let mut watch = Watch::new(EVENT_RESOLUTION_SECONDS * scale);
    let fails =
        |tau: f64, y: &[f64; 2]| device.first_failure(y[0], drive.bias_dimless_squared_at(tau));
    let key = |y: &[f64; 2]| (y[0], y[1]);
    let ys = match solver {
        // DOP853's 7th-order dense output between its own steps; Radau's collocation
        // polynomial between its own.
        Solver::Dop853 | Solver::Radau => {
            let mut on_step = |a, b, at: &mut dyn FnMut(f64) -> [f64; 2]| {
                watch.step(a, b, at, key, fails);
            };
            solver.sample(&counted, start, &times, tolerance, Some(&mut on_step))?
        }
        // BDF gives samples only (its own dense output at the times asked): taken at
        // `BDF_EVENT_SUBDIVISION` times the output's rate, a quintic through them (value,
        // slope and the model's curvature at each), O((ωh)⁶) between them.
        Solver::Bdf => {
            let fine: Vec<f64> = times
                .windows(2)
                .flat_map(|w| {
                    (0..BDF_EVENT_SUBDIVISION).map(move |k| {
                        w[0] + (w[1] - w[0]) * k as f64 / BDF_EVENT_SUBDIVISION as f64
                    })
                })
                .chain(times.last().copied())
                .collect();
            let all = solver.sample(&counted, start, &fine, tolerance, None)?;
            let jet = |tau: f64, y: &[f64; 2]| {
                let mut rate = [0.0; 2];
                motion.diff(tau, y, &mut rate);
                Jet {
                    t: tau,
                    stretch: y[0],
                    velocity: y[1],
                    acceleration: rate[1],
                }
            };
            for (pair, tau) in all.windows(2).zip(fine.windows(2)) {
                let path = Hermite::new(jet(tau[0], &pair[0]), jet(tau[1], &pair[1]));
                let at = |t: f64| {
                    let (stretch, velocity) = path.at(t);
                    [stretch, velocity]
                };
                watch.step((tau[0], pair[0]), (tau[1], pair[1]), at, key, fails);
            }
            all.into_iter().step_by(BDF_EVENT_SUBDIVISION).collect()
        }
    };
    let mut out = outcome(
        at_grid.iter().map(|&k| ys[k][0]).collect(),
        at_grid.iter().map(|&k| ys[k][1] * scale).collect(),
    );
    out.evaluated = t_eval.map(|times| Evaluated {
        times_seconds: times.to_vec(),
        stretch: at_asked.iter().map(|&k| ys[k][0]).collect(),
        velocity_per_second: at_asked.iter().map(|&k| ys[k][1] * scale).collect(),
    });
    out.min_stretch = out.min_stretch.min(watch.extremes.min);
    out.max_stretch = out.max_stretch.max(watch.extremes.max);
    out.first_limit = watch.first.map(|(tau, mode, _)| (mode, tau / scale));
    out.first_limit_state = watch.first.map(|(_, _, y)| (y[0], y[1] * scale));
    out.solver = Some(solver);
    out.evaluations = Some(counted.evaluations.get());
    Ok(out)
}

/// An equation of motion that counts its right-hand sides (a solve's `nfev`).
struct Counted<'a, F> {
    ode: &'a F,
    evaluations: Cell<u64>,
}

impl<F: ODE<f64, [f64; 2]>> ODE<f64, [f64; 2]> for Counted<'_, F> {
    fn diff(&self, t: f64, y: &[f64; 2], dydt: &mut [f64; 2]) {
        self.evaluations.set(self.evaluations.get() + 1);
        self.ode.diff(t, y, dydt);
    }

    fn jacobian(&self, t: f64, y: &[f64; 2], j: &mut Matrix<f64>) {
        self.ode.jacobian(t, y, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use de_resonator::REFERENCE_DEVICE;

    /// Whether this build has the solver (BDF only with the `bdf` feature).
    fn built<T>((solver, ..): &(Solver, T, T)) -> bool {
        *solver != Solver::Bdf || cfg!(feature = "bdf")
    }

    /// Closed form first: at zero bias, small amplitude, the reference follows
    /// λ* + a·cos(ωt) with ω from model.md §5, to the level of the neglected nonlinearity.
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
            Tolerance::both(1e-13),
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
            solve(
                Solver::Dop853,
                &device,
                drive,
                y0,
                end,
                every,
                Tolerance::both(tol),
            )
            .unwrap()
        };
        let (a, b) = (run(1e-12), run(1e-13));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x[0] - y[0]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10, "{worst}");
    }

    /// The stiff methods (Radau IIA 5 in every build, BDF where built, each at 1e-10) against
    /// DOP853 at 1e-12 on a driven scene and on a light bar (ω 30 times the reference's): a
    /// second method agreeing to its tolerance.
    #[test]
    fn stiff_methods_agree_with_dop853() {
        stiff_agrees_with_dop853(Solver::Radau);
        if cfg!(feature = "bdf") {
            stiff_agrees_with_dop853(Solver::Bdf);
        }
    }

    fn stiff_agrees_with_dop853(solver: Solver) {
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
            let (own, dop853) = (solver.default_tolerance(), Tolerance::both(1e-12));
            let stiff = solve(solver, &device, drive, y0, end, every, own).unwrap();
            let accurate = solve(Solver::Dop853, &device, drive, y0, end, every, dop853).unwrap();
            let swing = accurate.iter().map(|y| y[0]).fold(0.0, f64::max)
                - accurate.iter().map(|y| y[0]).fold(f64::INFINITY, f64::min);
            assert!(swing > 1e-3, "the scene moves: {swing}");
            for (a, b) in stiff.iter().zip(&accurate) {
                // Radau's error control is the tolerance asked (1e-10); BDF's looser.
                let within = if solver == Solver::Radau { 1e-8 } else { 1e-6 };
                assert!(
                    (a[0] - b[0]).abs() < within * swing,
                    "{solver:?}: {} vs {}",
                    a[0],
                    b[0]
                );
            }
        }
    }

    /// The dense output (one solve, samples interpolated between its steps) against a second
    /// method with no interpolation at all: a solve restarted at every sample, whose samples
    /// are its step ends. At 1e-12 they agree to the tolerance's level; DOP853's interpolant
    /// as released (differential-equations 0.7.0, host-sim/vendor/PATCH.md) was 5.6e-8 off.
    #[test]
    fn dense_output_matches_step_ends() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let scale = device.rad_per_s_per_unit();
        let drive = Drive::from_volts(&device, 7000.0, 200.0, 30.0);
        let y0 = [device.stretch_for_bias(7000.0, 3.0).unwrap(), 0.0];
        // Samples at an awkward spacing, off the solver's steps.
        let (end, every) = (0.5 * scale, 0.5 / 731.0 * scale);
        let solvers = [
            (Solver::Dop853, 1e-12, 1e-10),
            (Solver::Radau, STIFF_REFERENCE_TOLERANCE, 1e-9),
            (Solver::Bdf, 1e-10, 1e-7),
        ];
        for (solver, tol, within) in solvers.into_iter().filter(built) {
            let tolerance = Tolerance::both(tol);
            let dense = solve(solver, &device, drive, y0, end, every, tolerance).unwrap();
            assert_eq!(dense.len(), 732);
            let motion = Motion {
                device: &device,
                drive,
            };
            let mut y = y0;
            let mut worst = 0.0f64;
            for (k, sample) in dense.iter().enumerate().skip(1) {
                let (t0, t1) = ((k - 1) as f64 * every, k as f64 * every);
                let t1 = if k == 731 { end } else { t1 };
                // The restarted solve at DOP853, 1e-13: the independent one.
                (y, _) = Solver::Dop853
                    .advance(&motion, t0, t1, y, Tolerance::both(1e-13), None)
                    .unwrap();
                worst = worst.max((sample[0] - y[0]).abs());
            }
            assert!(worst < within, "{solver:?}: {worst}");
        }
    }

    /// A plant tick's solve leaves out DOP853's dense-output stages (PATCH.md); its steps
    /// are the same, so it ends where the sampled solve ends, bit for bit.
    #[test]
    fn leaving_out_the_dense_stages_changes_no_step() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let drive = Drive::from_volts(&device, 7000.0, 200.0, 30.0);
        let motion = Motion {
            device: &device,
            drive,
        };
        let y0 = [device.stretch_for_bias(7000.0, 3.0).unwrap(), 0.0];
        let end = 0.3 * device.rad_per_s_per_unit();
        let tolerance = Tolerance::both(1e-12);
        let sampled = Solver::Dop853
            .sample(&motion, y0, &[0.0, end], tolerance, None)
            .unwrap();
        let (advanced, _) = Solver::Dop853
            .advance(&motion, 0.0, end, y0, tolerance, None)
            .unwrap();
        assert_eq!(sampled[1], advanced);
    }

    /// The last sample is at the duration asked for, exactly: a duration that is no whole
    /// number of steps ends at the same state as one solve straight to it.
    #[test]
    fn the_run_ends_at_the_duration() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let scene = OpenLoop {
            params: REFERENCE_DEVICE,
            bias_volts: 7000.0,
            ac_volts: 200.0,
            drive_hz: 30.0,
            duration_seconds: 0.5,
            start: Start::Equilibrium,
            y0: None,
            tolerance: None,
        };
        let step = 0.5 / 100.3;
        let scale = device.rad_per_s_per_unit();
        let drive = Drive::from_volts(&device, 7000.0, 200.0, 30.0);
        let motion = Motion {
            device: &device,
            drive,
        };
        let y0 = [device.stretch_for_bias(7000.0, 3.0).unwrap(), 0.0];
        let (straight, _) = Solver::Dop853
            .advance(&motion, 0.0, 0.5 * scale, y0, Tolerance::both(1e-13), None)
            .unwrap();
        for choice in [
            Choice::Reference,
            Choice::ReferenceRadau,
            Choice::ReferenceBdf,
        ] {
            if choice == Choice::ReferenceBdf && !cfg!(feature = "bdf") {
                continue;
            }
            let out = simulate(&scene, choice, step).unwrap();
            assert_eq!(out.samples.len(), 102, "{choice:?}");
            assert!((out.step_seconds * 101.0 - 0.5).abs() < 1e-15);
            let within = if choice == Choice::Reference {
                1e-10
            } else {
                1e-7
            };
            assert!(
                (out.final_stretch - straight[0]).abs() < within,
                "{choice:?}: {} vs {}",
                out.final_stretch,
                straight[0]
            );
        }
        // The core's fixed steps too: 1001 of them, the last ending at 0.5 s.
        let rk4 = Choice::Core {
            method: Method::Rk4,
            single: false,
        };
        let out = simulate(&scene, rk4, 0.5 / 1000.3).unwrap();
        assert_eq!(out.samples.len(), 1002);
        assert!((out.final_stretch - straight[0]).abs() < 1e-5);
    }

    /// The asked times merge into the grid: one entry for a time on it (or a rounding off
    /// it), each index pointing where its time went.
    #[test]
    fn asked_times_merge_into_the_grid_without_repeats() {
        let grid = [0.0, 0.1, 0.2, 0.30000000000000004];
        let near = f64::from_bits(0.2_f64.to_bits() + 1);
        let (merged, at_grid, at_asked) = merge(&grid, &[0.0, 0.05, near, 0.25, 0.25, 0.3]);
        assert_eq!(merged, [0.0, 0.05, 0.1, 0.2, 0.25, 0.3]);
        assert_eq!(at_grid, [0, 2, 3, 5]);
        assert_eq!(at_asked, [0, 1, 3, 4, 4, 5]);
    }

    /// `t_eval` and `y0` as SciPy means them, for every method: the states at the times asked
    /// (off the output grid, on it, at both ends) against one tight solve straight to each
    /// from the same start.
    #[test]
    fn t_eval_gives_the_states_at_the_times_asked_from_y0() {
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let y0 = [2.2, -1.5];
        let scene = OpenLoop {
            params: REFERENCE_DEVICE,
            bias_volts: 7000.0,
            ac_volts: 300.0,
            drive_hz: 30.0,
            duration_seconds: 0.2,
            start: Start::Equilibrium,
            y0: Some(y0),
            tolerance: None,
        };
        let scale = device.rad_per_s_per_unit();
        let motion = Motion {
            device: &device,
            drive: Drive::from_volts(&device, 7000.0, 300.0, 30.0),
        };
        let times = [0.0, 0.012_345, 0.1, 0.1, 0.177, 0.2];
        let exact: Vec<[f64; 2]> = times
            .iter()
            .map(|&t| {
                if t == 0.0 {
                    return y0;
                }
                let start = [y0[0], y0[1] / scale];
                let (y, _) = Solver::Dop853
                    .advance(&motion, 0.0, t * scale, start, Tolerance::both(1e-13), None)
                    .unwrap();
                [y[0], y[1] * scale]
            })
            .collect();
        let rk4 = Choice::Core {
            method: Method::Rk4,
            single: false,
        };
        for (choice, within) in [
            (Choice::Reference, 1e-9),
            (Choice::ReferenceRadau, 1e-6),
            (Choice::ReferenceBdf, 1e-6),
            (rk4, 1e-6),
        ] {
            if choice == Choice::ReferenceBdf && !cfg!(feature = "bdf") {
                continue;
            }
            let out = simulate_at(&scene, choice, 1e-4, Some(&times)).unwrap();
            let at = out.evaluated.expect("evaluated");
            assert_eq!(at.times_seconds, times);
            assert_eq!((out.samples[0], out.velocities[0]), (y0[0], y0[1]));
            for (k, e) in exact.iter().enumerate() {
                let (x, v) = (at.stretch[k], at.velocity_per_second[k]);
                assert!(
                    (x - e[0]).abs() < within,
                    "{choice:?} t {}: {x} vs {}",
                    times[k],
                    e[0]
                );
                assert!(
                    (v - e[1]).abs() < 1e3 * within,
                    "{choice:?} t {}: {v} vs {}",
                    times[k],
                    e[1]
                );
            }
        }
        // Out of the run, or out of order: refused.
        assert!(simulate_at(&scene, Choice::Reference, 1e-3, Some(&[0.3])).is_err());
        assert!(simulate_at(&scene, Choice::Reference, 1e-3, Some(&[0.1, 0.05])).is_err());
    }

    /// The equilibrium start on a Gent device with a low Jlim and a high pre-stretch, where a
    /// search to the scan's end meets Φ = NaN past B's lock-up: every bias from 0 V to the
    /// limit starts at a state that stays put (at rest, no AC: an equilibrium, checked by
    /// the dynamics, not by the search).
    #[test]
    fn the_equilibrium_start_holds_on_a_locking_gent_device() {
        let params = DeviceParams {
            jlim: Some(12.0),
            prestretch_1: 2.5,
            ..REFERENCE_DEVICE
        };
        let device = Device::new(params).unwrap();
        let limit = Limit::of(&device).at.volts;
        for k in 0..=10 {
            let bias_volts = limit * f64::from(k) / 10.0;
            let scene = OpenLoop {
                params,
                bias_volts,
                ac_volts: 0.0,
                drive_hz: 0.0,
                duration_seconds: 0.05,
                start: Start::Equilibrium,
                y0: None,
                tolerance: None,
            };
            let out = simulate(&scene, Choice::Reference, 1e-3).unwrap();
            let drift = out.max_stretch - out.min_stretch;
            assert!(drift < 1e-9, "{bias_volts} V: the start moved by {drift}");
            assert!(out.samples[0] > 2.5 || k == 0, "{bias_volts} V");
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
        assert!(names.contains(&"reference-radau") && names.len() == 9);
    }
}
