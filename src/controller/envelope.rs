//! The drive's swing as the sensor measures it, against its prediction (model.md §7,
//! `Device::check_swing`). The checks of §6 passed on the predicted swing widened by
//! 1/(1 − margin), under the peak voltage raised as much; a measured swing that leaves that
//! box, or grows window after window without slowing fast enough to leave it within the
//! next, is taken off there: before any limit, whatever the device file says of the
//! damping (docs/safety.md, "The drive's swing").

use super::fault::Fault;
use crate::model::swing::Swing;

/// A tick's stretch noise (RMS, as the front end declares it), counted this many times on
/// each side of the swing.
const NOISE_SIGMAS: f32 = 5.0;

/// The noise allowed on each side of the swing, in stretch, where the front end declares
/// none (a host's sensor read directly).
const UNDECLARED_NOISE_STRETCH: f32 = 1e-4;

/// The drive's predicted swing, as the board watches it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Predicted {
    /// The half-span the measured swing may reach, in stretch: half the predicted swing's
    /// span (switch-on, the ramp's ring, a pulse's and a carried one included) widened by
    /// 1/(1 − margin) as the checks had it, and the sensor's noise.
    pub allowed: f32,
    /// A window's ticks: the longest period in the motion (two of the drive's, for the
    /// parametric response at half its frequency; the natural one, for the free ring).
    pub window_ticks: u32,
}

impl Predicted {
    /// The watch of `swing` (a drive at `ac_hz` that fits, its prediction with the margin
    /// `margin`) on a board ticking at `tick_hz` whose stretch reading has the RMS noise
    /// `noise` a tick (`None`: not declared).
    #[inline(never)]
    pub fn of(
        swing: &Swing<f32>,
        ac_hz: f32,
        tick_hz: f32,
        margin: f32,
        noise: Option<f32>,
    ) -> Self {
        // Half the predicted span: about the mean the motion settles to, the forced terms
        // and rings; the steady push's own step rings as much about it.
        let amplitude = (swing.high_stretch - swing.low_stretch) / 2.0;
        let noise = noise.map_or(UNDECLARED_NOISE_STRETCH, |sigma| NOISE_SIGMAS * sigma);
        let seconds = (2.0 / ac_hz).max(1.0 / swing.natural_hz);
        let window = libm::ceilf(seconds * tick_hz);
        Self {
            allowed: amplitude / (1.0 - margin) + noise,
            // Saturating: NaN and ∞ (no natural frequency) give 0 and u32::MAX.
            window_ticks: (window as u32).max(1),
        }
    }
}

/// The measured swing over the current window while a drive is on, and the last windows'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Envelope {
    ticks: u32,
    /// The window's lowest and highest samples (∞ and −∞ before its first).
    low: f32,
    high: f32,
    /// The last whole window's half-span (NaN before one).
    previous: f32,
    /// The growths of the last two windows' half-spans over the ones before them, the
    /// latest first (NaN where there was none).
    growths: (f32, f32),
}

impl Default for Envelope {
    fn default() -> Self {
        Self {
            ticks: 0,
            low: f32::INFINITY,
            high: f32::NEG_INFINITY,
            previous: f32::NAN,
            growths: (f32::NAN, f32::NAN),
        }
    }
}

impl Envelope {
    /// A stretch sample at tick `k` (a number: the watch refused any other before) of a
    /// drive predicted as `predicted`: a fault where the window's half-span so far is above
    /// what is allowed; or, at a window's end, where a growth that has not slowed for
    /// three windows (a swing pumped or driven past its damping, not one settling) carried
    /// a window ahead would be. The tick's budget: compares only, but at a window's end.
    pub(super) fn observe(&mut self, k: u32, stretch: f32, predicted: &Predicted) -> Option<Fault> {
        if stretch < self.low {
            self.low = stretch;
        }
        if stretch > self.high {
            self.high = stretch;
        }
        self.ticks += 1;
        let span = self.high - self.low;
        if self.ticks < predicted.window_ticks && span <= 2.0 * predicted.allowed {
            return None;
        }
        self.window_end(k, span / 2.0, predicted)
    }

    /// The window's end (or a half-span above what is allowed): the growth over the last
    /// window, carried ahead if it has not slowed, and the verdict.
    #[inline]
    fn window_end(&mut self, k: u32, half_span: f32, predicted: &Predicted) -> Option<Fault> {
        let mut ahead = 0.0;
        if self.ticks >= predicted.window_ticks {
            let now = half_span - self.previous;
            let (before, first) = self.growths;
            // Growing, and not slowing, three windows in a row (NaN compares false).
            if now >= before && before >= first && first > 0.0 {
                ahead = now;
            }
            self.growths = (now, before);
            (self.ticks, self.previous) = (0, half_span);
            (self.low, self.high) = (f32::INFINITY, f32::NEG_INFINITY);
        }
        let within = half_span + ahead <= predicted.allowed;
        (!within).then_some(Fault::SwingOutgrown {
            tick: k,
            half_span,
            growth: ahead,
            allowed: predicted.allowed,
        })
    }
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;

    fn predicted(allowed: f32, window_ticks: u32) -> Predicted {
        Predicted {
            allowed,
            window_ticks,
        }
    }

    /// The watch of a prediction as docs/safety.md states it: half the predicted span
    /// widened by 1/(1 − margin), and five times the declared noise (10⁻⁴ where none is);
    /// the window the longer of two drive periods and the natural one, in whole ticks.
    #[test]
    fn a_prediction_is_watched_as_documented() {
        let swing = Swing {
            stretch: 2.0,
            low_stretch: 1.99,
            high_stretch: 2.03,
            natural_hz: 40.0,
            quality_factor: 100.0,
        };
        let amplitude = (2.03f32 - 1.99) / 2.0;
        let p = Predicted::of(&swing, 30.0, 1000.0, 0.2, Some(1e-5));
        assert!((p.allowed - (amplitude / 0.8 + 5e-5)).abs() < 1e-7, "{p:?}");
        // Two periods of 30 Hz, 66.7 ms: 67 ticks at 1 kHz.
        assert_eq!(p.window_ticks, 67);
        let p = Predicted::of(&swing, 200.0, 1000.0, 0.0, None);
        assert!((p.allowed - (amplitude + 1e-4)).abs() < 1e-7, "{p:?}");
        // The natural period, 25 ms, is the longer.
        assert_eq!(p.window_ticks, 25);
        // No natural frequency: a window that never ends (the half-span still checked).
        let none = Swing {
            natural_hz: 0.0,
            ..swing
        };
        assert_eq!(
            Predicted::of(&none, 30.0, 1000.0, 0.05, None).window_ticks,
            u32::MAX
        );
    }

    /// A sine of `amplitude` about 2, `ticks_per_period` a period, at tick `k`.
    fn sine(amplitude: f32, ticks_per_period: u32, k: u32) -> f32 {
        let turn = (k % ticks_per_period) as f32 / ticks_per_period as f32;
        2.0 + amplitude * libm::sinf(core::f32::consts::TAU * turn)
    }

    #[test]
    fn a_swing_within_the_prediction_runs() {
        let p = predicted(1e-3, 40);
        let mut e = Envelope::default();
        for k in 0..4000 {
            assert_eq!(e.observe(k, sine(0.99e-3, 20, k), &p), None, "tick {k}");
        }
    }

    /// The half-span above what is allowed faults at the tick it is seen, not at the window's
    /// end.
    #[test]
    fn a_swing_above_the_allowed_faults_within_its_half_period() {
        let p = predicted(1e-3, 400);
        let mut e = Envelope::default();
        let fault = (0..400).find_map(|k| e.observe(k, sine(1.02e-3, 20, k), &p));
        match fault {
            Some(Fault::SwingOutgrown {
                tick, half_span, ..
            }) => {
                assert!(tick <= 15, "tick {tick}");
                assert!(half_span > 1e-3 && half_span <= 1.02e-3, "{half_span}");
            }
            other => panic!("{other:?}"),
        }
    }

    /// Growing by 3/16 of what is allowed a window, from 6/16 of it: the window at 15/16,
    /// its growth not slowing for three windows, carried one window ahead reaches 18/16 and
    /// faults a window before the swing itself would.
    #[test]
    fn a_growth_not_slowing_faults_a_window_ahead() {
        let p = predicted(1.0, 10);
        let mut e = Envelope::default();
        let mut fault = None;
        'windows: for window in 0..6u32 {
            let amplitude = 0.375 + 0.1875 * window as f32;
            for i in 0..10 {
                let k = window * 10 + i;
                let x = if i % 2 == 0 { amplitude } else { -amplitude };
                if let Some(f) = e.observe(k, x, &p) {
                    fault = Some(f);
                    break 'windows;
                }
            }
        }
        match fault {
            Some(Fault::SwingOutgrown {
                tick,
                half_span,
                growth,
                allowed,
            }) => {
                assert_eq!(tick, 39, "the fourth window's end");
                assert_eq!((half_span, growth), (0.9375, 0.1875));
                assert_eq!(allowed, 1.0);
            }
            other => panic!("{other:?}"),
        }
    }

    /// A swing settling (switched on: its growth falls window by window) is not carried
    /// ahead, however large its first growth.
    #[test]
    fn a_settling_growth_is_not_carried_ahead() {
        let p = predicted(1.0, 10);
        let mut e = Envelope::default();
        for k in 0..400u32 {
            let window = (k / 10) as f32;
            let amplitude = 0.99 * (1.0 - libm::expf(-(window + 1.0) / 1.5));
            let x = if k % 2 == 0 { amplitude } else { -amplitude };
            assert_eq!(e.observe(k, x, &p), None, "tick {k}");
        }
    }

    /// A swing that dies away (a ring decaying) never counts a growth.
    #[test]
    fn a_decaying_ring_is_no_growth() {
        let p = predicted(1.0, 10);
        let mut e = Envelope::default();
        for k in 0..1000u32 {
            let amplitude = 0.99 * libm::expf(-(k as f32) / 200.0);
            let x = if k % 2 == 0 { amplitude } else { -amplitude };
            assert_eq!(e.observe(k, x, &p), None, "tick {k}");
        }
    }

    /// An allowed half-span that is not a number passes nothing.
    #[test]
    fn nan_allowed_faults() {
        let p = predicted(f32::NAN, 10);
        let mut e = Envelope::default();
        assert!(e.observe(0, 2.0, &p).is_some());
    }
}
