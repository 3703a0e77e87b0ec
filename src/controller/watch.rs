//! The checks on what the controller measures each tick (`Inputs`, from `acquire`): the stretch
//! sample (a number, one a device could give, not stuck, inside model.md §6) and the
//! amplifier's monitored output against the last command.

use super::envelope::{Envelope, Predicted};
use super::fault::Fault;
pub use crate::acquire::Inputs;
use crate::model::device::Device;
use crate::model::safety::{FailureMode, Monitor, StretchBand};

/// Ticks in a row the amplifier may be off its command before it is a fault (its bandwidth
/// and slew limit lag a step by a tick or two).
pub const AMPLIFIER_TICKS: u32 = 3;

impl Ring {
    /// What the trim records this tick: the stretch when there is one, else the current.
    pub(super) fn of(inputs: &Inputs) -> Ring {
        match (inputs.stretch, inputs.current_amps) {
            (Some(stretch), _) => Ring::Stretch(stretch),
            (None, Some(amps)) => Ring::Current(amps),
            (None, None) => Ring::Nothing,
        }
    }
}

/// A sample of the ring the trim measures.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(feature = "trim"), allow(dead_code))]
pub(super) enum Ring {
    Stretch(f32),
    /// The current carries C·dΦ/dt too: the trim skips it while the pulse's step settles.
    Current(f32),
    Nothing,
}

/// The leakage watch's window, s: long enough that the AC drive and the ring average out of
/// the current (whole periods but a fraction), short against a leakage that falls over
/// seconds.
pub const LEAKAGE_WINDOW_SECONDS: f32 = 1.0;

/// The leakage watch's sums over its window at a steady bias (model.md §8): the current's
/// DC part against the voltage is the leakage conductance.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Leakage {
    ticks: u32,
    amps: f32,
    volts: f32,
    /// The current summed over the part of the window being summed, and the parts' means'
    /// sum and sum of squares: the scatter of the window's mean (the AC and the ring average
    /// out of each part, the noise does not).
    part_amps: f32,
    parts_mean: f32,
    parts_mean_squared: f32,
    /// The last window's conductance and its standard error, S.
    previous: Option<(f32, f32)>,
}

/// Parts of a window whose means give its scatter.
const PARTS: u32 = 10;

/// What the leakage watch tests at each window's end.
#[derive(Clone, Copy, Debug)]
pub(super) struct LeakageLimits {
    pub(super) window_ticks: u32,
    pub(super) floor_ohms: Option<f32>,
    /// Largest R_previous/R − 1 from one window to the next (the fall a second times the
    /// window).
    pub(super) fall: Option<f32>,
}

/// How far a fall must stand out of the windows' scatter (standard errors) to count.
const FALL_SIGNIFICANCE: f32 = 3.0;

impl Leakage {
    /// The last window's leakage conductance, S, if one is measured.
    pub(super) fn siemens(&self) -> Option<f32> {
        self.previous.map(|(siemens, _)| siemens)
    }

    /// A tick's current under `volts` (the command the current flowed under); at the window's
    /// end, the leakage resistance against the floor (below is a fault) and against the last
    /// window's (a fall faster than allowed, beyond the scatter, is a fault).
    pub(super) fn observe(
        &mut self,
        amps: f32,
        volts: f32,
        limits: LeakageLimits,
    ) -> Option<Fault> {
        self.ticks += 1;
        self.amps += amps;
        self.volts += volts;
        self.part_amps += amps;
        let part_ticks = (limits.window_ticks / PARTS).max(1);
        if self.ticks.is_multiple_of(part_ticks) {
            let mean = self.part_amps / part_ticks as f32;
            self.parts_mean += mean;
            self.parts_mean_squared += mean * mean;
            self.part_amps = 0.0;
        }
        if self.ticks < limits.window_ticks {
            return None;
        }
        let n = self.ticks as f32;
        let (amps, volts) = (self.amps, self.volts);
        let mean_amps = amps / n;
        let parts = (self.ticks / part_ticks).max(1) as f32;
        let part_mean = self.parts_mean / parts;
        let variance = (self.parts_mean_squared / parts - part_mean * part_mean).max(0.0);
        let spread_amps = libm::sqrtf(variance / parts);
        let previous = self.previous;
        *self = Leakage::default();
        if !(volts > 0.0) {
            return None;
        }
        // Σi/ΣΦ is the conductance; compared without dividing (Σi may be 0 or negative).
        if let Some(floor_ohms) = limits.floor_ohms {
            if amps * floor_ohms > volts {
                return Some(Fault::Leakage {
                    ohms: volts / amps,
                    floor_ohms,
                });
            }
        }
        let mean_volts = volts / n;
        let (siemens, spread) = (mean_amps / mean_volts, spread_amps / mean_volts);
        self.previous = Some((siemens, spread));
        let (fall, (was, was_spread)) = limits.fall.zip(previous)?;
        let resolved = was > FALL_SIGNIFICANCE * was_spread;
        let beyond_scatter = siemens - was > FALL_SIGNIFICANCE * (spread + was_spread);
        (resolved && beyond_scatter && siemens > was * (1.0 + fall)).then_some(
            Fault::LeakageFalling {
                ohms: 1.0 / siemens,
                previous_ohms: 1.0 / was,
            },
        )
    }
}

/// What a plan's checks set for the watch (`Watch::guard`), without its memory: what a
/// replan hands over.
#[derive(Clone, Copy, Debug)]
pub(super) struct Guard {
    band: StretchBand<f32>,
    raise: f32,
    predicted: Predicted,
}

/// The watch's memory between ticks.
#[derive(Clone, Copy, Debug)]
pub(super) struct Watch {
    monitor: Monitor<f32>,
    /// The stretches B's tensions and the Gent lock-up allow about the plan's tuned bias,
    /// narrowed by the margin (the direct solve's boot stage sets it): the margin on the
    /// checks no voltage enters.
    pub(super) band: StretchBand<f32>,
    /// 1/(1 − margin): the voltage the checks run under, over the tick's.
    raise: f32,
    /// The last stretch sample and how many times in a row it came (bit for bit).
    repeated: Option<(f32, u32)>,
    /// Ticks in a row the amplifier has been off its command.
    amplifier_off_ticks: u32,
    /// The swing the drive of the plan in force is predicted to have (`Predicted::NONE`: no
    /// AC), and the swing measured while it is on.
    predicted: Predicted,
    envelope: Envelope,
    /// The most any drive so far was allowed to swing, in stretch (`ring_to_carry_stretch`).
    carried_stretch: f32,
}

impl Watch {
    /// A watch for the settings' `margin`, with no band yet.
    pub(super) fn new(margin: f32) -> Self {
        Self {
            monitor: Monitor::new(),
            band: StretchBand::everywhere(),
            raise: 1.0 / (1.0 - margin),
            repeated: None,
            amplifier_off_ticks: 0,
            predicted: Predicted::NONE,
            envelope: Envelope::default(),
            carried_stretch: 0.0,
        }
    }

    /// A stretch sample at tick `k` under `volts`: a number (`Sensor`), one a device could
    /// give (`SensorImplausible`), not the same `stuck_samples` times in a row (`SensorStuck`;
    /// `None`: no such check), and inside model.md §6 for the device flashed and for the
    /// trim's estimate, if any, with whether it is the flashed device but for μ, under the
    /// voltage raised by 1/(1 − `margin`): a failure there is `NearLimit` (the motion is
    /// taken off before the limit), or `Limit` where it fails at the voltage itself too (a
    /// state outside the model is loss of tension 1).
    /// Outside the band (the stretches B's tensions and the lock-up allow, narrowed by the
    /// margin) is `NearLimit` too, or `Limit` where such a check fails at the sample.
    pub(super) fn stretch(
        &mut self,
        k: u32,
        stretch: f32,
        volts: f32,
        flashed: &Device<f32>,
        estimate: Option<(&Device<f32>, bool)>,
        stuck_samples: Option<u32>,
    ) -> Option<Fault> {
        if !stretch.is_finite() {
            return Some(Fault::Sensor { value: stretch });
        }
        let (low, high) = flashed.plausible_stretch();
        if !(stretch > low && stretch < high) {
            return Some(Fault::SensorImplausible {
                value: stretch,
                low,
                high,
            });
        }
        let count = match self.repeated {
            Some((last, n)) if last.to_bits() == stretch.to_bits() => n.saturating_add(1),
            _ => 1,
        };
        self.repeated = Some((stretch, count));
        if stuck_samples.is_some_and(|limit| count >= limit) {
            return Some(Fault::SensorStuck {
                samples: count,
                value: stretch,
            });
        }
        let tick = u64::from(k);
        let terms = flashed.stretch_terms(stretch);
        let within_margin = |at_limit: Option<FailureMode>, mode| match at_limit {
            Some(mode) => Fault::Limit { mode, tick: k },
            None => Fault::NearLimit {
                mode,
                tick: k,
                stretch,
                volts,
            },
        };
        if let Some(mode) = self.band.outside(stretch) {
            return Some(within_margin(terms.stretch_only_failure(), mode));
        }
        // The checks under the raised voltage; passing there, they pass under the voltage
        // itself. Every margin but the Hessian's is a term less Φ̄² times a positive
        // factor. The Hessian's d11 falls with Φ̄², and its determinant is a parabola in Φ̄²
        // opening downward (the bias term's is −3·λ1²·λ2²), positive at Φ̄² = 0: the elastic
        // energy is convex in (λ1, λ2) wherever the model is defined (I1 is convex on the
        // positive quadrant, Gent's energy increasing and convex in I1), so the Hessian
        // passes on an interval of Φ̄² from 0. Past the Gent pole nothing passes.
        let near = volts * self.raise;
        if let Some((device, true)) = estimate {
            // Both pass: one device's checks (`StretchTerms::both_pass`). Otherwise each in
            // turn below, which says the first that fails as it always has.
            let of = |d: &Device<f32>| {
                let p = near / d.volts_per_unit();
                (p * p, d.breakdown_field_dimless())
            };
            let (f, e) = (of(flashed), of(device));
            let (larger, smaller) = if e.0 > f.0 { (e, f) } else { (f, e) };
            if terms.both_pass(larger, smaller) {
                return None;
            }
        }
        for (device, shares) in core::iter::once((flashed, true)).chain(estimate) {
            // The trim's estimate is the device flashed with another μ: the stretch's terms
            // are the same (the tick's budget: they are most of the checks' work).
            let own;
            let terms = if shares {
                &terms
            } else {
                own = device.stretch_terms(stretch);
                &own
            };
            let breakdown = device.breakdown_field_dimless();
            let p = near / device.volts_per_unit();
            if let Some(mode) = terms.first_failure(p * p, breakdown) {
                let p = volts / device.volts_per_unit();
                let at_limit = self.monitor.observe_terms(terms, tick, p * p, breakdown);
                return Some(within_margin(at_limit, mode));
            }
        }
        None
    }

    /// What a plan's checks set for the watch: its band, raise and predicted swing.
    pub(super) fn guard(&self) -> Guard {
        Guard {
            band: self.band,
            raise: self.raise,
            predicted: self.predicted,
        }
    }

    /// The guard of another plan (an adopted replan's); the sample history stays. A plan
    /// without AC (`with_ac` false) carries no drive's ring on (its ring decaying then is
    /// not counted: docs/safety.md); one whose AC waits for a trim's Q does.
    pub(super) fn guard_as(&mut self, guard: &Guard, with_ac: bool) {
        self.band = guard.band;
        self.raise = guard.raise;
        self.predicted = guard.predicted;
        if !with_ac {
            self.carried_stretch = 0.0;
        }
    }

    /// The drive's swing at tick `k`, the drive's phase `phase` (`Envelope`): the stretch
    /// sample against the prediction.
    pub(super) fn swing(&mut self, k: u32, phase: u32, stretch: f32) -> Option<Fault> {
        if self.envelope.within(phase, stretch, &self.predicted) {
            return None;
        }
        Some(self.envelope.outgrown(k, &self.predicted))
    }

    /// The swing the next drive is predicted to have (`None`: no AC: `Predicted::NONE`, with
    /// which a drive faults at its second sample). One that allows a
    /// half-span that is not a finite number (a result from outside the tick that lies) is
    /// kept as NaN: the drive faults at its first sample rather than go unwatched.
    pub(super) fn predict(&mut self, predicted: Option<Predicted>) {
        self.predicted = match predicted {
            Some(p) if p.allowed.is_finite() => p,
            Some(p) => Predicted {
                allowed: f32::NAN,
                ..p
            },
            None => Predicted::NONE,
        };
    }

    /// A drive (re)started: its swing is measured afresh, and the membrane may carry as much
    /// as it is allowed into any plan after it.
    pub(super) fn drive_on(&mut self) {
        self.envelope = Envelope::default();
        self.carried_stretch = self.carried_stretch.max(self.predicted.allowed);
    }

    /// The swing a new plan may find the membrane in, in stretch: the most any drive since
    /// the last plan without AC was allowed (its ring outlasts the AC: a pause, a hold,
    /// `stop`), undecayed; 0 before any drive.
    pub(super) fn ring_to_carry_stretch(&self) -> f32 {
        self.carried_stretch
    }

    /// A current sample must be a number (`Sensor`); its size is the plant's business.
    pub(super) fn current(measured: Option<f32>) -> Option<Fault> {
        let measured = measured?;
        (!measured.is_finite()).then_some(Fault::Sensor { value: measured })
    }

    /// The amplifier's monitored output against the last command: off by more than
    /// `tolerance_volts` for more than `AMPLIFIER_TICKS` ticks in a row is a fault.
    pub(super) fn amplifier(
        &mut self,
        measured: Option<f32>,
        commanded_volts: f32,
        tolerance_volts: f32,
    ) -> Option<Fault> {
        let measured = measured?;
        if !measured.is_finite() {
            return Some(Fault::Sensor { value: measured });
        }
        if (measured - commanded_volts).abs() <= tolerance_volts {
            self.amplifier_off_ticks = 0;
            return None;
        }
        self.amplifier_off_ticks += 1;
        (self.amplifier_off_ticks > AMPLIFIER_TICKS).then_some(Fault::AmplifierDisagrees {
            commanded_volts,
            measured_volts: measured,
        })
    }
}
