//! Numbers and report pieces for people and for JSON: a leaf, used by the commands and the
//! studies alike.

use de_resonator::FailureMode;
use serde::Serialize;

/// Six significant figures, for people.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exponent = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&exponent) {
        // Tiny or huge: scientific, not a row of zeros.
        return format!("{x:.5e}");
    }
    let decimals = (5 - exponent).max(0) as usize;
    format!("{x:.decimals$}")
}

/// A number for JSON: `None` (null) when not finite, as JSON has no NaN.
pub fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Six significant figures without trailing zeros (a setting, a label: `2.5`, `120`).
pub fn short(x: f64) -> String {
    let text = sig(x);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// A check that failed along a run, and when (JSON: `{mode, time_seconds}`, and the state
/// there where the run located it: `stretch`, `velocity_per_second`).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Crossing {
    pub mode: &'static str,
    pub time_seconds: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch: Option<f64>,
    /// dλ/dt there, 1/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity_per_second: Option<f64>,
}

impl Crossing {
    pub fn of(first: Option<(FailureMode, f64)>) -> Option<Self> {
        Self::with_state(first, None)
    }

    /// With the state where it was located: stretch, dλ/dt in 1/s.
    pub fn with_state(
        first: Option<(FailureMode, f64)>,
        state: Option<(f64, f64)>,
    ) -> Option<Self> {
        first.map(|(mode, time_seconds)| Crossing {
            mode: mode.name(),
            time_seconds,
            stretch: state.map(|s| s.0),
            velocity_per_second: state.map(|s| s.1),
        })
    }
}
