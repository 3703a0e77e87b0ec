//! Exact events: `host-sim simulate --json` finds a crossing that comes and goes between two
//! output samples, with its time, mode and state, and the stretch's true extremes, against
//! an event-located solve written here: RK4 at 1 µs on the plain-SI restatement of
//! tests/common, its own §6.1–§6.2 checks by central differences, and every event located
//! by bisecting the length of one RK4 step from the last step before it.

#[path = "../../tests/common/mod.rs"]
mod model;

use std::process::Command;

use de_resonator::{DeviceParams, REFERENCE_DEVICE};
use serde_json::Value;

/// The first of model.md §6.1 (ω² > 0) and §6.2 (A's Hessian under the field positive
/// definite) that fails at stretch λ under `volts`: its name as host-sim writes it.
fn fails(p: &DeviceParams<f64>, l: f64, volts: f64) -> Option<&'static str> {
    // NaN fails too.
    if model::omega_squared_fd(p, l, volts).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Some("device_instability");
    }
    let l2 = p.prestretch_2;
    let e2 = model::permittivity(p) * (volts / p.thickness).powi(2);
    let h = 1e-6 * l;
    let d = |f: &dyn Fn(f64, f64) -> f64, (a, b): (f64, f64)| {
        (f(l + a * h, l2 + b * h) - f(l - a * h, l2 - b * h)) / (2.0 * h)
    };
    let s1 = |a: f64, b: f64| model::s1(p, a, b);
    let s2 = |a: f64, b: f64| model::s2(p, a, b);
    let h11 = d(&s1, (1.0, 0.0)) - e2 * l2 * l2;
    let h22 = d(&s2, (0.0, 1.0)) - e2 * l * l;
    let h12 = 0.5 * (d(&s1, (0.0, 1.0)) + d(&s2, (1.0, 0.0))) - 2.0 * e2 * l * l2;
    let definite = h11 > 0.0 && h11 * h22 - h12 * h12 > 0.0;
    (!definite).then_some("emi")
}

/// One classic RK4 step of λ'' = a(λ) at fixed voltage (plain SI, no damping).
fn rk4(p: &DeviceParams<f64>, volts: f64, (l, v): (f64, f64), h: f64) -> (f64, f64) {
    let a = |l: f64| model::acceleration(p, l, volts);
    let (k1l, k1v) = (v, a(l));
    let (k2l, k2v) = (v + 0.5 * h * k1v, a(l + 0.5 * h * k1l));
    let (k3l, k3v) = (v + 0.5 * h * k2v, a(l + 0.5 * h * k2l));
    let (k4l, k4v) = (v + h * k3v, a(l + h * k3l));
    (
        l + h / 6.0 * (k1l + 2.0 * k2l + 2.0 * k3l + k4l),
        v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
    )
}

/// The length of a step from `y` into `(0, h]` where `edge` first holds, bisected to 1e-14 s.
fn locate(
    p: &DeviceParams<f64>,
    volts: f64,
    y: (f64, f64),
    h: f64,
    edge: impl Fn((f64, f64)) -> bool,
) -> f64 {
    let (mut low, mut high) = (0.0, h);
    while high - low > 1e-14 {
        let mid = 0.5 * (low + high);
        if edge(rk4(p, volts, y, mid)) {
            high = mid;
        } else {
            low = mid;
        }
    }
    high
}

/// What the solve here finds from rest at the pre-stretch under `volts` switched on at 0.
struct Events {
    /// The first failure: time, mode, stretch, velocity; and when the trajectory is back.
    first: Option<(f64, &'static str, f64, f64)>,
    back_seconds: Option<f64>,
    min: f64,
    max: f64,
}

fn solve_here(p: &DeviceParams<f64>, volts: f64, seconds: f64) -> Events {
    let h = 1e-6;
    let steps = (seconds / h).round() as usize;
    let mut y = (p.prestretch_1, 0.0);
    let mut events = Events {
        first: None,
        back_seconds: None,
        min: y.0,
        max: y.0,
    };
    for k in 0..steps {
        let t = k as f64 * h;
        let next = rk4(p, volts, y, h);
        // A turn: the velocity's zero, located, and the stretch there.
        if (y.1 > 0.0) != (next.1 > 0.0) && y.1 != 0.0 {
            let rising = y.1 < 0.0;
            let s = locate(p, volts, y, h, |z| (z.1 > 0.0) == rising);
            let turn = rk4(p, volts, y, s).0;
            events.min = events.min.min(turn);
            events.max = events.max.max(turn);
        }
        match (events.first, fails(p, next.0, volts)) {
            (None, Some(mode)) => {
                let s = locate(p, volts, y, h, |z| fails(p, z.0, volts).is_some());
                let at = rk4(p, volts, y, s);
                events.first = Some((t + s, mode, at.0, at.1));
            }
            (Some(_), None) if events.back_seconds.is_none() => {
                let s = locate(p, volts, y, h, |z| fails(p, z.0, volts).is_none());
                events.back_seconds = Some(t + s);
            }
            _ => {}
        }
        events.min = events.min.min(next.0);
        events.max = events.max.max(next.0);
        y = next;
    }
    events
}

/// `simulate --json --method METHOD` on the step below, what the solve here finds on it, and
/// the output spacing.
fn crossing_run(method: &str) -> (Value, Events, f64) {
    let (volts, seconds, every) = (9360.0, 0.03, 0.005);
    let here = solve_here(&REFERENCE_DEVICE, volts, seconds);
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "simulate",
            "--start",
            "prestretch",
            "--ac-volts",
            "0",
            "--json",
        ])
        .args(["--method", method])
        .args(["--bias-volts", &volts.to_string()])
        .args(["--duration-seconds", &seconds.to_string()])
        .args(["--step-seconds", &every.to_string()])
        .output()
        .unwrap();
    // A run that crossed a limit exits with 1, its report complete.
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    (serde_json::from_slice(&out.stdout).unwrap(), here, every)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// A voltage step from rest whose overshoot enters the EMI region of §6.2 for about a
/// millisecond, between two output samples 5 ms apart: the samples alone see no crossing.
#[test]
fn a_crossing_between_samples_is_located_to_a_nanosecond() {
    let (report, here, every) = crossing_run("reference");
    let (t, mode, stretch, velocity) = here.first.expect("the scene crosses");
    let back = here.back_seconds.expect("and comes back");
    // The excursion lies between two samples: no sample sees it.
    assert_eq!((t / every).floor(), (back / every).floor(), "{t} .. {back}");
    assert!(back - t < every, "{t} .. {back}");
    let first = &report["first_limit"];
    assert_eq!(first["mode"], mode, "{report}");
    let (their_t, their_stretch) = (f(&first["time_seconds"]), f(&first["stretch"]));
    assert!(
        (their_t - t).abs() < 1e-9,
        "crossing at {their_t} s, here {t} s"
    );
    assert!(
        (their_stretch - stretch).abs() < 1e-9,
        "{their_stretch} vs {stretch}"
    );
    let their_velocity = f(&first["velocity_per_second"]);
    assert!(
        (their_velocity - velocity).abs() < 1e-6 * velocity.abs(),
        "{their_velocity}"
    );
    // The extremes: the peak inside the excursion, between samples, and the start.
    for (key, here) in [("max_stretch", here.max), ("min_stretch", here.min)] {
        let theirs = f(&report[key]);
        assert!((theirs - here).abs() < 1e-9, "{key}: {theirs} vs {here}");
    }
    assert_eq!(f(&report["steps"]), 6.0);
}

/// The stiff reference, Radau, finds the same crossing between its samples, through its
/// collocation polynomial between its steps: to its tolerance's level (1e-10 a step).
#[test]
fn radau_locates_the_crossing_between_samples_too() {
    stiff_locates_the_crossing("reference-radau");
}

/// BDF (the `bdf` feature) finds it too, through a quintic on its own samples eight times as
/// dense.
#[test]
#[cfg_attr(not(feature = "bdf"), ignore = "BDF: --features bdf")]
fn bdf_locates_the_crossing_between_samples_too() {
    stiff_locates_the_crossing("reference-bdf");
}

fn stiff_locates_the_crossing(method: &str) {
    let (report, here, _) = crossing_run(method);
    let (t, mode, stretch, _) = here.first.unwrap();
    let first = &report["first_limit"];
    assert_eq!(first["mode"], mode, "{report}");
    assert!(
        (f(&first["time_seconds"]) - t).abs() < 1e-8,
        "{first} vs {t}"
    );
    assert!((f(&first["stretch"]) - stretch).abs() < 1e-8, "{first}");
    assert!(
        (f(&report["max_stretch"]) - here.max).abs() < 1e-8,
        "{report}"
    );
}
