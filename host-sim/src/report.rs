//! What `safe` and `tune` print: a JSON object for tools, or a short text for people.

use de_resonator::{Equilibrium, TunableRange, Tuner};
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
