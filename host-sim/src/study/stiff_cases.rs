//! `host-sim stress`: the stiff and extreme cases, each named, run with every core method in
//! f32 and f64 at several steps and compared with the reference. Every run must end either
//! stable, or unstable but detected (the guard refused the step, or the integration stopped
//! with a typed error); a run that completes with a final stretch further from the
//! reference's than the whole swing of the motion (at least 1e-4), or not finite, has failed
//! silently, which must never happen. A run that completes without the monitor seeing a
//! crossing the reference saw is `missed_crossing`: listed, and counted in the summary.

use de_resonator::{Device, DeviceParams, Tuner};
use serde::Serialize;

use crate::engine::open_loop::{simulate, Choice, OpenLoop, RunError, Start};

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
    /// Stiff: the reference is Radau IIA 5 (DOP853's step would be bound by stability).
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
pub const STEPS_PER_PERIOD: [f64; 5] = [2.0, 8.0, 32.0, 128.0, 512.0];

/// Simulated time, in periods of the small oscillation.
pub const PERIODS: f64 = 20.0;

/// What a run at one step came to.
#[derive(Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Completed, within the swing of the reference at the end, crossings seen as the
    /// reference saw them.
    Stable,
    /// Refused by the guard (the step is past the method's stability limit).
    Refused,
    /// Ended by a typed error.
    Stopped,
    /// Ended by a typed error after the monitor had flagged a crossing.
    StoppedAfterCrossing,
    /// Completed without the monitor seeing a crossing the reference saw.
    MissedCrossing,
    /// An error beyond the whole swing, or not finite: must never happen.
    FailedSilently,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Stable => "stable",
            Verdict::Refused => "refused",
            Verdict::Stopped => "stopped",
            Verdict::StoppedAfterCrossing => "stopped_after_crossing",
            Verdict::MissedCrossing => "missed_crossing",
            Verdict::FailedSilently => "failed_silently",
        }
    }
}

/// One method at one step.
#[derive(Serialize, Debug)]
pub struct RunReport {
    pub method: &'static str,
    pub steps_per_period: f64,
    pub verdict: Verdict,
    pub final_error_over_swing: Option<f64>,
    pub monitor_crossed: Option<bool>,
}

/// The reference a case is measured against.
#[derive(Serialize, Debug)]
pub struct ReferenceRun {
    pub method: &'static str,
    pub run_seconds: f64,
    pub min_stretch: f64,
    pub max_stretch: f64,
    pub first_limit: Option<crate::text::Crossing>,
}

/// One case and every run of it.
#[derive(Serialize, Debug)]
pub struct CaseReport {
    pub case: &'static str,
    pub what: &'static str,
    /// `null` when the case could not be built on the device.
    pub natural_frequency_hz: Option<f64>,
    pub bias_volts: Option<f64>,
    /// `null` when the case could not be built or its reference failed (`problem` says why).
    pub reference: Option<ReferenceRun>,
    pub runs: Vec<RunReport>,
    /// Why the case has no runs: it could not be built on this device, or its reference
    /// failed. The other cases still run; the command fails (exit status 1).
    pub problem: Option<String>,
}

/// How many runs came to each verdict.
#[derive(Serialize, Debug, Default)]
pub struct Summary {
    pub runs: usize,
    pub stable: usize,
    pub refused: usize,
    /// Stopped, with or without a crossing first.
    pub stopped: usize,
    pub missed_crossing: usize,
    pub failed_silently: usize,
    /// Cases with no runs (no reference): `problem` says why.
    pub cases_without_reference: usize,
}

/// Every case on `base`, in parallel, with a progress bar.
pub fn run(base: DeviceParams<f64>) -> (Vec<CaseReport>, Summary) {
    let cases = crate::progress::map("stress", &cases(base), |case| {
        run_case(case).unwrap_or_else(|problem| CaseReport {
            case: case.name,
            what: case.what,
            natural_frequency_hz: None,
            bias_volts: None,
            reference: None,
            runs: Vec::new(),
            problem: Some(problem),
        })
    });
    let mut summary = Summary {
        cases_without_reference: cases.iter().filter(|c| c.reference.is_none()).count(),
        ..Summary::default()
    };
    for run in cases.iter().flat_map(|c| &c.runs) {
        summary.runs += 1;
        match run.verdict {
            Verdict::Stable => summary.stable += 1,
            Verdict::Refused => summary.refused += 1,
            Verdict::Stopped | Verdict::StoppedAfterCrossing => summary.stopped += 1,
            Verdict::MissedCrossing => summary.missed_crossing += 1,
            Verdict::FailedSilently => summary.failed_silently += 1,
        }
    }
    (cases, summary)
}

/// One case: the reference, then every core method at every step.
fn run_case(case: &Case) -> Result<CaseReport, String> {
    let device = Device::new(case.params).map_err(|e| format!("not a valid device: {e}"))?;
    let tuner = Tuner::new(device);
    let limit = tuner.limit().at.volts;
    let bias = case.bias_of_limit * limit;
    let at_bias = device
        .stretch_for_bias(bias, tuner.limit().at.stretch)
        .ok_or("no equilibrium at the case's bias")?;
    let f0 = device.natural_frequency_hz(at_bias);
    let period = 1.0 / f0;
    let scene = OpenLoop {
        params: case.params,
        bias_volts: bias,
        ac_volts: case.ac_of_limit * limit,
        drive_hz: f0,
        duration_seconds: PERIODS * period,
        start: case.start,
        y0: None,
        tolerance: None,
    };
    let solver = if case.stiff {
        Choice::ReferenceRadau
    } else {
        Choice::Reference
    };
    let reference = simulate(&scene, solver, period / 64.0)
        .map_err(|e| format!("the reference ({}) failed: {e}", solver.name()))?;
    let swing = (reference.max_stretch - reference.min_stretch).max(1e-4);
    let mut runs = Vec::new();
    for choice in Choice::core() {
        for per_period in STEPS_PER_PERIOD {
            let (verdict, error, caught) = match simulate(&scene, choice, period / per_period) {
                Err(RunError::Refused(_)) => (Verdict::Refused, None, None),
                Err(RunError::Failed(_)) => (Verdict::Stopped, None, None),
                Ok(out) if out.stopped.is_some() && out.first_limit.is_none() => {
                    (Verdict::Stopped, None, None)
                }
                Ok(out) if out.stopped.is_some() => (
                    Verdict::StoppedAfterCrossing,
                    None,
                    Some(out.first_limit.is_some()),
                ),
                Ok(out) => {
                    let error = (out.final_stretch - reference.final_stretch).abs() / swing;
                    let fine = error.is_finite() && error <= 1.0;
                    let crossed = out.first_limit.is_some();
                    let verdict = if !fine {
                        Verdict::FailedSilently
                    } else if reference.first_limit.is_some() && !crossed {
                        Verdict::MissedCrossing
                    } else {
                        Verdict::Stable
                    };
                    (verdict, Some(error), Some(crossed))
                }
            };
            runs.push(RunReport {
                method: choice.name(),
                steps_per_period: per_period,
                verdict,
                final_error_over_swing: error,
                monitor_crossed: caught,
            });
        }
    }
    Ok(CaseReport {
        case: case.name,
        what: case.what,
        natural_frequency_hz: Some(f0),
        bias_volts: Some(bias),
        reference: Some(ReferenceRun {
            method: solver.name(),
            run_seconds: reference.run_seconds,
            min_stretch: reference.min_stretch,
            max_stretch: reference.max_stretch,
            first_limit: crate::text::Crossing::of(reference.first_limit),
        }),
        runs,
        problem: None,
    })
}
