//! The adaptive f64 solvers (DOP853, Radau IIA 5, BDF) over any equation of motion: one solve
//! sampled at given times from its dense output, or advanced over a span with each step seen;
//! the resonator's equation (`Motion`) and the tolerances. The open-loop runs
//! (`open_loop`), the plant, the closed loop and the studies run on them.

use crate::engine::erk::{self, StepEnds, Stop, DOP853, DOPRI5};

use de_resonator::{Device, Drive, State};
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

    /// The least relative tolerance this solver keeps (`None`: any `Tolerance::check`
    /// passes): Radau's is the one host-sim's transform (`radau`) turns into RADAU5's floor,
    /// about 1.6e-11; a tighter one is solved at it.
    pub fn least_rtol(self) -> Option<f64> {
        match self {
            Solver::Radau => Some(RADAU_RTOL_FLOOR.powf(2.0 / 3.0) / 10.0),
            Solver::Dop853 | Solver::Bdf => None,
        }
    }
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
pub(crate) fn sample_times(dtau: f64, tau_end: f64) -> Vec<f64> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use de_resonator::{DeviceParams, REFERENCE_DEVICE};

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
}
