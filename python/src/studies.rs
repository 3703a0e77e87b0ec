//! The nonlinear studies from Python (docs/python.md): Poincaré sections, bifurcation
//! diagrams by continuation and the largest Lyapunov exponent, over host-sim's
//! `study::stroboscopic` and `study::lyapunov` (the CLI's `poincare`, `bifurcation` and
//! `lyapunov` run the same code); the safe drive map over `study::drive_map` (`drive-map`).

use host_sim::cmd::drive_map as drive_map_cmd;
use host_sim::cmd::DeviceSource;
use host_sim::engine::solver::Tolerance;
use host_sim::progress;
use host_sim::study::drive_map as map;
use host_sim::study::lyapunov as exponent;
use host_sim::study::stroboscopic::{
    self, Direction, Driven, Parameter, Point, Section, STUDY_TOLERANCE,
};
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::{numbers_of, stoppable, value_error, wrap, Device_};

/// The damping asked for: c in N·s, or the quality factor Q at the bias (not both).
#[derive(Clone, Copy)]
struct Damping {
    damping: Option<f64>,
    quality_factor: Option<f64>,
}

/// The drive on `device` (its damping replaced as asked), at `rtol` (atol the same).
fn driven(
    device: &Device_,
    bias_volts: f64,
    ac_volts: f64,
    ac_hz: f64,
    asked: Damping,
    rtol: Option<f64>,
) -> PyResult<Driven> {
    let mut params = device.params;
    if let Some(c) = asked.damping {
        params.damping = c;
    }
    let d = Driven {
        params,
        bias_volts,
        ac_volts,
        ac_hz,
        tolerance: Tolerance::both(rtol.unwrap_or(STUDY_TOLERANCE)),
    };
    d.device().map_err(value_error)?;
    match (asked.damping, asked.quality_factor) {
        (Some(_), Some(_)) => Err(value_error(
            "damping and quality_factor: give one (the damping, or Q at the bias)",
        )),
        (_, Some(q)) => d.with_quality(q).map_err(value_error),
        _ => Ok(d),
    }
}

/// Start states from `y0`: `None` (the rest state), a pair (stretch, dλ/dt in 1/s) or an
/// n × 2 array of them; whether it was many (the results then have a leading axis).
fn starts(
    y0: Option<&Bound<'_, PyAny>>,
    rest: impl Fn() -> PyResult<Point>,
) -> PyResult<(Vec<Point>, bool)> {
    let Some(y0) = y0 else {
        return Ok((vec![rest()?], false));
    };
    let (shape, values) = numbers_of("y0", y0)?;
    let many = match shape.as_slice() {
        [2] => false,
        [_, 2] => true,
        _ => {
            return Err(value_error(format!(
                "y0 of shape {shape:?}: a pair (stretch, velocity in 1/s) or an n × 2 array"
            )))
        }
    };
    let points = values
        .chunks(2)
        .map(|p| Point {
            stretch: p[0],
            velocity_per_second: p[1],
        })
        .collect();
    Ok((points, many))
}

/// A count given as an int ≥ `least`.
fn at_least(name: &str, value: i64, least: i64) -> PyResult<usize> {
    if value < least {
        return Err(value_error(format!(
            "{name} {value}: need at least {least}"
        )));
    }
    usize::try_from(value).map_err(value_error)
}

/// Sections as rows of `stretch` and `velocity` (NaN past a stopped run's last point), with
/// each run's first crossing and why it stopped, into `dict`.
fn put_sections(
    py: Python<'_>,
    dict: &Bound<'_, PyDict>,
    sections: &[Section],
    periods: usize,
    many: bool,
) -> PyResult<()> {
    let mut stretch = Array2::<f64>::from_elem((sections.len(), periods), f64::NAN);
    let mut velocity = stretch.clone();
    for (i, s) in sections.iter().enumerate() {
        for (k, p) in s.points.iter().enumerate() {
            stretch[(i, k)] = p.stretch;
            velocity[(i, k)] = p.velocity_per_second;
        }
    }
    let limits: Vec<Option<&str>> = sections
        .iter()
        .map(|s| s.first_limit.map(|(m, _)| m.name()))
        .collect();
    let times: Vec<f64> = sections
        .iter()
        .map(|s| s.first_limit.map_or(f64::NAN, |(_, t)| t))
        .collect();
    let stopped: Vec<Option<String>> = sections.iter().map(|s| s.stopped.clone()).collect();
    if many {
        dict.set_item("stretch", stretch.into_pyarray(py))?;
        dict.set_item("velocity", velocity.into_pyarray(py))?;
        dict.set_item("limit", PyList::new(py, limits)?)?;
        dict.set_item("limit_time_seconds", times.into_pyarray(py))?;
        dict.set_item("stopped", PyList::new(py, stopped)?)?;
    } else {
        dict.set_item("stretch", stretch.row(0).to_owned().into_pyarray(py))?;
        dict.set_item("velocity", velocity.row(0).to_owned().into_pyarray(py))?;
        dict.set_item("limit", limits[0])?;
        dict.set_item("limit_time_seconds", times[0])?;
        dict.set_item("stopped", stopped[0].clone())?;
    }
    Ok(())
}

/// A Poincaré section of the driven membrane (docs/python.md): `stretch` and `velocity`
/// (1/s) at t = k/ac_hz, k = transient_periods, …, transient_periods + periods − 1, the drive
/// Φ(t) = bias_volts + ac_volts·sin(2π·ac_hz·t); `t` those times. `y0`: the start (stretch,
/// dλ/dt in 1/s), or an n × 2 array of starts (rows of the results, computed on all cores);
/// default the rest state at the bias. `damping` (N·s) or `quality_factor` (Q at the bias)
/// over the device's damping. `limit`, `limit_time_seconds`: the first check of
/// docs/model.md §6 that failed along each run; `stopped`: why a run ended early.
#[pyfunction]
#[pyo3(signature = (device, bias_volts, ac_volts, ac_hz, *, periods = 200, transient_periods = 0, y0 = None, damping = None, quality_factor = None, rtol = None))]
#[allow(clippy::too_many_arguments)]
pub fn poincare<'py>(
    py: Python<'py>,
    device: &Device_,
    bias_volts: f64,
    ac_volts: f64,
    ac_hz: f64,
    periods: i64,
    transient_periods: i64,
    y0: Option<&Bound<'py, PyAny>>,
    damping: Option<f64>,
    quality_factor: Option<f64>,
    rtol: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let asked = Damping {
        damping,
        quality_factor,
    };
    let d = driven(device, bias_volts, ac_volts, ac_hz, asked, rtol)?;
    let (periods, transient) = (
        at_least("periods", periods, 1)?,
        at_least("transient_periods", transient_periods, 0)?,
    );
    let (points, many) = starts(y0, || d.rest().map_err(value_error))?;
    let work = points.len() as f64 * (transient as f64 + periods as f64);
    if work > stroboscopic::MAX_SECTION_POINTS {
        return Err(value_error(format!(
            "{work} drive periods in all: more than {}",
            stroboscopic::MAX_SECTION_POINTS
        )));
    }
    let sections = stoppable(py, || {
        let out = progress::map("poincare", &points, |&from| {
            stroboscopic::section(&d, from, transient, periods)
        });
        let out: Vec<Section> = out.into_iter().collect::<Result<_, _>>()?;
        if out
            .iter()
            .any(|s| s.stopped.as_deref() == Some(progress::INTERRUPTED))
        {
            return Err(progress::INTERRUPTED.to_string());
        }
        Ok(out)
    })?;
    let dict = PyDict::new(py);
    let t: Vec<f64> = (transient..transient + periods)
        .map(|k| k as f64 / ac_hz)
        .collect();
    dict.set_item("t", t.into_pyarray(py))?;
    put_sections(py, &dict, &sections, periods, many)?;
    wrap(py, dict.into_any())
}

/// A bifurcation diagram by continuation (docs/python.md): exactly one of `bias_volts`,
/// `ac_volts`, `ac_hz` is an increasing array, the parameter varied. Each walk (`direction`:
/// "up", "down" or "both", the two beside each other) starts from `y0` (default the rest
/// state at its first value's bias) and each next value from the previous one's last
/// section point. Returns `parameter` (the value of each row, in the order walked),
/// `direction` (each row's walk), `varied` (the parameter's name), and `stretch`, `velocity`
/// (rows × periods: the Poincaré points), `limit`, `limit_time_seconds`, `stopped` per row.
/// `damping` (N·s) or `quality_factor` (Q at the bias) over the device's damping.
#[pyfunction]
#[pyo3(signature = (device, bias_volts, ac_hz, ac_volts, *, periods = 50, transient_periods = 100, direction = "both", y0 = None, damping = None, quality_factor = None, rtol = None))]
#[allow(clippy::too_many_arguments)]
pub fn bifurcation<'py>(
    py: Python<'py>,
    device: &Device_,
    bias_volts: &Bound<'py, PyAny>,
    ac_hz: &Bound<'py, PyAny>,
    ac_volts: &Bound<'py, PyAny>,
    periods: i64,
    transient_periods: i64,
    direction: &str,
    y0: Option<&Bound<'py, PyAny>>,
    damping: Option<f64>,
    quality_factor: Option<f64>,
    rtol: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let (periods, transient) = (
        at_least("periods", periods, 1)?,
        at_least("transient_periods", transient_periods, 0)?,
    );
    let direction = match direction {
        "up" => Direction::Up,
        "down" => Direction::Down,
        "both" => Direction::Both,
        other => {
            return Err(value_error(format!(
                "direction `{other}`: `up`, `down` or `both`"
            )))
        }
    };
    let mut varied = None;
    let mut fixed = [0.0; 3];
    for (i, (name, parameter, given)) in [
        ("bias_volts", Parameter::BiasVolts, bias_volts),
        ("ac_volts", Parameter::AcVolts, ac_volts),
        ("ac_hz", Parameter::AcHz, ac_hz),
    ]
    .into_iter()
    .enumerate()
    {
        let (shape, values) = numbers_of(name, given)?;
        match shape.len() {
            0 => fixed[i] = values[0],
            1 if values.is_empty() => {
                return Err(value_error(format!(
                    "{name}: no values to vary (an empty array)"
                )))
            }
            1 if varied.is_none() => {
                fixed[i] = values.first().copied().unwrap_or(f64::NAN);
                varied = Some((parameter, values));
            }
            1 => {
                return Err(value_error(
                    "only one of bias_volts, ac_volts and ac_hz may be an array",
                ))
            }
            _ => return Err(value_error(format!("{name}: a number or a 1-D array"))),
        }
    }
    let Some((parameter, values)) = varied else {
        return Err(PyTypeError::new_err(
            "one of bias_volts, ac_volts and ac_hz must be an array: the values to vary",
        ));
    };
    let asked = Damping {
        damping,
        quality_factor,
    };
    let base = driven(device, fixed[0], fixed[1], fixed[2], asked, rtol)?;
    let from = match y0 {
        None => None,
        Some(y) => match starts(Some(y), || Err(value_error("no y0")))? {
            (p, false) => Some(p[0]),
            (_, true) => return Err(value_error("y0: one start (a pair) for a diagram")),
        },
    };
    let rows = stoppable(py, || {
        stroboscopic::bifurcation(
            &base, parameter, &values, direction, from, transient, periods,
        )
    })?;
    let dict = PyDict::new(py);
    dict.set_item("varied", parameter.name())?;
    let values: Vec<f64> = rows.iter().map(|r| r.value).collect();
    dict.set_item("parameter", values.into_pyarray(py))?;
    let walks: Vec<&str> = rows
        .iter()
        .map(|r| match r.direction {
            Direction::Down => "down",
            _ => "up",
        })
        .collect();
    dict.set_item("direction", PyList::new(py, walks)?)?;
    let sections: Vec<Section> = rows.into_iter().map(|r| r.section).collect();
    put_sections(py, &dict, &sections, periods, true)?;
    wrap(py, dict.into_any())
}

/// The largest Lyapunov exponent (docs/python.md), 1/s, from the variational equation along
/// the motion under Φ(t) = bias_volts + ac_volts·sin(2π·ac_hz·t) from `y0` (default the rest
/// state at the bias), renormalised once a drive period (without a drive, once a period of
/// the small oscillation at the start), over `periods` of them after `transient_periods`.
/// Returns `exponent`, its convergence (`t` s after the transient, `estimate` 1/s),
/// `interval_seconds`, `limit`, `limit_time_seconds` (the checks at the solver's steps),
/// `stopped`. `damping` (N·s) or `quality_factor` (Q at the bias) over the device's.
#[pyfunction]
#[pyo3(signature = (device, bias_volts, ac_volts = 0.0, ac_hz = 0.0, *, periods = 200, transient_periods = 20, y0 = None, damping = None, quality_factor = None, rtol = None))]
#[allow(clippy::too_many_arguments)]
pub fn lyapunov<'py>(
    py: Python<'py>,
    device: &Device_,
    bias_volts: f64,
    ac_volts: f64,
    ac_hz: f64,
    periods: i64,
    transient_periods: i64,
    y0: Option<&Bound<'py, PyAny>>,
    damping: Option<f64>,
    quality_factor: Option<f64>,
    rtol: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let asked = Damping {
        damping,
        quality_factor,
    };
    let d = driven(device, bias_volts, ac_volts, ac_hz, asked, rtol)?;
    let (periods, transient) = (
        at_least("periods", periods, 1)?,
        at_least("transient_periods", transient_periods, 0)?,
    );
    let from = match starts(y0, || d.rest().map_err(value_error))? {
        (p, false) => p[0],
        (_, true) => return Err(value_error("y0: one start (a pair) for an exponent")),
    };
    let out = stoppable(py, || {
        let out = exponent::lyapunov(&d, from, transient, periods)?;
        progress::interrupted([out.stopped.as_deref()])?;
        Ok(out)
    })?;
    let dict = PyDict::new(py);
    dict.set_item("exponent", out.per_second)?;
    let (t, estimate): (Vec<f64>, Vec<f64>) = out.convergence.iter().copied().unzip();
    dict.set_item("t", t.into_pyarray(py))?;
    dict.set_item("estimate", estimate.into_pyarray(py))?;
    dict.set_item("interval_seconds", out.interval_seconds)?;
    dict.set_item("limit", out.first_limit.map(|(m, _)| m.name()))?;
    dict.set_item(
        "limit_time_seconds",
        out.first_limit.map_or(f64::NAN, |(_, t)| t),
    )?;
    dict.set_item("stopped", out.stopped)?;
    wrap(py, dict.into_any())
}

/// The safe drive map (docs/python.md) at the bias a board tunes to for `target_hz` (default:
/// 44 Hz on the reference device) with `settings` (a settings file), the damping of
/// `quality_factor` at that bias if given: over `ac_volts` × `ac_hz` (1-D arrays), the full
/// simulation's `max_swing` (largest |λ − λ*|, from rest, the AC switched on at t = 0, for
/// `periods` of f0) and `safe` (inside docs/model.md §6), beside `accepted` (the board's own
/// boot checks of `start` with that `ac` pass) and `refusal` (its words), each an
/// len(ac_volts) × len(ac_hz) array; `limit` the first check each crossed, `stopped` why a
/// run ended early (it left the model's range: not safe); `bias_volts`, `stretch`,
/// `natural_frequency_hz`, `duration_seconds`, `damping` (N·s), `disagreements` (accepted
/// yet not safe: 0 when the two agree). `gain`: the amplifier's (full scale 2.5 V × gain), as `image`'s.
#[pyfunction]
#[pyo3(signature = (device = None, *, ac_volts, ac_hz, target_hz = None, periods = 200.0, quality_factor = None, settings = None, gain = 4000.0))]
#[allow(clippy::too_many_arguments)]
pub fn drive_map<'py>(
    py: Python<'py>,
    device: Option<&Device_>,
    ac_volts: &Bound<'py, PyAny>,
    ac_hz: &Bound<'py, PyAny>,
    target_hz: Option<f32>,
    periods: f64,
    quality_factor: Option<f64>,
    settings: Option<std::path::PathBuf>,
    gain: f32,
) -> PyResult<Bound<'py, PyAny>> {
    let grid = |name: &str, values: &Bound<'py, PyAny>| -> PyResult<Vec<f64>> {
        match numbers_of(name, values)? {
            (shape, v) if shape.len() == 1 => Ok(v),
            (shape, _) => Err(value_error(format!(
                "{name} of shape {shape:?}: a 1-D array"
            ))),
        }
    };
    let (amplitudes, frequencies) = (grid("ac_volts", ac_volts)?, grid("ac_hz", ac_hz)?);
    if amplitudes.len() * frequencies.len() > drive_map_cmd::MAX_CELLS {
        return Err(value_error(format!(
            "{} drives: at most {}",
            amplitudes.len() * frequencies.len(),
            drive_map_cmd::MAX_CELLS
        )));
    }
    let source = device.map_or(DeviceSource::Reference, Device_::as_source);
    let map = stoppable(py, || {
        let (image, batch, _) =
            drive_map_cmd::board_image(&source, target_hz, settings, quality_factor, gain)?;
        let map = map::drive_map(&image, batch.nominal, &amplitudes, &frequencies, periods)?;
        Ok((map, batch.nominal.damping))
    })?;
    let (map, damping) = map;
    let shape = (amplitudes.len(), frequencies.len());
    let column = |f: &dyn Fn(&map::Cell) -> f64| {
        Array2::from_shape_vec(shape, map.cells.iter().map(f).collect()).map_err(value_error)
    };
    let flags = |f: &dyn Fn(&map::Cell) -> bool| {
        Array2::from_shape_vec(shape, map.cells.iter().map(f).collect()).map_err(value_error)
    };
    let dict = PyDict::new(py);
    dict.set_item("ac_volts", amplitudes.into_pyarray(py))?;
    dict.set_item("ac_hz", frequencies.into_pyarray(py))?;
    dict.set_item("max_swing", column(&|c| c.max_swing)?.into_pyarray(py))?;
    dict.set_item("safe", flags(&map::Cell::safe)?.into_pyarray(py))?;
    dict.set_item(
        "accepted",
        flags(&|c| c.refused.is_none())?.into_pyarray(py),
    )?;
    let rows = |f: &dyn Fn(&map::Cell) -> Option<String>| -> PyResult<Bound<'py, PyList>> {
        let out: Vec<Vec<Option<String>>> = map
            .cells
            .chunks(shape.1.max(1))
            .map(|row| row.iter().map(f).collect())
            .collect();
        PyList::new(py, out)
    };
    dict.set_item("refusal", rows(&|c| c.refused.clone())?)?;
    dict.set_item(
        "limit",
        rows(&|c| c.first_limit.map(|(m, _)| m.name().to_string()))?,
    )?;
    dict.set_item("stopped", rows(&|c| c.stopped.clone())?)?;
    dict.set_item(
        "disagreements",
        map.cells.iter().filter(|c| c.disagrees()).count(),
    )?;
    dict.set_item("bias_volts", map.bias_volts)?;
    dict.set_item("stretch", map.stretch)?;
    dict.set_item("natural_frequency_hz", map.natural_frequency_hz)?;
    dict.set_item("duration_seconds", map.duration_seconds)?;
    dict.set_item("damping", damping)?;
    wrap(py, dict.into_any())
}
