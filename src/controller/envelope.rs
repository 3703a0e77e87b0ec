//! The drive's swing as the sensor measures it, against its prediction (model.md §7,
//! `Device::check_swing`). The checks of §6 passed on the predicted swing widened by
//! 1/(1 − margin), under the peak voltage raised as much; a measured swing that leaves that
//! box, or grows window after window without slowing fast enough to leave it within the
//! next, is taken off there: before any limit, whatever the device file says of the
//! damping (docs/safety.md, "The measured swing stays inside the box the checks passed").

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
    /// A window's drive periods: the longest period in the motion (two of the drive's, for
    /// the parametric response at half its frequency; the natural one, for the free ring).
    /// Counted on the drive's phase, each ending as it passes half a turn: half a period
    /// from where a tracker's cycle ends (the tick's budget).
    pub window_periods: u32,
    /// The quality factor the swing was predicted with (the device's, or the trim's ring's
    /// highest): the fault log says it when the measured swing outgrows the prediction.
    pub quality_factor: f32,
}

impl Predicted {
    /// No prediction: a drive with it faults at its second sample rather than go unwatched.
    pub const NONE: Predicted = Predicted {
        allowed: f32::NAN,
        window_periods: u32::MAX,
        quality_factor: f32::NAN,
    };

    /// The watch of `swing` (a drive at `ac_hz` that fits, its prediction with the margin
    /// `margin`) on a board whose stretch reading has the RMS noise `noise` a tick (`None`:
    /// not declared). Out of line: the boot's frame stays the smaller (the stack's budget).
    #[inline(never)]
    pub fn of(swing: &Swing<f32>, ac_hz: f32, margin: f32, noise: Option<f32>) -> Self {
        // Half the predicted span: about the mean the motion settles to, the forced terms
        // and rings; the steady push's own step rings as much about it.
        let amplitude = (swing.high_stretch - swing.low_stretch) / 2.0;
        let noise = noise.map_or(UNDECLARED_NOISE_STRETCH, |sigma| NOISE_SIGMAS * sigma);
        let periods = libm::ceilf((ac_hz / swing.natural_hz).max(2.0));
        Self {
            allowed: amplitude / (1.0 - margin) + noise,
            // Saturating: ∞ (no natural frequency) gives u32::MAX, NaN 0 (then 2).
            window_periods: (periods as u32).max(2),
            quality_factor: swing.quality_factor,
        }
    }
}

/// The measured swing over the current window while a drive is on, and the last windows'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Envelope {
    /// Whether the drive's phase was past half a turn at the last sample, and the half
    /// turns it has passed in this window (`None`: no window yet).
    past_half: bool,
    periods: Option<u32>,
    /// The window's lowest and highest samples.
    low: f32,
    high: f32,
    /// The last whole window's half-span (NaN before one).
    previous: f32,
    /// The growths of the last two windows' half-spans over the ones before them, the
    /// latest first (NaN where there was none).
    growths: (f32, f32),
    /// The growth carried ahead at the last window's end (0 where none was).
    ahead: f32,
}

impl Default for Envelope {
    fn default() -> Self {
        Self {
            past_half: false,
            periods: None,
            low: f32::NAN,
            high: f32::NAN,
            previous: f32::NAN,
            growths: (f32::NAN, f32::NAN),
            ahead: 0.0,
        }
    }
}

impl Envelope {
    /// A stretch sample (a number: the watch refused any other before) at the drive's
    /// `phase` (a turn is 2³²) of a drive predicted as `predicted`: whether the swing is
    /// within what is allowed. Not where the window's span so far is above twice it; nor,
    /// at a window's end, where a growth that has not slowed for three windows (a swing
    /// pumped or driven past its damping, not one settling) carried a window ahead would be
    /// (`outgrown` says how). The tick's budget: a few compares a sample, a few operations
    /// more at a window's end.
    pub(super) fn within(&mut self, phase: u32, stretch: f32, predicted: &Predicted) -> bool {
        let past_half = phase >= 1 << 31;
        let passed = past_half && !self.past_half;
        self.past_half = past_half;
        let Some(periods) = self.periods else {
            (self.periods, self.low, self.high) = (Some(0), stretch, stretch);
            return true;
        };
        if stretch < self.low {
            self.low = stretch;
        } else if stretch > self.high {
            self.high = stretch;
        }
        let span = self.high - self.low;
        if !passed || periods + 1 < predicted.window_periods {
            self.periods = Some(periods + u32::from(passed));
            return span <= predicted.allowed + predicted.allowed;
        }
        self.window_end(stretch, span * 0.5, predicted)
    }

    /// The window's end: the growth over the last window, carried ahead if it has not
    /// slowed, the verdict, and the next window from this sample.
    fn window_end(&mut self, stretch: f32, half_span: f32, predicted: &Predicted) -> bool {
        let now = half_span - self.previous;
        let (before, first) = self.growths;
        // Growing, and not slowing, three windows in a row (NaN compares false).
        self.ahead = if now >= before && before >= first && first > 0.0 {
            now
        } else {
            0.0
        };
        self.growths = (now, before);
        self.previous = half_span;
        let within = half_span + self.ahead <= predicted.allowed;
        if within {
            (self.periods, self.low, self.high) = (Some(0), stretch, stretch);
        }
        within
    }

    /// Why the swing is not within (`within` false at tick `k`): its half-span, the growth
    /// carried ahead, and what was allowed.
    pub(super) fn outgrown(&self, k: u32, predicted: &Predicted) -> Fault {
        Fault::SwingOutgrown {
            tick: k,
            half_span: (self.high - self.low) * 0.5,
            growth: self.ahead,
            allowed: predicted.allowed,
            quality_factor: predicted.quality_factor,
        }
    }
}

#[cfg(test)]
#[allow(clippy::panic, clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The drive's phase at tick `k`, `ticks_per_period` ticks a period.
    fn phase(k: u32, ticks_per_period: u32) -> u32 {
        ((u64::from(k % ticks_per_period) << 32) / u64::from(ticks_per_period)) as u32
    }

    /// The fault a sample at tick `k` brings, if any, the drive 5 ticks a period.
    fn observe(e: &mut Envelope, k: u32, stretch: f32, p: &Predicted) -> Option<Fault> {
        (!e.within(phase(k, 5), stretch, p)).then(|| e.outgrown(k, p))
    }

    /// Windows of two drive periods (10 ticks).
    fn predicted(allowed: f32) -> Predicted {
        Predicted {
            allowed,
            window_periods: 2,
            quality_factor: 50.0,
        }
    }

    /// The watch of a prediction as docs/safety.md states it: half the predicted span
    /// widened by 1/(1 − margin), and five times the declared noise (10⁻⁴ where none is);
    /// the window the longer of two drive periods and the natural one, in drive periods.
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
        let p = Predicted::of(&swing, 30.0, 0.2, Some(1e-5));
        assert!((p.allowed - (amplitude / 0.8 + 5e-5)).abs() < 1e-7, "{p:?}");
        assert_eq!(p.window_periods, 2);
        assert_eq!(p.quality_factor, 100.0);
        let p = Predicted::of(&swing, 200.0, 0.0, None);
        assert!((p.allowed - (amplitude + 1e-4)).abs() < 1e-7, "{p:?}");
        // The natural period, 25 ms, is five of the drive's 5 ms.
        assert_eq!(p.window_periods, 5);
        // No natural frequency: a window that never ends (the half-span still checked).
        let none = Swing {
            natural_hz: 0.0,
            ..swing
        };
        assert_eq!(
            Predicted::of(&none, 30.0, 0.05, None).window_periods,
            u32::MAX
        );
    }

    #[test]
    fn a_swing_within_the_prediction_runs() {
        let p = predicted(1e-3);
        let mut e = Envelope::default();
        for k in 0..4000 {
            let x = 2.0 + 0.99e-3 * libm::sinf(core::f32::consts::TAU * (k % 5) as f32 / 5.0);
            assert_eq!(observe(&mut e, k, x, &p), None, "tick {k}");
        }
    }

    /// The half-span above what is allowed faults at the tick it is seen, not at the window's
    /// end.
    #[test]
    fn a_swing_above_the_allowed_faults_within_its_half_period() {
        let p = Predicted {
            window_periods: 1000,
            ..predicted(1e-3)
        };
        let mut e = Envelope::default();
        let fault = (0..400).find_map(|k| {
            let x = 2.0 + 1.02e-3 * libm::sinf(core::f32::consts::TAU * (k % 20) as f32 / 20.0);
            observe(&mut e, k, x, &p)
        });
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

    /// Growing by 1/64 of what is allowed a tick from a quarter of it, not slowing: carried
    /// one window ahead, it faults at a window's end while the swing itself is still within
    /// what is allowed, a window before it would not be.
    #[test]
    fn a_growth_not_slowing_faults_a_window_ahead() {
        let p = predicted(1.0);
        let mut e = Envelope::default();
        let amplitude = |k: u32| 0.25 + k as f32 / 64.0 / 10.0;
        let fault = (0..1000u32).find_map(|k| {
            let x = if k % 2 == 0 {
                amplitude(k)
            } else {
                -amplitude(k)
            };
            observe(&mut e, k, x, &p)
        });
        match fault {
            Some(Fault::SwingOutgrown {
                tick,
                half_span,
                growth,
                allowed,
                quality_factor,
            }) => {
                // The Q it was predicted with, said with it.
                assert_eq!(quality_factor, 50.0);
                assert!(
                    growth > 0.0 && half_span <= allowed,
                    "{half_span} + {growth}"
                );
                assert!(half_span + growth > allowed);
                // The swing itself passes what is allowed only later.
                assert!(
                    amplitude(tick) <= 1.0 && amplitude(tick + 10) > 0.98,
                    "tick {tick}"
                );
            }
            other => panic!("{other:?}"),
        }
    }

    /// A swing settling (switched on: its growth falls window by window) is not carried
    /// ahead, however large its first growth.
    #[test]
    fn a_settling_growth_is_not_carried_ahead() {
        let p = predicted(1.0);
        let mut e = Envelope::default();
        for k in 0..400u32 {
            let window = (k / 10) as f32;
            let amplitude = 0.99 * (1.0 - libm::expf(-(window + 1.0) / 1.5));
            let x = if k % 2 == 0 { amplitude } else { -amplitude };
            assert_eq!(observe(&mut e, k, x, &p), None, "tick {k}");
        }
    }

    /// A swing settling fast (each window's growth under half the one before: carried
    /// ahead, it would pass what is allowed) is not carried ahead either.
    #[test]
    fn a_fast_settling_growth_is_not_carried_ahead() {
        let p = predicted(1.0);
        let mut e = Envelope::default();
        for k in 0..400u32 {
            let amplitude = 0.98 - 0.5 * libm::powf(0.3, (k / 10) as f32);
            let x = if k % 2 == 0 { amplitude } else { -amplitude };
            assert_eq!(observe(&mut e, k, x, &p), None, "tick {k}");
        }
    }

    /// A window ends as the drive's phase passes half a turn, every `window_periods` turns
    /// (2 here, 5 ticks a turn, the phase past half a turn at ticks 3, 8, 13, …: windows end
    /// at 8, 18, 28, …, half a period from where a tracker's cycle ends): a swing growing by
    /// 1/512 a tick (exact in binary) grows 10/512 a window, and that growth carried ahead is said at the first
    /// such end where the swing and it pass what is allowed.
    #[test]
    fn windows_end_as_the_phase_passes_half_a_turn() {
        let p = predicted(1.0);
        let mut e = Envelope::default();
        let amplitude = |k: u32| 0.25 + k as f32 / 512.0;
        let fault = (0..1000u32).find_map(|k| {
            let x = if k % 2 == 0 {
                amplitude(k)
            } else {
                -amplitude(k)
            };
            observe(&mut e, k, x, &p).map(|f| (k, f))
        });
        let Some((k, Fault::SwingOutgrown { growth, .. })) = fault else {
            panic!("{fault:?}");
        };
        let expected = (8..1000)
            .step_by(10)
            .find(|&end| amplitude(end) + 10.0 / 512.0 > 1.0)
            .unwrap();
        assert!(growth > 0.0, "said at a window's end");
        assert_eq!(k, expected);
        assert!(phase(k, 5) >= 1 << 31 && phase(k - 1, 5) < 1 << 31);
    }

    /// A swing that dies away (a ring decaying) never counts a growth.
    #[test]
    fn a_decaying_ring_is_no_growth() {
        let p = predicted(1.0);
        let mut e = Envelope::default();
        for k in 0..1000u32 {
            let amplitude = 0.99 * libm::expf(-(k as f32) / 200.0);
            let x = if k % 2 == 0 { amplitude } else { -amplitude };
            assert_eq!(observe(&mut e, k, x, &p), None, "tick {k}");
        }
    }

    /// An allowed half-span that is not a number passes nothing.
    #[test]
    fn nan_allowed_faults() {
        let p = predicted(f32::NAN);
        let mut e = Envelope::default();
        let first = observe(&mut e, 0, 2.0, &p);
        assert!(first.or(observe(&mut e, 1, 2.0, &p)).is_some());
    }
}
