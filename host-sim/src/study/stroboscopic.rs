//! The driven membrane seen once a drive period (model.md §4, §7): Poincaré sections at the
//! drive's phase 0, Φ(t) = Φdc + Φac·sin(2π·f·t) at t = k/f, and bifurcation diagrams by
//! continuation, each parameter value starting from the previous one's end state. Solved by
//! the reference's DOP853 (Radau where DOP853 finds the motion stiff), the section points read
//! from its dense output, the checks of model.md §6 watched on the same path.

use de_resonator::{Device, DeviceParams, Drive, FailureMode, Limit};
use serde::Serialize;

use crate::engine::events::{Extremes, Watch};
use crate::engine::solver::{
    Motion, Solver, Tolerance, EVENT_RESOLUTION_SECONDS, STIFF_FOR_DOP853,
};
use crate::text::sig;

/// The studies' tolerance unless told: DOP853's, as SciPy's tests hold it (rtol = atol).
pub const STUDY_TOLERANCE: f64 = 1e-10;

/// The most section points a call computes (periods × initial conditions or values): about a
/// minute of work on two cores at ~20 µs a period.
pub const MAX_SECTION_POINTS: f64 = 1e7;

/// A state of the membrane: its stretch and dλ/dt, 1/s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Point {
    pub stretch: f64,
    pub velocity_per_second: f64,
}

/// A device under a fixed drive Φdc + Φac·sin(2π·f·t).
#[derive(Clone, Copy, Debug)]
pub struct Driven {
    /// The device, its damping as the study asks.
    pub params: DeviceParams<f64>,
    pub bias_volts: f64,
    pub ac_volts: f64,
    pub ac_hz: f64,
    pub tolerance: Tolerance,
}

impl Driven {
    /// The device, checked, and the drive's numbers finite (the frequency may be 0: no AC).
    pub fn device(&self) -> Result<Device<f64>, String> {
        for (what, value) in [
            ("bias_volts", self.bias_volts),
            ("ac_volts", self.ac_volts),
            ("ac_hz", self.ac_hz),
        ] {
            if !value.is_finite() {
                return Err(format!("{what} {value} must be a finite number"));
            }
        }
        if self.ac_hz < 0.0 {
            return Err(format!("ac_hz {} must be ≥ 0", sig(self.ac_hz)));
        }
        self.tolerance.check()?;
        Device::new(self.params).map_err(|e| e.to_string())
    }

    /// With the damping that gives the small oscillation at the bias's rest state the quality
    /// factor `q` (c = M·ω0/Q, model.md §4).
    pub fn with_quality(self, q: f64) -> Result<Driven, String> {
        if !(q.is_finite() && q > 0.0) {
            return Err(format!("quality factor {q}: need Q > 0"));
        }
        let natural_hz = self.device()?.natural_frequency_hz(self.rest()?.stretch);
        let mut out = self;
        out.params.damping = self.params.damping_for_quality(natural_hz, q);
        Ok(out)
    }

    /// The state at rest at the bias's equilibrium on the loading branch (the studies'
    /// default start).
    pub fn rest(&self) -> Result<Point, String> {
        let device = self.device()?;
        let stretch = Limit::of(&device)
            .stretch_for_bias(&device, self.bias_volts)
            .ok_or_else(|| {
                format!(
                    "no equilibrium holds {} V on the loading branch: give a start state (y0)",
                    sig(self.bias_volts)
                )
            })?;
        Ok(Point {
            stretch,
            velocity_per_second: 0.0,
        })
    }
}

/// One run's section: the state at t = k/f for k = transient, transient + 1, …
#[derive(Clone, Debug, Default)]
pub struct Section {
    pub points: Vec<Point>,
    /// The first check of model.md §6 that failed along the run (transient included), and
    /// when, s from the run's start.
    pub first_limit: Option<(FailureMode, f64)>,
    /// Why the run ended before its last point (the motion left the model's range, or the
    /// caller stopped it): the points so far are kept.
    pub stopped: Option<String>,
}

/// One run of `driven` from `from` at t = 0 to `end_seconds`, watched on the reference's
/// path: the states at `times_seconds` (increasing, within the run), the stretch's extremes
/// and the first check of model.md §6 that failed, kept when the solve stops early (`stopped`
/// says why).
#[derive(Clone, Debug)]
pub struct Watched {
    pub points: Vec<Point>,
    pub extremes: Extremes,
    pub first_limit: Option<(FailureMode, f64)>,
    pub stopped: Option<String>,
}

/// The run of [`Watched`], by DOP853, or by Radau where DOP853 finds the motion stiff.
pub fn watched(
    driven: &Driven,
    from: Point,
    times_seconds: &[f64],
    end_seconds: f64,
) -> Result<Watched, String> {
    let device = driven.device()?;
    for (what, value) in [
        ("the start's stretch", from.stretch),
        ("the start's velocity", from.velocity_per_second),
    ] {
        if !value.is_finite() {
            return Err(format!("{what} {value} must be a finite number"));
        }
    }
    if !(end_seconds.is_finite() && end_seconds > 0.0) {
        return Err(format!(
            "a run of {end_seconds} s: need a positive duration"
        ));
    }
    let scale = device.rad_per_s_per_unit();
    let drive = Drive::from_volts(&device, driven.bias_volts, driven.ac_volts, driven.ac_hz);
    let times: Vec<f64> = times_seconds.iter().map(|t| t * scale).collect();
    let end = end_seconds * scale;
    let y0 = [from.stretch, from.velocity_per_second / scale];
    let at_point = |y: [f64; 2]| Point {
        stretch: y[0],
        velocity_per_second: y[1] * scale,
    };
    let run = |solver: Solver| {
        let mut points = Vec::with_capacity(times.len());
        let mut watch = Watch::new(EVENT_RESOLUTION_SECONDS * scale);
        let fails =
            |tau: f64, y: &[f64; 2]| device.first_failure(y[0], drive.bias_dimless_squared_at(tau));
        while times.get(points.len()) == Some(&0.0) {
            points.push(at_point(y0));
        }
        let mut on_step =
            |a: (f64, [f64; 2]), b: (f64, [f64; 2]), at: &mut dyn FnMut(f64) -> [f64; 2]| {
                while let Some(&tau) = times.get(points.len()) {
                    if tau > b.0 {
                        break;
                    }
                    points.push(at_point(if tau == b.0 { b.1 } else { at(tau) }));
                }
                watch.step(a, b, at, |y| (y[0], y[1]), fails);
            };
        let solved = solver.sample(
            &Motion {
                device: &device,
                drive,
            },
            y0,
            &[0.0, end],
            driven.tolerance,
            Some(&mut on_step),
        );
        let stopped = match solved {
            Ok(ys) => {
                // The solver's end, where the dense output's last time fell a rounding past it.
                while points.len() < times.len() && times[points.len()] >= end {
                    points.extend(ys.last().map(|&y| at_point(y)));
                }
                None
            }
            Err(why) => Some(why),
        };
        Watched {
            points,
            extremes: watch.extremes,
            first_limit: watch.first.map(|(tau, mode, _)| (mode, tau / scale)),
            stopped,
        }
    };
    let out = run(Solver::Dop853);
    if out
        .stopped
        .as_deref()
        .is_some_and(|why| why.starts_with(STIFF_FOR_DOP853))
    {
        return Ok(run(Solver::Radau));
    }
    Ok(out)
}

/// `periods` section points of `driven` from `from` at t = 0, after `transient` periods.
pub fn section(
    driven: &Driven,
    from: Point,
    transient: usize,
    periods: usize,
) -> Result<Section, String> {
    if !(driven.ac_hz > 0.0) {
        return Err("a section needs a drive: ac_hz must be > 0".into());
    }
    if periods == 0 {
        return Err("periods must be at least 1".into());
    }
    if transient as f64 + periods as f64 > MAX_SECTION_POINTS {
        return Err(format!(
            "{} drive periods: more than {}",
            sig(transient as f64 + periods as f64),
            sig(MAX_SECTION_POINTS)
        ));
    }
    let period = 1.0 / driven.ac_hz;
    let times: Vec<f64> = (transient..transient + periods)
        .map(|k| k as f64 * period)
        .collect();
    let end = times[times.len() - 1].max(period);
    let Watched {
        points,
        first_limit,
        stopped,
        ..
    } = watched(driven, from, &times, end)?;
    let stopped = stopped.or_else(|| {
        (points.len() < periods).then(|| format!("{} of {periods} points", points.len()))
    });
    Ok(Section {
        points,
        first_limit,
        stopped,
    })
}

/// What a bifurcation diagram varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    AcVolts,
    AcHz,
    BiasVolts,
}

impl Parameter {
    pub fn name(self) -> &'static str {
        match self {
            Parameter::AcVolts => "ac_volts",
            Parameter::AcHz => "ac_hz",
            Parameter::BiasVolts => "bias_volts",
        }
    }

    /// `driven` with this parameter at `value`.
    pub fn set(self, driven: &Driven, value: f64) -> Driven {
        let mut d = *driven;
        match self {
            Parameter::AcVolts => d.ac_volts = value,
            Parameter::AcHz => d.ac_hz = value,
            Parameter::BiasVolts => d.bias_volts = value,
        }
        d
    }
}

/// Which way a continuation walks the values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// The values in the order given.
    Up,
    /// In the reverse order.
    Down,
    /// Both, each from its own start: hysteresis shows where the two differ.
    Both,
}

/// One value of a diagram: its section, started from the previous value's end state.
#[derive(Clone, Debug)]
pub struct Row {
    pub value: f64,
    /// `Up` or `Down`: the walk it belongs to.
    pub direction: Direction,
    pub section: Section,
}

/// A bifurcation diagram: `parameter` over `values` (increasing), walked as `direction` says.
/// Each walk starts from `from` at its first value (`None`: the rest state at that value's
/// bias), then each value from the last section point of the one before (a whole number of
/// drive periods: phase 0 again), so the branch a state is on is followed, jumps and all.
/// With `Both` the two walks run beside each other (each from its own start). A walk that
/// stops leaves the values after it with no points, saying why.
#[allow(clippy::too_many_arguments)]
pub fn bifurcation(
    base: &Driven,
    parameter: Parameter,
    values: &[f64],
    direction: Direction,
    from: Option<Point>,
    transient: usize,
    periods: usize,
) -> Result<Vec<Row>, String> {
    if values.is_empty() {
        return Err(format!("no values of {} to vary", parameter.name()));
    }
    if !values.windows(2).all(|w| w[0] < w[1]) {
        return Err(format!(
            "the values of {} must increase (to walk them down, ask for the direction `down`)",
            parameter.name()
        ));
    }
    for &v in values {
        parameter.set(base, v).device()?;
        if parameter == Parameter::AcHz && !(v > 0.0) {
            return Err(format!("ac_hz {} must be > 0", sig(v)));
        }
    }
    if parameter != Parameter::AcHz && !(base.ac_hz > 0.0) {
        return Err("a section needs a drive: ac_hz must be > 0".into());
    }
    if periods == 0 {
        return Err("periods must be at least 1".into());
    }
    let walks: Vec<Direction> = match direction {
        Direction::Both => vec![Direction::Up, Direction::Down],
        one => vec![one],
    };
    let total = (walks.len() * values.len()) as f64 * (transient as f64 + periods as f64);
    if total > MAX_SECTION_POINTS {
        return Err(format!(
            "{} drive periods in all, more than {}: fewer values, periods or transient periods",
            sig(total),
            sig(MAX_SECTION_POINTS)
        ));
    }
    let start = |value: f64| match from {
        Some(p) => Ok(p),
        None => parameter.set(base, value).rest(),
    };
    let firsts: Vec<(Direction, Point)> = walks
        .iter()
        .map(|&d| {
            let first = if d == Direction::Up {
                values[0]
            } else {
                values[values.len() - 1]
            };
            start(first).map(|p| (d, p))
        })
        .collect::<Result<_, _>>()?;
    let walked = crate::progress::map_units(
        "bifurcation",
        &firsts,
        firsts.len() * values.len(),
        |&(direction, first), tick| -> Result<Vec<Row>, String> {
            let order: Vec<f64> = match direction {
                Direction::Down => values.iter().rev().copied().collect(),
                _ => values.to_vec(),
            };
            let mut state = Some(first);
            let mut rows = Vec::with_capacity(order.len());
            for value in order {
                let section = match state {
                    Some(from) => section(&parameter.set(base, value), from, transient, periods)?,
                    None => Section {
                        stopped: Some("the walk stopped at a value before".into()),
                        ..Section::default()
                    },
                };
                state = match (&section.stopped, section.points.last()) {
                    (None, Some(&p)) => Some(p),
                    _ => None,
                };
                crate::progress::interrupted([section.stopped.as_deref()])?;
                rows.push(Row {
                    value,
                    direction,
                    section,
                });
                tick();
            }
            Ok(rows)
        },
    );
    let mut rows = Vec::new();
    for walk in walked {
        rows.extend(walk?);
    }
    Ok(rows)
}
