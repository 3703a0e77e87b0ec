//! `simulate` from Python (docs/python.md, "Motion"): host-sim's open-loop run
//! (`engine::open_loop`, as `host-sim simulate` runs it) shaped like SciPy's OdeResult.

use host_sim::cmd::simulate::Asked;
use host_sim::engine::open_loop::{self as engine, Choice, Start};
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::{numbers_of, stoppable, value_error, wrap, Device_};

/// The motion from rest under Φ(t) = bias_volts + ac_volts·sin(2π·ac_hz·t) (V, Hz), watched
/// by the six checks of docs/model.md §6, as `host-sim simulate` runs it, for
/// `duration_seconds` (s). `method`: `reference` (adaptive DOP853, f64, rtol = atol = 1e-12,
/// stiff cases handed to Radau), `reference-radau`, or a core fixed-step method (`rk4`,
/// `verlet`, `implicit-midpoint`, each `-f32` as on the target or `-f64`); `step_seconds`:
/// the output spacing (default 1/64 of the period at 0 V); `start`: `equilibrium` (at rest
/// at the bias) or `prestretch` (the voltage switched on at t = 0); `damping` (N·s)
/// overrides the device's; `y0`: a start state of one's own (stretch, dλ/dt in 1/s) over
/// `start`; `t_eval`: the times (s, increasing, within the run) to give the state at, as
/// SciPy's (the reference's dense output; a core method's quintic through its step ends).
/// Returns a Result shaped like SciPy's OdeResult: `t` (s), `y`
/// (2 × n: stretch, dλ/dt in 1/s), `volts`, `status` (0: the end reached with no limit
/// crossed; 1: a limit crossed, its time in `t_events[0]`, the state in `y_events[0]`,
/// its mode in `message` and `limit`), `success`, `min_stretch`, `max_stretch` (over the
/// whole run), `nfev` (the adaptive solver's right-hand sides). With `stop_at_limit` (the
/// default) the samples end at the crossing, as at SciPy's terminal event (with `t_eval`,
/// the times before it); without, they run to the end.
#[pyfunction]
#[pyo3(signature = (device, bias_volts, *, duration_seconds, ac_volts = 0.0, ac_hz = None, method = "reference", rtol = None, atol = None, step_seconds = None, start = "equilibrium", damping = None, stop_at_limit = true, y0 = None, t_eval = None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    device: &Device_,
    bias_volts: f64,
    duration_seconds: f64,
    ac_volts: f64,
    ac_hz: Option<f64>,
    method: &str,
    rtol: Option<f64>,
    atol: Option<f64>,
    step_seconds: Option<f64>,
    start: &str,
    damping: Option<f64>,
    stop_at_limit: bool,
    y0: Option<&Bound<'py, PyAny>>,
    t_eval: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let y0 = match y0.map(|y| numbers_of("y0", y)).transpose()? {
        None => None,
        Some((shape, v)) if shape == [2] => Some([v[0], v[1]]),
        Some((shape, _)) => {
            return Err(value_error(format!(
                "y0 of shape {shape:?}: a pair (stretch, velocity in 1/s)"
            )))
        }
    };
    let t_eval = match t_eval.map(|t| numbers_of("t_eval", t)).transpose()? {
        None => None,
        Some((shape, v)) if shape.len() == 1 => Some(v),
        Some((shape, _)) => {
            return Err(value_error(format!(
                "t_eval of shape {shape:?}: a 1-D array of times"
            )))
        }
    };
    let choice = Choice::ALL
        .into_iter()
        .find(|c| c.name() == method)
        .ok_or_else(|| {
            let names: Vec<&str> = Choice::ALL.iter().map(Choice::name).collect();
            value_error(format!("method `{method}`: one of {}", names.join(", ")))
        })?;
    let start = match start {
        "equilibrium" => Start::Equilibrium,
        "prestretch" => Start::Prestretch,
        other => {
            return Err(value_error(format!(
                "start `{other}`: `equilibrium` or `prestretch`"
            )))
        }
    };
    let asked = Asked {
        bias_volts,
        ac_volts,
        ac_hz,
        damping,
        duration_seconds,
        start,
        y0,
        method: choice,
        step_seconds,
        rtol,
        atol,
    };
    let (scene, step) = asked
        .scene(device.params, &device.info())
        .map_err(value_error)?;
    let ac_hz = scene.drive_hz;
    let out = stoppable(py, || {
        engine::simulate_at(&scene, choice, step, t_eval.as_deref()).map_err(|e| e.to_string())
    })?;
    let (mut t, mut stretch, mut rate) = match &out.evaluated {
        Some(at) => (
            at.times_seconds.clone(),
            at.stretch.clone(),
            at.velocity_per_second.clone(),
        ),
        None => (
            (0..out.samples.len())
                .map(|k| k as f64 * out.step_seconds)
                .collect(),
            out.samples.clone(),
            out.velocities.clone(),
        ),
    };
    // Stopped at the first crossing, as SciPy's terminal event: the samples before it, then
    // the crossing itself (with `t_eval`, as SciPy: the times asked for before it only).
    if let (true, Some((_, at)), Some((x, v))) =
        (stop_at_limit, out.first_limit, out.first_limit_state)
    {
        let before = t.iter().take_while(|&&s| s < at).count();
        t.truncate(before);
        stretch.truncate(before);
        rate.truncate(before);
        if out.evaluated.is_none() {
            t.push(at);
            stretch.push(x);
            rate.push(v);
        }
    }
    let n = t.len();
    let volts: Vec<f64> = t
        .iter()
        .map(|&t| bias_volts + ac_volts * (std::f64::consts::TAU * ac_hz * t).sin())
        .collect();
    let mut y = Array2::<f64>::zeros((2, n));
    for k in 0..n {
        y[(0, k)] = stretch[k];
        y[(1, k)] = rate[k];
    }
    let dict = PyDict::new(py);
    dict.set_item("t", t.into_pyarray(py))?;
    dict.set_item("y", y.into_pyarray(py))?;
    dict.set_item("volts", volts.into_pyarray(py))?;
    let (status, message, t_events, y_events) = match (out.first_limit, out.first_limit_state) {
        (Some((mode, at)), state) => {
            let (stretch, rate) = state.unwrap_or((f64::NAN, f64::NAN));
            (
                1,
                format!(
                    "a limit was crossed: {} ({}) at t = {at} s",
                    mode.name(),
                    mode.description()
                ),
                vec![at],
                vec![stretch, rate],
            )
        }
        // A step left the range the method was checked for before any crossing: the
        // trajectory to there, failed, as SciPy's solvers say a failed step.
        (None, _) if out.stopped.is_some() => (
            -1,
            format!(
                "the method stopped: {}",
                out.stopped.as_deref().unwrap_or("")
            ),
            vec![],
            vec![],
        ),
        (None, _) => (
            0,
            "the end of the interval was reached; no limit crossed".to_string(),
            vec![],
            vec![],
        ),
    };
    let events = t_events.len();
    dict.set_item("status", status)?;
    dict.set_item("message", message)?;
    dict.set_item("success", status >= 0)?;
    dict.set_item("limit", out.first_limit.map(|(mode, _)| mode.name()))?;
    dict.set_item("t_events", PyList::new(py, [t_events.into_pyarray(py)])?)?;
    let y_events = Array2::from_shape_vec((events, 2), y_events).map_err(value_error)?;
    dict.set_item("y_events", PyList::new(py, [y_events.into_pyarray(py)])?)?;
    dict.set_item("min_stretch", out.min_stretch)?;
    dict.set_item("max_stretch", out.max_stretch)?;
    dict.set_item("method", choice.name())?;
    dict.set_item(
        "solver",
        out.solver.map(host_sim::engine::solver::Solver::name),
    )?;
    dict.set_item("solver_note", out.switched.clone())?;
    dict.set_item(
        "tolerance",
        out.solver.map(|s| {
            let t = scene.tolerance_of(s);
            (t.rtol, t.atol)
        }),
    )?;
    dict.set_item("nfev", out.evaluations)?;
    dict.set_item("step_seconds", out.step_seconds)?;
    dict.set_item("stopped", out.stopped.clone())?;
    dict.set_item("run_seconds", out.run_seconds)?;
    wrap(py, dict.into_any())
}
