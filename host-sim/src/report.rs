//! What `safe` and `tune` print: a JSON object for tools, or a short text for people.

use de_resonator::{Equilibrium, TunableRange, Tuner};

use crate::simulate::Outcome;
use serde_json::{json, Value};

/// The keys `safe` and `tune` share: zero-bias frequency, limit, tunable range.
fn region(tuner: &Tuner<f64>, range: &TunableRange<f64>, margin: f64) -> Value {
    let limit = tuner.limit();
    json!({
        "zero_bias_frequency_hz": tuner.zero_bias().natural_frequency_hz,
        "limit": {
            "mode": limit.mode.name(),
            "volts": limit.at.volts,
            "stretch": limit.at.stretch,
            "natural_frequency_hz": limit.at.natural_frequency_hz,
        },
        "margin": margin,
        "max_bias_volts": range.max_bias.volts,
        "tunable_range_hz": [range.low_hz, range.high_hz],
    })
}

/// Six significant figures, for people.
fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (5 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

fn region_text(name: &str, tuner: &Tuner<f64>, range: &TunableRange<f64>, margin: f64) -> String {
    let limit = tuner.limit();
    let zero = tuner.zero_bias();
    format!(
        "device          {name}\n\
         zero bias       f = {} Hz at stretch {}\n\
         limit           {}: {}\n\
         \x20               at {} V, stretch {}, f = {} Hz\n\
         margin {margin:<8} bias at most {} V (stretch {})\n\
         tunable range   {} .. {} Hz",
        sig(zero.natural_frequency_hz),
        sig(zero.stretch),
        limit.mode.name(),
        limit.mode.description(),
        sig(limit.at.volts),
        sig(limit.at.stretch),
        sig(limit.at.natural_frequency_hz),
        sig(range.max_bias.volts),
        sig(range.max_bias.stretch),
        sig(range.low_hz),
        sig(range.high_hz),
    )
}

/// The output of `host-sim safe`.
pub fn safe(
    name: &str,
    tuner: &Tuner<f64>,
    range: &TunableRange<f64>,
    margin: f64,
    as_json: bool,
) -> String {
    if as_json {
        region(tuner, range, margin).to_string()
    } else {
        region_text(name, tuner, range, margin)
    }
}

/// The output of `host-sim tune`.
pub fn tune(
    name: &str,
    tuner: &Tuner<f64>,
    range: &TunableRange<f64>,
    margin: f64,
    target_hz: f64,
    bias: &Equilibrium<f64>,
    as_json: bool,
) -> String {
    if as_json {
        let mut out = region(tuner, range, margin);
        out["target_hz"] = json!(target_hz);
        out["bias_volts"] = json!(bias.volts);
        out["stretch"] = json!(bias.stretch);
        out["natural_frequency_hz"] = json!(bias.natural_frequency_hz);
        out.to_string()
    } else {
        format!(
            "{}\n\ntarget          {} Hz\nbias            {} V (stretch {}, f = {} Hz)",
            region_text(name, tuner, range, margin),
            sig(target_hz),
            sig(bias.volts),
            sig(bias.stretch),
            sig(bias.natural_frequency_hz),
        )
    }
}

/// The output of `host-sim simulate`.
pub fn simulation(name: &str, method: &str, step: f64, out: &Outcome, as_json: bool) -> String {
    let first_limit = out
        .first_limit
        .map(|(mode, time)| json!({"mode": mode.name(), "time": time}));
    if as_json {
        json!({
            "method": method,
            "step_seconds": step,
            "steps": out.samples.len().saturating_sub(1),
            "final": {
                "stretch": out.final_stretch,
                "velocity": out.final_velocity_per_second,
            },
            "min_stretch": out.min_stretch,
            "max_stretch": out.max_stretch,
            "first_limit": first_limit,
            "run_seconds": out.run_seconds,
        })
        .to_string()
    } else {
        let limit = match out.first_limit {
            Some((mode, time)) => format!("{} at t = {} s", mode.description(), sig(time)),
            None => "none crossed".into(),
        };
        format!(
            "device          {name}\n\
             method          {method}, step {} s, {} steps in {} ms\n\
             final           stretch {}, velocity {} 1/s\n\
             stretch range   {} .. {}\n\
             first limit     {limit}",
            sig(step),
            out.samples.len().saturating_sub(1),
            sig(out.run_seconds * 1e3),
            sig(out.final_stretch),
            sig(out.final_velocity_per_second),
            sig(out.min_stretch),
            sig(out.max_stretch),
        )
    }
}
