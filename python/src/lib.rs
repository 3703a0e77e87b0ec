//! `de_resonator._native`: the core and host-sim's engines from Python, over numpy arrays.
//! No second implementation: every figure comes from the code the CLI and the firmware run
//! (the core's `Tuner` and `Device`, host-sim's `simulate`, `curve` and scenes); the
//! reports are the CLI's `--json` ones, as Python objects. The package around it
//! (`python/de_resonator`) adds the result type and the type stubs.

mod motion;
mod studies;

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use de_resonator::image::PowerUp;
use de_resonator::model::tolerance::{DeviceBox, Spread};
use de_resonator::{Device, DeviceParams, Field, Limit, Tuner, REFERENCE_DEVICE};
use host_sim::cmd::curve::{one_curve, Curve};
use host_sim::cmd::image::ImageSpec;
use host_sim::cmd::lut::LutFormat;
use host_sim::cmd::safe::{tune_batch, tune_in_batch, Guaranteed, Region, Tuned};
use host_sim::cmd::{sweep, DeviceInfo, DeviceSource};
use host_sim::{device_file, progress, scene};
use numpy::ndarray::ArrayD;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyError, PyOSError, PyPermissionError, PyRuntimeError, PyTypeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyList};
use serde::Serialize;

/// A value error with the core's (or host-sim's) message, in Python's words.
fn value_error(why: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(pythonic(&why.to_string()))
}

/// host-sim's words for its command line, as this package is called: a flag `--ac-hz` is
/// the keyword `ac_hz` (said once where the message gave both), and a build without BDF is
/// this package's, not a cargo command's.
fn pythonic(message: &str) -> String {
    if message == host_sim::engine::solver::BDF_NOT_BUILT {
        return "BDF is not in this package's build: method=\"reference-radau\" (Radau IIA 5) \
                is the stiff method in every build"
            .into();
    }
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(at) = rest.find("--") {
        let (before, from) = rest.split_at(at);
        let name: String = from[2..]
            .chars()
            .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '-')
            .collect();
        if name.is_empty() {
            out.push_str(&from[..2]);
            rest = &from[2..];
            continue;
        }
        let keyword = name.replace('-', "_");
        let after = &from[2 + name.len()..];
        // "ac_hz (--ac-hz)": the keyword was said already.
        let repeated = before.ends_with(&format!("{keyword} (")) && after.starts_with(')');
        if repeated {
            out.push_str(&before[..before.len() - 2]);
            rest = &after[1..];
        } else {
            out.push_str(before);
            out.push_str(&keyword);
            rest = after;
        }
    }
    out.push_str(rest);
    out
}

/// A file that cannot be read, as Python's own `open` says it: FileNotFoundError for a file
/// that is not there, PermissionError, else OSError; the path named.
fn read_error(path: &Path, e: &std::io::Error) -> PyErr {
    let why = format!("cannot read {}: {e}", path.display());
    match e.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(why),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(why),
        _ => PyOSError::new_err(why),
    }
}

/// `job` on a thread of its own with the GIL released, the caller's thread waiting for it and
/// for Ctrl-C: a `KeyboardInterrupt` raises the job's stop flag (`progress::stopped`, read by
/// the long loops) and is raised once the job has stopped. The job's error is a
/// `ValueError` with its message.
fn stoppable<R: Send>(
    py: Python<'_>,
    job: impl FnOnce() -> Result<R, String> + Send,
) -> PyResult<R> {
    let stop = Arc::new(AtomicBool::new(false));
    std::thread::scope(|scope| {
        let (done, mut finished) = mpsc::channel();
        let flag = stop.clone();
        let worker = scope.spawn(move || {
            let out = progress::stoppable(flag, job);
            let _ = done.send(());
            out
        });
        loop {
            let waiting = &mut finished;
            let ended = py.detach(move || {
                !matches!(
                    waiting.recv_timeout(Duration::from_millis(50)),
                    Err(mpsc::RecvTimeoutError::Timeout)
                )
            });
            if ended {
                break;
            }
            if let Err(interrupt) = py.check_signals() {
                stop.store(true, Ordering::Relaxed);
                let _ = py.detach(|| worker.join());
                return Err(interrupt);
            }
        }
        match worker.join() {
            Ok(out) => out.map_err(value_error),
            Err(_) => Err(PyRuntimeError::new_err("the computation panicked")),
        }
    })
}

/// A serde report as the package's `Result` (a dict whose keys are attributes too), through
/// JSON: the same keys and values as the CLI's `--json`.
fn result<'py>(py: Python<'py>, report: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(report).map_err(value_error)?;
    let dict = py.import("json")?.call_method1("loads", (text,))?;
    wrap(py, dict)
}

/// A dict as the package's `Result`.
fn wrap<'py>(py: Python<'py>, dict: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    py.import("de_resonator")?.getattr("Result")?.call1((dict,))
}

/// Numbers as an array of any shape, from anything numpy takes as an int or float dtype
/// (coerced to float64 and copied): its shape and values. Strings, bools and objects are
/// refused with a TypeError naming `name`, as `tune("43")` refuses a string.
fn numbers_of(name: &str, values: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let array = values
        .py()
        .import("numpy")?
        .call_method1("asarray", (values,))?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        return Err(PyTypeError::new_err(format!(
            "{name} must be numbers (an int or float dtype), not {} of dtype {dtype}",
            values.get_type().name()?
        )));
    }
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = array.extract()?;
    Ok((
        array.shape().to_vec(),
        array.as_array().iter().copied().collect(),
    ))
}

/// Numbers as an array of any shape (`numbers_of`), `f` applied to each with the GIL
/// released; a 0-d input gives a float.
fn map_array<'py>(
    py: Python<'py>,
    name: &str,
    values: &Bound<'py, PyAny>,
    f: impl Fn(f64) -> f64 + Send + Sync,
) -> PyResult<Bound<'py, PyAny>> {
    let (shape, input) = numbers_of(name, values)?;
    let out = stoppable(py, || progress::each(&input, |&x| f(x)))?;
    if shape.is_empty() {
        return Ok(out[0].into_pyobject(py)?.into_any());
    }
    let array = ArrayD::from_shape_vec(shape, out).map_err(value_error)?;
    Ok(array.into_pyarray(py).into_any())
}

/// A dielectric elastomer resonator (docs/model.md): a pre-stretched membrane with mass
/// bars. Keyword arguments are the device file's keys in SI units (shear_modulus Pa, jlim,
/// relative_permittivity, density kg/m³, breakdown_field V/m, thickness m, length_active m,
/// length_passive m, width m, bar_mass kg, prestretch_1, prestretch_2, damping N·s); an
/// absent key takes the reference device's value, an absent `jlim` makes it neo-Hookean.
/// A value the model refuses raises ValueError with the model's reason.
#[pyclass(name = "Device", module = "de_resonator", frozen, eq)]
#[derive(Clone)]
struct Device_ {
    params: DeviceParams<f64>,
    /// Where it came from: a file, `keywords`, or the reference device.
    source: String,
    /// The batch its tolerances declare (docs/model.md §10): the device alone without any.
    batch: DeviceBox,
}

/// Two devices are equal when their values and tolerances are (wherever they came from).
impl PartialEq for Device_ {
    fn eq(&self, other: &Self) -> bool {
        self.params == other.params && self.batch == other.batch
    }
}

impl Device_ {
    /// The device from checked parameters.
    fn new(params: DeviceParams<f64>, source: String) -> PyResult<Self> {
        Self::of_batch(DeviceBox::exact(params), source)
    }

    /// The device of a batch (its nominal device, the batch kept).
    fn of_batch(batch: DeviceBox, source: String) -> PyResult<Self> {
        let params = batch.nominal;
        Device::new(params).map_err(|e| value_error(format!("{source}: {e}")))?;
        Ok(Self {
            params,
            source,
            batch,
        })
    }

    fn device(&self) -> Device<f64> {
        // Checked when made.
        Device::new(self.params).expect("a checked device")
    }

    fn tuner(&self) -> Tuner<f64> {
        Tuner::new(self.device())
    }

    fn info(&self) -> DeviceInfo {
        DeviceInfo::new(self.source.clone(), &self.params).with_tolerance(&self.batch)
    }

    /// The device as host-sim's commands take it: its batch, named where it came from.
    fn as_source(&self) -> DeviceSource {
        DeviceSource::Given {
            batch: Box::new(self.batch),
            name: self.source.clone(),
        }
    }

    /// The margin checked: 0 ≤ margin < 1.
    fn margin(margin: f64) -> PyResult<f64> {
        if (0.0..1.0).contains(&margin) {
            Ok(margin)
        } else {
            Err(value_error(format!("margin {margin}: need 0 ≤ margin < 1")))
        }
    }
}

/// The device from keyword arguments: the device file's keys. `jlim=None` says neo-Hookean;
/// keywords without `jlim` make it neo-Hookean too, as a device file does, and say so (a
/// warning); `quiet` (a pickled device coming back) says nothing.
fn from_keys(keys: &Bound<'_, PyDict>, quiet: bool) -> PyResult<Device_> {
    let mut pairs = Vec::new();
    let mut jlim_given = false;
    let mut tolerance = None;
    for (key, value) in keys.iter() {
        let key: String = key.extract()?;
        if key == device_file::TOLERANCE {
            tolerance = Some(spreads_of(&value)?);
            continue;
        }
        if key == Field::Jlim.key() {
            jlim_given = true;
            if value.is_none() {
                continue;
            }
        }
        // A bool is an int to Python, but no device's value: `shear_modulus=True` is a
        // slip, not 1 Pa.
        let number: Option<f64> = if value.is_instance_of::<PyBool>() {
            None
        } else {
            value.extract().ok()
        };
        let number = number.ok_or_else(|| {
            PyTypeError::new_err(format!(
                "`{key}` must be a number (SI units), not {value:?}"
            ))
        })?;
        pairs.push((key, number));
    }
    let borrowed: Vec<(&str, f64)> = pairs.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    let (params, notes) = device_file::from_keys(&borrowed).map_err(value_error)?;
    let batch = match tolerance {
        Some(spreads) => device_file::with_tolerances(params, &spreads).map_err(value_error)?,
        None => DeviceBox::exact(params),
    };
    let device = Device_::of_batch(batch, "keywords".into())?;
    if !quiet {
        let mut said = notes.implausible;
        if !jlim_given {
            said.push(
                "no `jlim`: the material is neo-Hookean, as in a device file (give `jlim` for \
                 Gent, or `jlim=None` to say neo-Hookean)"
                    .into(),
            );
        }
        warn(keys.py(), &said)?;
    }
    Ok(device)
}

/// `tolerance={key: fraction or (low, high)}`: each key's spread, as a device file's
/// `[tolerance]` table gives it (a bool is no number here either).
fn spreads_of(value: &Bound<'_, PyAny>) -> PyResult<Vec<(String, Result<Spread, String>)>> {
    let dict = value.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(
            "`tolerance` is a dict: {key: fraction (0.1 for ±10%) or (low, high) in SI units}",
        )
    })?;
    let number = |v: &Bound<'_, PyAny>| -> Option<f64> {
        if v.is_instance_of::<PyBool>() {
            None
        } else {
            v.extract().ok()
        }
    };
    let mut out = Vec::new();
    for (key, v) in dict.iter() {
        let key: String = key.extract()?;
        let spread = if let Some(x) = number(&v) {
            Spread::Relative(x)
        } else {
            let ends: Option<(Bound<'_, PyAny>, Bound<'_, PyAny>)> = v.extract().ok();
            match ends.and_then(|(low, high)| Some((number(&low)?, number(&high)?))) {
                Some((low, high)) => Spread::Range { low, high },
                None => {
                    return Err(PyTypeError::new_err(format!(
                        "tolerance `{key}` must be a fraction or (low, high), not {v:?}"
                    )))
                }
            }
        };
        out.push((key, Ok(spread)));
    }
    Ok(out)
}

/// Each line a `UserWarning` (a value no real membrane has: a unit slip).
fn warn(py: Python<'_>, lines: &[String]) -> PyResult<()> {
    let warnings = py.import("warnings")?;
    for line in lines {
        warnings.call_method1("warn", (pythonic(line),))?;
    }
    Ok(())
}

#[pymethods]
impl Device_ {
    #[new]
    #[pyo3(signature = (**keys))]
    fn py_new(keys: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        match keys {
            Some(keys) if !keys.is_empty() => from_keys(keys, false),
            _ => Self::reference(),
        }
    }

    /// The reference device of docs/model.md §9 (built in).
    #[staticmethod]
    fn reference() -> PyResult<Self> {
        Self::new(REFERENCE_DEVICE, "reference device (built in)".into())
    }

    /// A device file (TOML, SI units, flat keys), as `host-sim --device FILE` reads it.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let text = std::fs::read_to_string(&path).map_err(|e| read_error(&path, &e))?;
        let source = path.display().to_string();
        let (batch, notes) = device_file::parse_box_noting(&text)
            .map_err(|e| value_error(format!("{source}: {e}")))?;
        let device = Self::of_batch(batch, source)?;
        warn(py, &notes.implausible)?;
        Ok(device)
    }

    /// A device file's text.
    #[staticmethod]
    fn from_toml(py: Python<'_>, text: &str) -> PyResult<Self> {
        let (batch, notes) = device_file::parse_box_noting(text).map_err(value_error)?;
        let device = Self::of_batch(batch, "toml".into())?;
        warn(py, &notes.implausible)?;
        Ok(device)
    }

    /// The device's keys and values (SI units): `Device(**d)` makes the same device.
    /// `jlim` is None for a neo-Hookean membrane.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for field in Field::ALL {
            match (field, self.params.jlim) {
                (Field::Jlim, None) => dict.set_item(field.key(), py.None())?,
                _ => dict.set_item(field.key(), self.params.get(field))?,
            }
        }
        if let Some(tolerance) = self.tolerance(py)? {
            dict.set_item(device_file::TOLERANCE, tolerance)?;
        }
        Ok(dict)
    }

    /// The tolerances as ranges, `{key: (low, high)}` in SI units (docs/model.md §10);
    /// None without any.
    #[getter]
    fn tolerance<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        if self.batch.is_exact() {
            return Ok(None);
        }
        let dict = PyDict::new(py);
        for f in self.batch.spread_fields() {
            dict.set_item(f.key(), (self.batch.low.get(f), self.batch.high.get(f)))?;
        }
        Ok(Some(dict))
    }

    /// `gent` or `neo_hookean` (docs/model.md §3).
    #[getter]
    fn material(&self) -> &'static str {
        self.info().material
    }

    /// Where the device came from: a file's path, `keywords`, `toml` or the reference.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// A device's value by its key (SI units): `device["thickness"]`.
    fn __getitem__(&self, key: &str) -> PyResult<f64> {
        let field = Field::from_key(key).ok_or_else(|| PyKeyError::new_err(key.to_string()))?;
        match (field, self.params.jlim) {
            (Field::Jlim, None) => Err(PyKeyError::new_err("jlim (neo-Hookean: no jlim)")),
            _ => Ok(self.params.get(field)),
        }
    }

    fn __repr__(&self) -> String {
        let material = match self.params.jlim {
            Some(_) => "Gent",
            None => "neo-Hookean",
        };
        let keys: Vec<String> = Field::ALL
            .iter()
            .map(|&f| match (f, self.params.jlim) {
                (Field::Jlim, None) => "jlim=None".to_string(),
                _ => format!("{}={:?}", f.key(), self.params.get(f)),
            })
            .collect();
        format!("Device({}) # {material}", keys.join(", "))
    }

    /// Pickled by its keys: worker processes (Dask, multiprocessing) get the same device.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let make = py
            .import("de_resonator._native")?
            .getattr("_device_from_keys")?;
        Ok((make, (self.to_dict(py)?,)))
    }

    /// The safe region (docs/model.md §§5–7): the limit first reached on the loading branch
    /// (mode, volts V, stretch, natural_frequency_hz Hz), the highest bias within `margin`
    /// (max_bias_volts V) and the tunable range (tunable_range_hz Hz): `host-sim safe --json`.
    #[pyo3(signature = (margin = 0.05))]
    fn safe<'py>(&self, py: Python<'py>, margin: f64) -> PyResult<Bound<'py, PyAny>> {
        let margin = Self::margin(margin)?;
        let region = Region::of_batch(self.info(), &self.tuner(), &self.batch, margin)
            .map_err(value_error)?;
        result(py, &region)
    }

    /// The smallest bias that tunes the natural frequency to `target_hz` (Hz) within `margin`
    /// of the limit: bias_volts V, stretch, natural_frequency_hz Hz, and the safe region
    /// (`host-sim tune --json`). A target out of reach raises ValueError with the range.
    #[pyo3(signature = (target_hz, margin = 0.05))]
    fn tune<'py>(
        &self,
        py: Python<'py>,
        target_hz: f64,
        margin: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let margin = Self::margin(margin)?;
        let report = tune_batch(self.info(), &self.tuner(), &self.batch, target_hz, margin)
            .map_err(value_error)?;
        result(py, &report)
    }

    /// The small-oscillation natural frequency (Hz) at a static bias (V) on the loading
    /// branch (docs/model.md §5), for a number or an array of any shape and numeric dtype;
    /// NaN where no equilibrium holds the bias (negative, or past the limit).
    fn frequency<'py>(
        &self,
        py: Python<'py>,
        bias_volts: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let device = self.device();
        let limit = Limit::of(&device);
        map_array(py, "bias_volts", bias_volts, |volts| {
            // On the loading branch from 0 V to the limit only: past it no equilibrium holds
            // (model.md §6), whatever stretch the branch's solve would find.
            match limit.stretch_for_bias(&device, volts) {
                Some(stretch) if volts >= 0.0 && volts <= limit.at.volts => {
                    device.natural_frequency_hz(stretch)
                }
                _ => f64::NAN,
            }
        })
    }

    /// `tune` for every target of an array (Hz, any numeric dtype), with the GIL released: a
    /// Result of arrays of the targets' shape, `bias_volts` (V), `stretch`,
    /// `natural_frequency_hz` (NaN where a target is out of reach), `ok` (bool) and
    /// `reason` (a list, None where tuned).
    #[pyo3(signature = (targets_hz, margin = 0.05))]
    fn tune_many<'py>(
        &self,
        py: Python<'py>,
        targets_hz: &Bound<'py, PyAny>,
        margin: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let margin = Self::margin(margin)?;
        let (shape, targets) = numbers_of("targets_hz", targets_hz)?;
        let tuner = self.tuner();
        // What holds for the batch, once for every target (docs/model.md §10).
        let guaranteed = Guaranteed::of(&self.batch, margin).map_err(value_error)?;
        let tuned = stoppable(py, || {
            progress::each(&targets, |&hz| {
                tune_in_batch(&tuner, &self.batch, guaranteed.as_ref(), hz, margin)
            })
        })?;
        let column = |f: &dyn Fn(&Tuned) -> f64| -> PyResult<_> {
            let values: Vec<f64> = tuned
                .iter()
                .map(|t| t.as_ref().map_or(f64::NAN, f))
                .collect();
            Ok(ArrayD::from_shape_vec(shape.clone(), values)
                .map_err(value_error)?
                .into_pyarray(py))
        };
        let ok: Vec<bool> = tuned.iter().map(Result::is_ok).collect();
        let reasons: Vec<Option<String>> =
            tuned.iter().map(|t| t.as_ref().err().cloned()).collect();
        let dict = PyDict::new(py);
        dict.set_item(
            "targets_hz",
            ArrayD::from_shape_vec(shape.clone(), targets)
                .map_err(value_error)?
                .into_pyarray(py),
        )?;
        dict.set_item("bias_volts", column(&|t| t.bias.volts)?)?;
        dict.set_item("stretch", column(&|t| t.bias.stretch)?)?;
        dict.set_item(
            "natural_frequency_hz",
            column(&|t| t.bias.natural_frequency_hz)?,
        )?;
        if guaranteed.is_some() {
            let end = |i: usize| move |t: &Tuned| t.band_hz.map_or(f64::NAN, |b| b[i]);
            dict.set_item("band_low_hz", column(&end(0))?)?;
            dict.set_item("band_high_hz", column(&end(1))?)?;
            let every: Vec<bool> = tuned
                .iter()
                .map(|t| {
                    t.as_ref()
                        .is_ok_and(|t| t.every_device_reaches == Some(true))
                })
                .collect();
            dict.set_item(
                "every_device_reaches",
                ArrayD::from_shape_vec(shape.clone(), every)
                    .map_err(value_error)?
                    .into_pyarray(py),
            )?;
        }
        dict.set_item(
            "ok",
            ArrayD::from_shape_vec(shape, ok)
                .map_err(value_error)?
                .into_pyarray(py),
        )?;
        dict.set_item("reason", PyList::new(py, reasons)?)?;
        dict.set_item("margin", margin)?;
        wrap(py, dict.into_any())
    }

    /// The tuning curve (`host-sim curve`): the loading branch from 0 V to the limit at
    /// `points` biases, as arrays ready for matplotlib (bias_volts V, natural_frequency_hz
    /// Hz, stretch, beyond_margin bool), with the limit, max_bias_volts and
    /// tunable_range_hz; `target_hz` marks the smallest bias for it.
    #[pyo3(signature = (points = 200, margin = 0.05, target_hz = None))]
    fn curve<'py>(
        &self,
        py: Python<'py>,
        points: i64,
        margin: f64,
        target_hz: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        curves(py, vec![self.params], points, margin, target_hz)?
            .into_iter()
            .next()
            .ok_or_else(|| PyRuntimeError::new_err("no curve"))
    }

    /// A family of curves over pre-stretches: one `curve` for each pair of `prestretch_1` ×
    /// `prestretch_2` (numbers or sequences); a pair that makes no valid device has no
    /// points and its `problem` says why.
    #[pyo3(signature = (prestretch_1 = None, prestretch_2 = None, points = 200, margin = 0.05, target_hz = None))]
    fn family<'py>(
        &self,
        py: Python<'py>,
        prestretch_1: Option<&Bound<'py, PyAny>>,
        prestretch_2: Option<&Bound<'py, PyAny>>,
        points: i64,
        margin: f64,
        target_hz: Option<f64>,
    ) -> PyResult<Bound<'py, PyList>> {
        let ones = numbers("prestretch_1", prestretch_1, self.params.prestretch_1)?;
        let twos = numbers("prestretch_2", prestretch_2, self.params.prestretch_2)?;
        let mut devices = Vec::new();
        for &l1 in &ones {
            for &l2 in &twos {
                let mut p = self.params;
                p.set(Field::Prestretch1, l1);
                p.set(Field::Prestretch2, l2);
                devices.push(p);
            }
        }
        PyList::new(py, curves(py, devices, points, margin, target_hz)?)
    }

    /// The tuning table the firmware flashes (`host-sim lut`): `points` (None: the fewest of
    /// 64 … 1024 that interpolate within 1e-5 in frequency) within `margin`. A Result with
    /// `data` (the table's bytes as flashed), `natural_frequency_hz` and `bias_volts` (float32
    /// arrays, the table's points) and `lut --json`'s keys; `out` writes it (a `.csv` name:
    /// the points as CSV, else the bytes).
    #[pyo3(signature = (points = None, margin = 0.05, out = None))]
    fn lut<'py>(
        &self,
        py: Python<'py>,
        points: Option<i64>,
        margin: f64,
        out: Option<std::path::PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let margin = Self::margin(margin)?;
        let points = points.map(|n| count("points", n, 1024)).transpose()?;
        let batch = self.batch;
        let made = stoppable(py, move || {
            host_sim::lut::make(&batch, margin, points, true).map_err(|e| e.to_string())
        })?;
        let csv = out
            .as_ref()
            .and_then(|p| p.extension())
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        let format = if csv { LutFormat::Csv } else { LutFormat::Bin };
        let mut files = Vec::new();
        if let Some(path) = &out {
            let bytes = host_sim::cmd::lut::file_bytes(&made, format).map_err(value_error)?;
            files.push(host_sim::cmd::write_path(path, &bytes).map_err(value_error)?);
        }
        let report = host_sim::cmd::lut::report(self.info(), &made, margin, format, files);
        let out = result(py, &report)?;
        out.set_item("data", PyBytes::new(py, &made.bytes))?;
        let hz: Vec<f32> = made.points.iter().map(|p| p.0).collect();
        let volts: Vec<f32> = made.points.iter().map(|p| p.1).collect();
        out.set_item("natural_frequency_hz", hz.into_pyarray(py))?;
        out.set_item("bias_volts", volts.into_pyarray(py))?;
        Ok(out)
    }

    /// The frequency response (`host-sim sweep`): the settled stretch amplitude at `points`
    /// drive frequencies from `from_ratio`·f0 to `to_ratio`·f0, with `ac_volts` (V) on
    /// `bias_volts` (V; defaults 0.2 and 0.6 of the limit's voltage), damped to
    /// `quality_factor` (0: the device's damping), each run `periods` periods of f0 by RK4 at
    /// `steps_per_period`. A Result with `sweep --json`'s keys and arrays `drive_hz` (Hz),
    /// `ratio`, `amplitude` (NaN where the run stopped), `crossed` (bool).
    #[pyo3(signature = (bias_volts = None, ac_volts = None, quality_factor = 200.0, from_ratio = 0.3, to_ratio = 2.4, points = 211, periods = 400.0, steps_per_period = 48.0))]
    #[allow(clippy::too_many_arguments)]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        bias_volts: Option<f64>,
        ac_volts: Option<f64>,
        quality_factor: f64,
        from_ratio: f64,
        to_ratio: f64,
        points: i64,
        periods: f64,
        steps_per_period: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = count("points", points, usize::MAX)?;
        let asked = sweep::Asked {
            bias_volts,
            ac_volts,
            quality_factor,
            from_ratio,
            to_ratio,
            points,
            periods,
            steps_per_period,
        };
        let (report, _) = stoppable(py, || sweep::measure(&asked, &self.as_source(), || Ok(())))?;
        let out = result(py, &report)?;
        let column = |f: &dyn Fn(&sweep::Point) -> f64| {
            report
                .points
                .iter()
                .map(f)
                .collect::<Vec<f64>>()
                .into_pyarray(py)
        };
        out.set_item("drive_hz", column(&|p| p.drive_hz))?;
        out.set_item("ratio", column(&|p| p.ratio))?;
        out.set_item("amplitude", column(&|p| p.amplitude.unwrap_or(f64::NAN)))?;
        let crossed: Vec<bool> = report
            .points
            .iter()
            .map(|p| p.first_limit_mode.is_some())
            .collect();
        out.set_item("crossed", crossed.into_pyarray(py))?;
        Ok(out)
    }
}

/// A number, a sequence or an array of numbers as a list, flattened (`numbers_of`; `None`:
/// the default alone).
fn numbers(name: &str, given: Option<&Bound<'_, PyAny>>, default: f64) -> PyResult<Vec<f64>> {
    match given {
        None => Ok(vec![default]),
        Some(values) => numbers_of(name, values).map(|(_, values)| values),
    }
}

/// A count from Python: within 2 ..= `most`, or a ValueError naming it.
fn count(name: &str, given: i64, most: usize) -> PyResult<usize> {
    usize::try_from(given)
        .ok()
        .filter(|n| (2..=most).contains(n))
        .ok_or_else(|| value_error(format!("{name} {given}: need 2 to {most}")))
}

/// The curves of `devices`, with the GIL released.
fn curves<'py>(
    py: Python<'py>,
    devices: Vec<DeviceParams<f64>>,
    points: i64,
    margin: f64,
    target_hz: Option<f64>,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let margin = Device_::margin(margin)?;
    let points = count("points", points, host_sim::cmd::curve::MAX_POINTS)?;
    if let Some(hz) = target_hz.filter(|hz| !(hz.is_finite() && *hz > 0.0)) {
        return Err(value_error(format!(
            "target_hz {hz}: need a finite frequency > 0"
        )));
    }
    let made: Vec<Curve> = stoppable(py, || {
        progress::each(&devices, |p| one_curve(*p, margin, target_hz, points))
    })?;
    made.iter()
        .map(|c| {
            let column = |f: &dyn Fn(&host_sim::cmd::curve::Point) -> f64| {
                c.points
                    .iter()
                    .map(f)
                    .collect::<Vec<f64>>()
                    .into_pyarray(py)
            };
            // `curve --json`'s keys, its points as arrays.
            let dict = result(py, c)?;
            dict.del_item("points")?;
            dict.set_item("bias_volts", column(&|p| p.bias_volts))?;
            dict.set_item("natural_frequency_hz", column(&|p| p.natural_frequency_hz))?;
            dict.set_item("stretch", column(&|p| p.stretch))?;
            let beyond: Vec<bool> = c.points.iter().map(|p| p.beyond_margin).collect();
            dict.set_item("beyond_margin", beyond.into_pyarray(py))?;
            Ok(dict)
        })
        .collect()
}

/// A scene (the path of a scene file, or its TOML text) run as `host-sim run` runs it: the
/// core's board ticking against the full plant. Returns the report (`run --json`'s keys)
/// with `history`: per tick `time_seconds` (s), `dac_code`, `dac_on`, `enable`, `phase`
/// (a list), `stretch`, `membrane_volts` (V), `current_amps` (A), as arrays. Writes no files.
#[pyfunction]
fn run_scene<'py>(py: Python<'py>, scene: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    // A path (str or os.PathLike) to a file, else a str of TOML (it holds `=` or a newline).
    let mut parsed = match scene.extract::<String>() {
        Ok(text) if !Path::new(&text).is_file() && (text.contains('\n') || text.contains('=')) => {
            scene::parse(&text).map_err(value_error)?
        }
        _ => {
            let path: std::path::PathBuf = scene.extract()?;
            if let Err(e) = std::fs::metadata(&path) {
                return Err(read_error(&path, &e));
            }
            scene::load(&path).map_err(value_error)?
        }
    };
    parsed.plot = false;
    parsed.history = false;
    parsed.run.history = true;
    let (parsed, run) = stoppable(py, move || {
        let run = parsed.run.run()?;
        Ok((parsed, run))
    })?;
    let report = host_sim::cmd::run::report(&parsed, &run, Vec::new());
    let out = result(py, &report)?;
    let history = PyDict::new(py);
    let h = &run.history;
    let column = |f: &dyn Fn(&host_sim::engine::closed_loop::Sample) -> f64| {
        h.iter().map(f).collect::<Vec<f64>>().into_pyarray(py)
    };
    history.set_item("time_seconds", column(&|s| s.seconds))?;
    history.set_item("stretch", column(&|s| s.stretch))?;
    history.set_item("membrane_volts", column(&|s| s.membrane_volts))?;
    history.set_item("current_amps", column(&|s| s.current_amps))?;
    history.set_item(
        "dac_code",
        h.iter()
            .map(|s| s.dac_code)
            .collect::<Vec<u16>>()
            .into_pyarray(py),
    )?;
    history.set_item(
        "dac_on",
        h.iter()
            .map(|s| s.dac_on)
            .collect::<Vec<bool>>()
            .into_pyarray(py),
    )?;
    history.set_item(
        "enable",
        h.iter()
            .map(|s| s.enable)
            .collect::<Vec<bool>>()
            .into_pyarray(py),
    )?;
    let phases: Vec<&str> = h
        .iter()
        .map(|s| s.phase.map_or("none", |p| p.name()))
        .collect();
    history.set_item("phase", PyList::new(py, phases)?)?;
    out.set_item("history", wrap(py, history.into_any())?)?;
    Ok(out)
}

/// A configuration image to flash (`host-sim image`): for `device` (None: the reference) with
/// `settings` (a settings file's path: the keys of a scene's [controller]), `target_hz` (Hz,
/// over the settings'), the amplifier (`dac_reference_volts` V, `gain` V/V, `rail_volts` V)
/// and `power_up` (`wait` for `start`, the default, or `drive`); or a scene's image (`scene`:
/// its path; it drives at power-up unless `power_up` is `wait`).
/// A Result with `data` (the bytes) and `image --check --json`'s keys (`bytes`: their
/// count); `out` writes them. An image
/// the firmware's boot would refuse raises ValueError saying why.
#[pyfunction]
#[pyo3(signature = (device = None, *, settings = None, target_hz = None, dac_reference_volts = 2.5, gain = 4000.0, rail_volts = None, power_up = None, scene = None, out = None))]
#[allow(clippy::too_many_arguments)]
fn image<'py>(
    py: Python<'py>,
    device: Option<&Device_>,
    settings: Option<std::path::PathBuf>,
    target_hz: Option<f32>,
    dac_reference_volts: f32,
    gain: f32,
    rail_volts: Option<f32>,
    power_up: Option<&str>,
    scene: Option<std::path::PathBuf>,
    out: Option<std::path::PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let power_up = match power_up {
        None => None,
        Some("wait") => Some(PowerUp::Wait),
        Some("drive") => Some(PowerUp::Drive),
        Some(other) => {
            return Err(value_error(format!(
                "power_up `{other}`: `wait` or `drive`"
            )))
        }
    };
    // A file named that is not there: said as Python's `open` says it.
    for path in settings.iter().chain(scene.iter()) {
        if let Err(e) = std::fs::metadata(path) {
            return Err(read_error(path, &e));
        }
    }
    let spec = ImageSpec {
        scene,
        device: device.map_or(DeviceSource::Reference, Device_::as_source),
        settings,
        target_hz,
        dac_reference_volts,
        gain,
        rail_volts,
        power_up,
    };
    if spec.scene.is_none() {
        warn(py, &host_sim::cmd::image::amplifier_warnings(&spec))?;
    }
    let name = out
        .as_ref()
        .map_or("(in memory)".into(), |p| p.display().to_string());
    let (bytes, report) = stoppable(py, || host_sim::cmd::image::build(&spec, name))?;
    warn(py, &host_sim::cmd::image::noise_warnings(&report))?;
    if let Some(path) = &out {
        host_sim::cmd::write_path(path, &bytes).map_err(value_error)?;
    }
    let dict = result(py, &report)?;
    dict.set_item("data", PyBytes::new(py, &bytes))?;
    Ok(dict)
}

/// What an image or a table holds and whether the firmware's boot accepts it (`host-sim
/// image --check`): from its bytes, or a file's path.
#[pyfunction]
fn check_image<'py>(py: Python<'py>, image: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let (bytes, name) = match image.cast::<PyBytes>() {
        Ok(bytes) => (bytes.as_bytes().to_vec(), "(bytes)".to_string()),
        Err(_) => {
            let path: std::path::PathBuf = image.extract()?;
            let bytes = std::fs::read(&path).map_err(|e| read_error(&path, &e))?;
            (bytes, path.display().to_string())
        }
    };
    let report = host_sim::cmd::image::describe(&bytes, name).map_err(value_error)?;
    result(py, &report)
}

/// Pickling's way back: the device from its keys (`Device.to_dict()`).
#[pyfunction]
fn _device_from_keys(keys: &Bound<'_, PyDict>) -> PyResult<Device_> {
    from_keys(keys, true)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Device_>()?;
    m.add_function(wrap_pyfunction!(motion::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(studies::poincare, m)?)?;
    m.add_function(wrap_pyfunction!(studies::bifurcation, m)?)?;
    m.add_function(wrap_pyfunction!(studies::lyapunov, m)?)?;
    m.add_function(wrap_pyfunction!(studies::drive_map, m)?)?;
    m.add_function(wrap_pyfunction!(image, m)?)?;
    m.add_function(wrap_pyfunction!(check_image, m)?)?;
    m.add_function(wrap_pyfunction!(_device_from_keys, m)?)?;
    Ok(())
}
