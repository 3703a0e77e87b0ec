//! The axes: a data range onto pixels, linear or log10, and their ticks.

/// 10^e as people write it: 1, 10, 100, 10³, 10⁻³.
pub(super) fn power_of_ten(e: i32) -> String {
    match e {
        0 => "1".into(),
        1 => "10".into(),
        2 => "100".into(),
        _ => {
            const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
            let digits: String = e
                .unsigned_abs()
                .to_string()
                .chars()
                .filter_map(|d| d.to_digit(10).and_then(|d| SUPERSCRIPT.get(d as usize)))
                .collect();
            format!("10{}{digits}", if e < 0 { "⁻" } else { "" })
        }
    }
}

/// An axis: data range mapped onto pixels, linear or log10.
pub(super) struct Axis {
    low: f64,
    high: f64,
    log: bool,
}

impl Axis {
    pub(super) fn new(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
            let v = if log { v.log10() } else { v };
            low = low.min(v);
            high = high.max(v);
        }
        if !low.is_finite() {
            (low, high) = (0.0, 1.0);
        }
        if log {
            (low, high) = (low.floor(), high.ceil().max(low.floor() + 1.0));
        } else {
            // A flat line gets a range around it (a zero span has no ticks).
            let pad = if high - low > 1e-9 * high.abs().max(low.abs()) {
                0.05 * (high - low)
            } else {
                0.1 * high.abs().max(1.0)
            };
            (low, high) = (low - pad, high + pad);
        }
        Axis { low, high, log }
    }

    /// Position in [0, 1], or None when the value cannot be drawn.
    pub(super) fn fraction(&self, v: f64) -> Option<f64> {
        let v = if self.log {
            (v > 0.0).then(|| v.log10())?
        } else {
            v
        };
        v.is_finite()
            .then(|| (v - self.low) / (self.high - self.low))
    }

    /// Tick positions (data values) and labels.
    pub(super) fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (a, b) = (self.low as i32, self.high as i32);
            let every = ((b - a) / 8).max(1);
            return (a..=b)
                .step_by(every as usize)
                .map(|e| (10f64.powi(e), power_of_ten(e)))
                .collect();
        }
        let span = self.high - self.low;
        let raw = span / 6.0;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * magnitude);
        let first = (self.low / step).ceil() as i64;
        let last = (self.high / step).floor() as i64;
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        (first..=last)
            .map(|k| {
                let v = k as f64 * step;
                (v, format!("{v:.decimals$}"))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_of_ten_are_written_as_people_write_them() {
        let written: Vec<String> = [-12, -3, -1, 0, 1, 2, 3, 10].map(power_of_ten).into();
        assert_eq!(
            written,
            ["10⁻¹²", "10⁻³", "10⁻¹", "1", "10", "100", "10³", "10¹⁰"]
        );
    }

    #[test]
    fn log_axis_spans_whole_decades_and_drops_what_it_cannot_draw() {
        let axis = Axis::new([3e-7, 2e-2, 0.0, f64::NAN].into_iter(), true);
        assert_eq!((axis.low, axis.high), (-7.0, -1.0));
        assert_eq!(axis.fraction(1e-4), Some(0.5));
        assert_eq!(axis.fraction(0.0), None);
    }

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let axis = Axis::new([0.0, 100.0].into_iter(), false);
        let ticks = axis.ticks();
        assert!(ticks.iter().all(|(v, _)| *v >= axis.low && *v <= axis.high));
        let labels: Vec<&str> = ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0", "20", "40", "60", "80", "100"]);
        let fine = Axis::new([0.3, 0.9].into_iter(), false);
        assert!(fine.ticks().iter().any(|(_, l)| l == "0.6"));
    }
}
