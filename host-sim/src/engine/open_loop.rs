//! Open-loop runs: a device under a fixed drive from a start state, for a duration, by a
//! core fixed-step method (f32 or f64, the code the firmware runs) or a reference solver
//! (`solver`: DOP853, Radau, BDF; f64), under the dynamic safety monitor, sampled on a grid or
//! at the times asked for. `host-sim simulate` (`cmd::simulate`) and the studies run on it.

use std::cell::Cell;
use std::time::Instant;

use crate::engine::events::{self, Extremes, Hermite, Jet, Watch};
use crate::engine::solver::{
    sample_times, Motion, Solver, Tolerance, EVENT_RESOLUTION_SECONDS, STIFF_FOR_DOP853,
};
use crate::text::sig;

use de_resonator::{
    Device, DeviceParams, Drive, FailureMode, Integrator, Limit, Method, Monitor, Real, State,
    StepError,
};
use differential_equations::prelude::*;

/// BDF's path between output samples is a quintic through its own samples at this many
/// times the output's rate: at the default 1/64 period, (ωh)⁶/46080 is then 1e-16 of the
/// swing.
const BDF_EVENT_SUBDIVISION: usize = 8;

/// The most samples a run keeps (two f64 each, and as many monitor checks): 16 M, 256 MB.
pub const MAX_SAMPLES: f64 = 16.0 * 1024.0 * 1024.0;

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
    /// DOP853 for Radau when it did, or solved at a tolerance other than the one asked.
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
    /// The tolerance `solver` solves this scene at: the one asked, else its default.
    pub fn tolerance_of(&self, solver: Solver) -> Tolerance {
        self.tolerance.unwrap_or(solver.default_tolerance())
    }

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
    // A tolerance tighter than the solver keeps is solved at its least: said, not silent.
    if let Some(solver) = outcome.solver {
        let asked = scene.tolerance_of(solver).rtol;
        if let Some(least) = solver.least_rtol().filter(|&least| asked < least) {
            let floor = format!(
                "{} keeps rtol {least:.2e} at least (RADAU5's floor): solved at it, not at \
                 {asked:e}",
                solver.name()
            );
            outcome.switched = Some(match outcome.switched.take() {
                Some(why) => format!("{why}; {floor}"),
                None => floor,
            });
        }
    }
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
    let tolerance = scene.tolerance_of(solver);
    let grid = sample_times(step_seconds * scale, scene.duration_seconds * scale);
    // The asked times (SciPy's t_eval) among the grid's: one solve samples both.
    // Without them the grid is the times (no copy: 29,411 samples of the reference scene are
    // a few hundred pages the process would fault in).
    let asked: Vec<f64> = t_eval.unwrap_or(&[]).iter().map(|t| t * scale).collect();
    let (merged, at_grid, at_asked) = if asked.is_empty() {
        (None, None, Vec::new())
    } else {
        let (merged, at_grid, at_asked) = merge(&grid, &asked);
        (Some(merged), Some(at_grid), at_asked)
    };
    let times: &[f64] = merged.as_deref().unwrap_or(&grid);
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
            solver.sample(&counted, start, times, tolerance, Some(&mut on_step))?
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
    let mut out = match &at_grid {
        Some(at_grid) => outcome(
            at_grid.iter().map(|&k| ys[k][0]).collect(),
            at_grid.iter().map(|&k| ys[k][1] * scale).collect(),
        ),
        None => outcome(
            ys.iter().map(|y| y[0]).collect(),
            ys.iter().map(|y| y[1] * scale).collect(),
        ),
    };
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

    /// Radau says where its tolerance stops: above the floor a tighter tolerance changes the
    /// answer and no note is given; below it two tolerances give the same answer, bit for
    /// bit, and the note names both. DOP853 has no floor to say.
    #[test]
    fn radau_says_when_its_tolerance_floor_is_what_ran() {
        let run = |choice, rtol: f64| {
            let scene = OpenLoop {
                params: REFERENCE_DEVICE,
                bias_volts: 7000.0,
                ac_volts: 200.0,
                drive_hz: 30.0,
                duration_seconds: 0.2,
                start: Start::Prestretch,
                y0: None,
                tolerance: Some(Tolerance::both(rtol)),
            };
            simulate(&scene, choice, 1e-3).unwrap()
        };
        let (loose, tight) = (
            run(Choice::ReferenceRadau, 1e-9),
            run(Choice::ReferenceRadau, 1e-10),
        );
        assert_ne!(loose.final_stretch, tight.final_stretch);
        assert_eq!((loose.switched, tight.switched), (None, None));
        let (below, further) = (
            run(Choice::ReferenceRadau, 1e-12),
            run(Choice::ReferenceRadau, 1e-13),
        );
        assert_eq!(below.final_stretch, further.final_stretch);
        for (out, asked) in [(&below, "1e-12"), (&further, "1e-13")] {
            let note = out.switched.as_deref().unwrap_or_default();
            assert!(note.contains("not at") && note.contains(asked), "{note}");
        }
        assert_eq!(run(Choice::Reference, 1e-13).switched, None);
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
