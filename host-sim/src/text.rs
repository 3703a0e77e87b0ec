//! Numbers for people and for JSON: a leaf, used by the commands and the studies alike.

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
