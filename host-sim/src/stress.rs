//! `host-sim stress`: the stiff and extreme cases, each named, run with every core method in
//! f32 and f64 at several steps and compared with the reference. Every run must end either
//! stable, or unstable but detected (the guard refused the step, or the integration stopped
//! with a typed error); a run that completes with a final stretch further from the
//! reference's than the whole swing of the motion (at least 1e-4), or not finite, has failed
//! silently, which must never happen. A run that completes without the monitor seeing a
//! crossing the reference saw is `missed_crossing`: listed, and counted in the summary.

use de_resonator::{Device, DeviceParams, Tuner};
use serde_json::{json, Value};

use crate::simulate::{simulate, Choice, RunError, Scene, Start};

/// A named extreme case: a device, a drive, and how it starts.
struct Case {
    name: &'static str,
    what: &'static str,
    params: DeviceParams<f64>,
    /// Bias as a fraction of the device's limit voltage.
    bias_of_limit: f64,
    /// AC amplitude as a fraction of the limit voltage, at the natural frequency.
    ac_of_limit: f64,
    start: Start,
    /// Stiff: the reference is BDF (DOP853's step would be bound by stability).
    stiff: bool,
}

/// The cases, built on `r` (the reference device unless another is given).
fn cases(r: DeviceParams<f64>) -> Vec<Case> {
    vec![
        Case {
            name: "near_emi_limit",
            what: "bias at 99.5% of the EMI limit, small resonant drive",
            params: r,
            bias_of_limit: 0.995,
            ac_of_limit: 0.002,
            start: Start::Equilibrium,
            stiff: false,
        },
        Case {
            name: "passive_near_slack",
            what: "long active membrane, passive one close to slack at 98% of its limit",
            params: DeviceParams {
                prestretch_1: 0.7,
                prestretch_2: 2.8,
                length_passive: 0.05,
                jlim: None,
                ..r
            },
            bias_of_limit: 0.98,
            ac_of_limit: 0.0,
            start: Start::Equilibrium,
            stiff: true,
        },
        Case {
            name: "gent_lock_up",
            what: "Jlim just above I1 of the pre-stretch, voltage step to 90% of the limit",
            params: DeviceParams {
                jlim: Some(8.3),
                ..r
            },
            bias_of_limit: 0.9,
            ac_of_limit: 0.0,
            start: Start::Prestretch,
            stiff: false,
        },
        Case {
            name: "light_bar",
            what: "massless bars and a 100x lighter membrane: high natural frequency",
            params: DeviceParams {
                bar_mass: 0.0,
                density: 9.6,
                ..r
            },
            bias_of_limit: 0.5,
            ac_of_limit: 0.05,
            start: Start::Equilibrium,
            stiff: true,
        },
        Case {
            name: "large_ac",
            what: "AC amplitude 45% of the limit on a 50% bias, at resonance",
            params: r,
            bias_of_limit: 0.5,
            ac_of_limit: 0.45,
            start: Start::Equilibrium,
            stiff: false,
        },
        Case {
            name: "fast_step",
            what: "voltage step from zero to 90% of the limit",
            params: r,
            bias_of_limit: 0.9,
            ac_of_limit: 0.0,
            start: Start::Prestretch,
            stiff: false,
        },
    ]
}

/// Steps per small-oscillation period tried for every method; 2 is past every explicit
/// method's stability limit.
const STEPS_PER_PERIOD: [f64; 5] = [2.0, 8.0, 32.0, 128.0, 512.0];

/// Simulated time, in periods of the small oscillation.
const PERIODS: f64 = 20.0;

/// Run every case on `base`; the report as JSON, and whether any run failed silently.
pub fn run(base: DeviceParams<f64>) -> Result<(Value, bool), String> {
    let results = crate::work::map("stress", &cases(base), run_case);
    let mut rows = Vec::new();
    let mut silent = false;
    for result in results {
        let (row, failed) = result?;
        rows.push(row);
        silent |= failed;
    }
    let count = |verdict: &str| {
        rows.iter()
            .flat_map(|case| case["runs"].as_array().cloned().unwrap_or_default())
            .filter(|run| run["verdict"] == verdict)
            .count()
    };
    let summary = json!({
        "runs": rows.len() * Choice::core().len() * STEPS_PER_PERIOD.len(),
        "stable": count("stable"),
        "refused": count("refused"),
        "stopped": count("stopped") + count("stopped_after_crossing"),
        "missed_crossing": count("missed_crossing"),
        "failed_silently": count("failed_silently"),
    });
    Ok((
        json!({ "periods": PERIODS, "summary": summary, "cases": rows }),
        silent,
    ))
}

/// One case: its JSON row, and whether any run failed silently.
fn run_case(case: &Case) -> Result<(Value, bool), String> {
    let mut silent = false;
    let device = Device::new(case.params).map_err(|e| format!("{}: {e}", case.name))?;
    let tuner = Tuner::new(device);
    let limit = tuner.limit().at.volts;
    let bias = case.bias_of_limit * limit;
    let at_bias = device
        .stretch_for_bias(bias, tuner.limit().at.stretch)
        .ok_or("bias above the limit")?;
    let f0 = device.natural_frequency_hz(at_bias);
    let period = 1.0 / f0;
    let scene = Scene {
        params: case.params,
        bias_volts: bias,
        ac_volts: case.ac_of_limit * limit,
        drive_hz: f0,
        duration_seconds: PERIODS * period,
        start: case.start,
    };
    let solver = if case.stiff {
        Choice::ReferenceBdf
    } else {
        Choice::Reference
    };
    let reference = simulate(&scene, solver, period / 64.0)
        .map_err(|e| format!("{}: reference: {e}", case.name))?;
    // A run has failed silently if its error exceeds the whole swing of the motion (and
    // 1e-4 in stretch, for scenes that barely move).
    let swing = (reference.max_stretch - reference.min_stretch).max(1e-4);
    let mut runs = Vec::new();
    for choice in Choice::core() {
        for per_period in STEPS_PER_PERIOD {
            let (verdict, error, caught) = match simulate(&scene, choice, period / per_period) {
                Err(RunError::Refused(_)) => ("refused", None, None),
                Err(RunError::Failed(_)) => ("stopped", None, None),
                Ok(out) if out.stopped.is_some() => (
                    "stopped_after_crossing",
                    None,
                    Some(out.first_limit.is_some()),
                ),
                Ok(out) => {
                    let error = (out.final_stretch - reference.final_stretch).abs() / swing;
                    let fine = error.is_finite() && error <= 1.0;
                    let crossed = out.first_limit.is_some();
                    let verdict = if !fine {
                        "failed_silently"
                    } else if reference.first_limit.is_some() && !crossed {
                        "missed_crossing"
                    } else {
                        "stable"
                    };
                    silent |= !fine;
                    (verdict, Some(error), Some(crossed))
                }
            };
            runs.push(json!({
                "method": choice.name(),
                "steps_per_period": per_period,
                "verdict": verdict,
                "final_error_over_swing": error,
                "monitor_crossed": caught,
            }));
        }
    }
    let row = json!({
        "case": case.name,
        "what": case.what,
        "natural_frequency_hz": f0,
        "bias_volts": bias,
        "reference": {
            "method": solver.name(),
            "run_seconds": reference.run_seconds,
            "min_stretch": reference.min_stretch,
            "max_stretch": reference.max_stretch,
            "first_limit": reference.first_limit.map(|(m, t)| json!({"mode": m.name(), "time": t})),
        },
        "runs": runs,
    });
    Ok((row, silent))
}

/// A short table for people: one line a case and method, verdicts by steps per period.
pub fn table(report: &Value) -> String {
    let mut out = String::from("case                 method                    ");
    for n in STEPS_PER_PERIOD {
        out += &format!("{:>24}", format!("{n}/period"));
    }
    out.push('\n');
    for case in report["cases"].as_array().into_iter().flatten() {
        let runs = case["runs"].as_array().cloned().unwrap_or_default();
        for chunk in runs.chunks(STEPS_PER_PERIOD.len()) {
            let method = chunk[0]["method"].as_str().unwrap_or("");
            out += &format!("{:<21}{:<26}", case["case"].as_str().unwrap_or(""), method);
            for run in chunk {
                let cell = match run["final_error_over_swing"].as_f64() {
                    Some(e) => format!("{} {e:.1e}", run["verdict"].as_str().unwrap_or("")),
                    None => run["verdict"].as_str().unwrap_or("").to_string(),
                };
                out += &format!("{cell:>24}");
            }
            out.push('\n');
        }
    }
    out += &format!("\nsummary: {}", report["summary"]);
    out
}
