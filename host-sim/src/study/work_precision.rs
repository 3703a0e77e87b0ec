//! `host-sim report`: error against run time (a work-precision study) of every core
//! fixed-step method in f32 and f64, against the reference, on named scenes.
//!
//! Each scene runs 40 periods of its base frequency. A method runs at 8 to 512 steps a
//! period; the reference (DOP853 at 1e-12) samples every 1/512 period. Errors: the final
//! stretch's relative error, the largest stretch error on a grid of 8 points a period, and
//! the phase error, the shift of the last upward crossing of the mean stretch times 2π·f.
//! Run time: the whole `simulate` call (steps, monitor, samples), the fastest of repeats
//! adding up to at least 20 ms, per simulated second.

use std::time::Instant;

use de_resonator::{Device, DeviceParams, Tuner, DEFAULT_MARGIN};

use crate::engine::open_loop::{simulate, Choice, OpenLoop, Outcome, RunError, Start};
use crate::engine::solver::{Solver, Tolerance};

/// Steps a period each method runs at.
pub const STEPS_PER_PERIOD: [u32; 7] = [8, 16, 32, 64, 128, 256, 512];
/// Periods of the base frequency each scene runs.
pub const PERIODS: u32 = 40;
/// The error grid: points a period (every step count above is a multiple of it).
const GRID_PER_PERIOD: u32 = 8;

/// A named scene of the study.
pub struct Study {
    pub name: &'static str,
    pub what: String,
    pub scene: OpenLoop,
    /// The frequency that sets the step: the faster of the oscillation and the drive, Hz.
    pub base_hz: f64,
}

/// The three scenes, on `params`: a small oscillation about a tuned bias, a large
/// parametric drive, and a bias near the limit.
pub fn studies(params: DeviceParams<f64>) -> Result<Vec<Study>, String> {
    let device = Device::new(params).map_err(|e| e.to_string())?;
    let tuner = Tuner::new(device);
    let range = tuner
        .tunable_range(DEFAULT_MARGIN)
        .map_err(|e| e.to_string())?;
    let limit = tuner.limit().at.volts;
    let target_hz = 0.5 * (range.low_hz + range.high_hz);
    let tuned = tuner
        .tune(target_hz, DEFAULT_MARGIN)
        .map_err(|e| e.to_string())?;
    let at = |volts: f64| -> Result<f64, String> {
        let stretch = tuner
            .limit()
            .stretch_for_bias(&device, volts)
            .ok_or_else(|| format!("no equilibrium at {volts} V"))?;
        Ok(device.natural_frequency_hz(stretch))
    };
    let scene = |bias_volts, ac_volts, drive_hz, base_hz: f64| OpenLoop {
        params,
        bias_volts,
        ac_volts,
        drive_hz,
        duration_seconds: f64::from(PERIODS) / base_hz,
        start: Start::Equilibrium,
        y0: None,
        tolerance: None,
    };
    let f_tuned = tuned.natural_frequency_hz;
    let (big_bias, big_ac) = (0.6 * limit, 0.2 * limit);
    let f_big = at(big_bias)?;
    let near = 0.98 * limit;
    let f_near = at(near)?;
    Ok(vec![
        Study {
            name: "small_oscillation",
            what: format!(
                "tuned to {:.2} Hz ({:.0} V); AC 1% of the bias at 0.9 f0",
                f_tuned, tuned.volts
            ),
            scene: scene(tuned.volts, 0.01 * tuned.volts, 0.9 * f_tuned, f_tuned),
            base_hz: f_tuned,
        },
        Study {
            name: "parametric",
            what: format!(
                "{big_bias:.0} V bias, {big_ac:.0} V AC at 2 f0 = {:.2} Hz (principal parametric resonance)",
                2.0 * f_big
            ),
            scene: scene(big_bias, big_ac, 2.0 * f_big, 2.0 * f_big),
            base_hz: 2.0 * f_big,
        },
        Study {
            name: "near_limit",
            what: format!(
                "{near:.0} V bias (98% of the limit, f0 = {f_near:.2} Hz), AC 0.5% of the limit at f0"
            ),
            scene: scene(near, 0.005 * limit, f_near, f_near),
            base_hz: f_near,
        },
    ])
}

/// One method at one step on one scene.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub scene: &'static str,
    pub method: &'static str,
    pub steps_per_period: u32,
    pub step_seconds: f64,
    /// `ok`, `refused` (the guard) or `stopped` (a typed error).
    pub status: &'static str,
    /// The errors and the run time, where the run completed with finite values (JSON null
    /// and an empty CSV cell otherwise).
    pub final_relative_error: Option<f64>,
    pub max_error: Option<f64>,
    pub phase_error_rad: Option<f64>,
    pub run_seconds_per_simulated_second: Option<f64>,
}

/// The reference of one scene, sampled every 1/512 period, and its own error floor.
pub struct Reference {
    pub outcome: Outcome,
    /// Largest stretch difference on the error grid between tolerance 1e-12 and 1e-13.
    pub floor: f64,
    /// The reference at looser tolerances against the run at 1e-13.
    pub tolerances: Vec<ToleranceRow>,
}

/// The reference's tolerances in the study, against a run at 1e-13.
pub const REFERENCE_TOLERANCES: [f64; 4] = [1e-6, 1e-8, 1e-10, 1e-12];

/// The reference at one tolerance.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ToleranceRow {
    pub tolerance: f64,
    /// Largest stretch difference on the error grid against the run at 1e-13.
    pub max_error: f64,
    /// The solve alone (the fastest of repeats adding up to 20 ms), per simulated second.
    pub run_seconds_per_simulated_second: f64,
}

/// The reference run of a study, the floor (1e-12 against 1e-13), and the reference at each
/// of `REFERENCE_TOLERANCES` against 1e-13.
pub fn reference(study: &Study) -> Result<Reference, String> {
    let finest = STEPS_PER_PERIOD[STEPS_PER_PERIOD.len() - 1];
    let step = 1.0 / (f64::from(finest) * study.base_hz);
    let outcome = simulate(&study.scene, Choice::Reference, step).map_err(|e| e.to_string())?;
    let device = Device::new(study.scene.params).map_err(|e| e.to_string())?;
    let scale = device.rad_per_s_per_unit();
    let grid = step * f64::from(finest / GRID_PER_PERIOD) * scale;
    let start = [outcome.samples[0], 0.0];
    let drive = de_resonator::Drive::from_volts(
        &device,
        study.scene.bias_volts,
        study.scene.ac_volts,
        study.scene.drive_hz,
    );
    let end = study.scene.duration_seconds * scale;
    let at = |tolerance| {
        let tolerance = Tolerance::both(tolerance);
        crate::engine::solver::solve(Solver::Dop853, &device, drive, start, end, grid, tolerance)
    };
    let tighter = at(1e-13)?;
    let mut tolerances = Vec::new();
    for tolerance in REFERENCE_TOLERANCES {
        let (mut fastest, mut spent, mut ys) = (f64::INFINITY, 0.0, Vec::new());
        while spent < 0.02 {
            let started = Instant::now();
            ys = at(tolerance)?;
            let took = started.elapsed().as_secs_f64();
            (fastest, spent) = (fastest.min(took), spent + took);
        }
        let max_error = ys
            .iter()
            .zip(&tighter)
            .map(|(a, b)| (a[0] - b[0]).abs())
            .fold(0.0, f64::max);
        tolerances.push(ToleranceRow {
            tolerance,
            max_error,
            run_seconds_per_simulated_second: fastest / study.scene.duration_seconds,
        });
    }
    // The reference's own: one solve whatever its output times, so its run at 1e-12 is this.
    let floor = tolerances
        .iter()
        .find(|t| t.tolerance == crate::engine::solver::REFERENCE_TOLERANCE)
        .map_or(f64::NAN, |t| t.max_error);
    Ok(Reference {
        outcome,
        floor,
        tolerances,
    })
}

/// The time (s) at which a cubic Hermite interpolant through (t0, x0, v0), (t1, x1, v1)
/// crosses zero, found by bisection; x0 < 0 <= x1.
fn hermite_root(t0: f64, t1: f64, x0: f64, x1: f64, v0: f64, v1: f64) -> f64 {
    let h = t1 - t0;
    let at = |s: f64| {
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * x0
            + (s3 - 2.0 * s2 + s) * h * v0
            + (-2.0 * s3 + 3.0 * s2) * x1
            + (s3 - s2) * h * v1
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if at(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    t0 + 0.5 * (lo + hi) * h
}

/// Times of the upward crossings of `level` by the sampled motion (step `dt`).
fn upward_crossings(out: &Outcome, dt: f64, level: f64) -> Vec<f64> {
    let x = &out.samples;
    let v = &out.velocities;
    (1..x.len())
        .filter(|&k| x[k - 1] - level < 0.0 && x[k] - level >= 0.0)
        .map(|k| {
            let t0 = (k - 1) as f64 * dt;
            hermite_root(t0, t0 + dt, x[k - 1] - level, x[k] - level, v[k - 1], v[k])
        })
        .collect()
}

/// The errors of `run` (at `steps_per_period`) against the reference.
fn errors(
    study: &Study,
    reference: &Reference,
    run: &Outcome,
    steps_per_period: u32,
) -> (f64, f64, f64) {
    let finest = STEPS_PER_PERIOD[STEPS_PER_PERIOD.len() - 1];
    let r = &reference.outcome.samples;
    let fine = (finest / GRID_PER_PERIOD) as usize;
    let own = (steps_per_period / GRID_PER_PERIOD) as usize;
    let max_error = (0..)
        .map_while(|k| Some((run.samples.get(k * own)? - r.get(k * fine)?).abs()))
        .fold(0.0, f64::max);
    let last = |x: &[f64]| *x.last().unwrap_or(&f64::NAN);
    let final_relative_error = ((last(&run.samples) - last(r)) / last(r)).abs();
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let dt_ref = 1.0 / (f64::from(finest) * study.base_hz);
    let dt_run = 1.0 / (f64::from(steps_per_period) * study.base_hz);
    let phase = match (
        upward_crossings(&reference.outcome, dt_ref, mean).last(),
        upward_crossings(run, dt_run, mean),
    ) {
        (Some(&t_ref), own) => {
            own.iter()
                .map(|t| (t - t_ref).abs())
                .fold(f64::INFINITY, f64::min)
                * std::f64::consts::TAU
                * study.base_hz
        }
        _ => f64::NAN,
    };
    (final_relative_error, max_error, phase)
}

/// One core method at every step on one study.
pub fn rows(study: &Study, reference: &Reference, choice: Choice) -> Vec<Row> {
    let mut rows = Vec::new();
    for n in STEPS_PER_PERIOD {
        let step = 1.0 / (f64::from(n) * study.base_hz);
        let mut row = Row {
            scene: study.name,
            method: choice.name(),
            steps_per_period: n,
            step_seconds: step,
            status: "ok",
            final_relative_error: None,
            max_error: None,
            phase_error_rad: None,
            run_seconds_per_simulated_second: None,
        };
        let mut fastest = f64::INFINITY;
        let mut spent = 0.0;
        let mut last = None;
        while spent < 0.02 {
            let started = Instant::now();
            let result = simulate(&study.scene, choice, step);
            let took = started.elapsed().as_secs_f64();
            spent += took;
            fastest = fastest.min(took);
            match result {
                // Left the model's range before any crossing: no error to measure.
                Ok(out) if out.stopped.is_some() && out.first_limit.is_none() => {
                    row.status = "stopped";
                    break;
                }
                Ok(out) => last = Some(out),
                Err(RunError::Refused(_)) => {
                    row.status = "refused";
                    break;
                }
                Err(RunError::Failed(_)) => {
                    row.status = "stopped";
                    break;
                }
            }
        }
        if let Some(out) = last.filter(|_| row.status == "ok") {
            if out.stopped.is_some() {
                row.status = "stopped";
            } else {
                let (final_relative, max, phase) = errors(study, reference, &out, n);
                let finite = crate::text::finite;
                row.final_relative_error = finite(final_relative);
                row.max_error = finite(max);
                row.phase_error_rad = finite(phase);
                row.run_seconds_per_simulated_second =
                    finite(fastest / study.scene.duration_seconds);
            }
        }
        rows.push(row);
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_root_is_exact_for_a_cubic() {
        // x(t) = t³ − 0.1 on [0, 1]: root at 0.1^(1/3); Hermite data is exact for a cubic.
        let root = hermite_root(0.0, 1.0, -0.1, 0.9, 0.0, 3.0);
        assert!((root - 0.1f64.cbrt()).abs() < 1e-14, "{root}");
    }

    #[test]
    fn crossings_of_a_sine_sampled_coarsely() {
        // sin(2πt) sampled 16 times a period: upward crossings at whole t, to O(h⁴).
        let dt = 1.0 / 16.0;
        let t: Vec<f64> = (0..=48).map(|k| k as f64 * dt - 0.3).collect();
        let out = Outcome {
            final_stretch: 0.0,
            final_velocity_per_second: 0.0,
            min_stretch: -1.0,
            max_stretch: 1.0,
            first_limit: None,
            first_limit_state: None,
            samples: t
                .iter()
                .map(|t| (std::f64::consts::TAU * t).sin())
                .collect(),
            velocities: t
                .iter()
                .map(|t| std::f64::consts::TAU * (std::f64::consts::TAU * t).cos())
                .collect(),
            stopped: None,
            run_seconds: 0.0,
            step_seconds: dt,
            solver: None,
            switched: None,
            evaluations: None,
            evaluated: None,
        };
        let found = upward_crossings(&out, dt, 0.0);
        assert_eq!(found.len(), 3);
        for (k, t) in found.iter().enumerate() {
            // Times are from the first sample, at t = −0.3.
            assert!((t - 0.3 - k as f64).abs() < 1e-4, "{t}");
        }
    }
}
