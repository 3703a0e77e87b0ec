//! The plan: the voltage at every tick (ramp from a voltage to the bias, hold, with the
//! trim's pulse, then the AC drive), its range against [0, cap], and its run through the
//! model under the monitor (model.md §6).

use super::fault::Fault;
use super::settings::{Setting, Settings};
use crate::model::device::Device;
use crate::model::motion::{Drive, Integrator, Method, State, StepError};
use crate::model::safety::Monitor;
use crate::numerics::real::sin_cos_turns;

/// The longest plan, in ticks (about 18 hours at 1 kHz before the AC starts).
pub const MAX_PLAN_TICKS: f32 = 6.4e7;

/// The plan: ramp from a voltage to the bias, hold (with the trim's pulse, if any), then the
/// AC drive; the voltage at every tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plan {
    /// Where the ramp starts: the tick and the voltage there.
    pub start_tick: u32,
    pub start_volts: f32,
    pub bias_volts: f32,
    /// Bias step per tick on the ramp (up or down), V.
    pub ramp_volts_per_tick: f32,
    /// Ticks [from, to) at which the voltage drops by `pulse_volts` (the trim's ping; a drop
    /// is always toward safety).
    pub pulse_ticks: (u32, u32),
    pub pulse_volts: f32,
    /// The tick at which the AC starts (`None`: not yet, as while a trim measures).
    pub ac_tick: Option<u32>,
    pub ac_volts: f32,
    /// AC phase advance per tick, in units of 2π/2³²: the phase is an exact integer, so it
    /// neither drifts nor loses precision however long the drive runs.
    pub ac_phase_step: u32,
    /// The AC's phase at `ac_tick` (a tracked drive changes its frequency there, in phase).
    pub ac_phase_start: u32,
    /// The amplifier's lag at the drive's frequency, in the same units: the output's phase
    /// is the command's less it (`Settings::amplifier_lag`; a tracked drive's at the target
    /// it holds the resonance on: off it, by the lag's change between, until it settles).
    /// A tracker reads the motion against the output.
    pub ac_lag_phase: u32,
    /// The amplifier's gain there (`Settings::amplifier_gain`): the AC at its output is
    /// `ac_volts` times it, the force a tracker fits its Q with.
    pub ac_gain: f32,
    /// The self-sensing probe (`crate::estimate::capacitance`): ±`probe_volts` on the ramp wherever the ramp
    /// is at least that high, its sign flipping every `probe_half_ticks` ticks (0: none).
    pub probe_volts: f32,
    pub probe_half_ticks: u32,
}

/// The AC's phase advance per tick for `hz` at `tick_hz`, in units of 2π/2³².
pub(super) fn phase_step(hz: f32, tick_hz: f32) -> u32 {
    ((hz / tick_hz) as f64 * 4_294_967_296.0) as u32
}

impl Plan {
    /// No voltage at all (before a plan is made).
    pub(super) const fn idle() -> Self {
        Self {
            start_tick: 0,
            start_volts: 0.0,
            bias_volts: 0.0,
            ramp_volts_per_tick: 0.0,
            pulse_ticks: (0, 0),
            pulse_volts: 0.0,
            ac_tick: None,
            ac_volts: 0.0,
            ac_phase_step: 0,
            ac_phase_start: 0,
            ac_lag_phase: 0,
            ac_gain: 1.0,
            probe_volts: 0.0,
            probe_half_ticks: 0,
        }
    }

    /// A ramp from `from_volts` at tick 0 to `bias_volts` at the settings' slew rate, the
    /// hold, and (when `drive`, else later) the AC; with the ticks up to the end of its model
    /// check.
    pub(super) fn ramp(
        s: &Settings,
        from_volts: f32,
        bias_volts: f32,
        drive: bool,
    ) -> Result<(Self, u32), Fault> {
        let ramp_ticks = (bias_volts - from_volts).abs() / s.slew_volts_per_second * s.tick_hz;
        let ac_tick = libm::ceilf(ramp_ticks) + s.settle_seconds * s.tick_hz;
        let check_ticks = s.check_seconds * s.tick_hz;
        if !(ac_tick + check_ticks < MAX_PLAN_TICKS) {
            // Name the part that makes the plan too long: the ramp, the hold or the check.
            let settle_ticks = s.settle_seconds * s.tick_hz;
            let (setting, value) = if check_ticks >= ramp_ticks.max(settle_ticks) {
                (Setting::CheckSeconds, s.check_seconds)
            } else if settle_ticks >= ramp_ticks {
                (Setting::SettleSeconds, s.settle_seconds)
            } else {
                (Setting::SlewVoltsPerSecond, s.slew_volts_per_second)
            };
            return Err(Fault::Setting { setting, value });
        }
        // The drive's frequency for the amplifier's lag and gain: a tracked drive's target.
        let drive_hz = match s.track_seconds {
            Some(_) => s.target_hz,
            None => s.ac_hz,
        };
        let plan = Plan {
            start_tick: 0,
            start_volts: from_volts,
            bias_volts,
            ramp_volts_per_tick: s.slew_volts_per_second / s.tick_hz,
            pulse_ticks: (0, 0),
            pulse_volts: 0.0,
            ac_tick: drive.then_some(ac_tick as u32),
            ac_volts: if s.ac_hz > 0.0 { s.ac_volts } else { 0.0 },
            ac_phase_step: phase_step(s.ac_hz, s.tick_hz),
            ac_phase_start: 0,
            ac_lag_phase: (s.amplifier_lag(drive_hz) / core::f32::consts::TAU * 4_294_967_296.0)
                as u32,
            ac_gain: s.amplifier_gain(drive_hz),
            probe_volts: s.probe_volts.unwrap_or(0.0),
            probe_half_ticks: match s.probe_volts {
                Some(_) if cfg!(feature = "probe") => s.probe_half_ticks()?,
                _ => 0,
            },
        };
        Ok((plan, ac_tick as u32 + check_ticks as u32 + 1))
    }

    /// The same plan `ticks` later (a plan made at tick 0, started at tick `ticks`).
    pub(super) fn delayed(self, ticks: u32) -> Self {
        let (from, to) = self.pulse_ticks;
        Self {
            start_tick: self.start_tick.saturating_add(ticks),
            pulse_ticks: (from.saturating_add(ticks), to.saturating_add(ticks)),
            ac_tick: self.ac_tick.map(|at| at.saturating_add(ticks)),
            ..self
        }
    }

    /// The ramp's voltage at tick `k` (the bias once it is reached).
    pub fn ramp_volts(&self, k: u32) -> f32 {
        let step = self.ramp_volts_per_tick * k.saturating_sub(self.start_tick) as f32;
        if self.bias_volts >= self.start_volts {
            (self.start_volts + step).min(self.bias_volts)
        } else {
            (self.start_volts - step).max(self.bias_volts)
        }
    }

    /// The AC's phase at tick `k`, in units of 2π/2³² (0 before the AC starts).
    pub fn phase(&self, k: u32) -> u32 {
        match self.ac_tick {
            Some(from) if k >= from => (k - from)
                .wrapping_mul(self.ac_phase_step)
                .wrapping_add(self.ac_phase_start),
            _ => 0,
        }
    }

    /// The voltage at tick `k`: the AC rides on the ramp (a tracked drive's bias moves with
    /// the drive on), and the probe on both.
    pub fn volts(&self, k: u32) -> f32 {
        self.volts_at(k, self.phase(k))
    }

    /// As `volts`, the AC's phase at `k` given (`phase(k)`: the tick works it out once for
    /// the voltage and the swing's watch).
    pub fn volts_at(&self, k: u32, phase: u32) -> f32 {
        let ramp = self.ramp_volts(k);
        let probe = match self.probe_positive(k, ramp) {
            Some(true) => self.probe_volts,
            Some(false) => -self.probe_volts,
            None => 0.0,
        };
        match self.ac_tick {
            Some(from) if k >= from => ramp + self.ac_volts * sin_cos_turns(phase).0 + probe,
            _ => {
                let (from, to) = self.pulse_ticks;
                if k >= from && k < to {
                    (ramp - self.pulse_volts).max(0.0)
                } else {
                    ramp + probe
                }
            }
        }
    }

    /// The probe's sign at tick `k` on a ramp at `ramp_volts` (`None`: no probe then).
    pub fn probe_positive(&self, k: u32, ramp_volts: f32) -> Option<bool> {
        let half = self.probe_half_ticks;
        // Without the feature no plan has a probe (`Settings::check`): none in the code.
        let on = cfg!(feature = "probe")
            && half > 0
            && self.probe_volts > 0.0
            && ramp_volts >= self.probe_volts;
        on.then(|| (k / half).is_multiple_of(2))
    }

    /// A new plan under a cap `max_volts` that may have just been lowered, the voltage last
    /// sent `last_volts`: where the ramp's start or the voltage sent is above the cap, the
    /// ramp starts from the voltage sent (down at the slew rate from there, never up from
    /// it). Check its range next (`check_range`, the probe counted: it rides again at the
    /// bias), then `probe_off_above`.
    pub(super) fn start_under(&mut self, max_volts: f32, last_volts: f32) {
        if !(self.start_volts <= max_volts && last_volts <= max_volts) {
            self.start_volts = last_volts;
        }
    }

    /// The probe off on a ramp whose top with the probe would pass `max_volts` (a ramp down
    /// from above a cap since lowered): the controller sets it back at the bias, where
    /// `check_range` has made sure it fits.
    pub(super) fn probe_off_above(&mut self, max_volts: f32) {
        let top = self.start_volts.max(self.bias_volts);
        if !(top + self.probe_volts <= max_volts) {
            self.probe_volts = 0.0;
        }
    }

    /// The probe of `probe_volts` back on at the bias (after a trim's window, at the end of a
    /// way down it was off for), where the bias, the AC and it fit under `max_volts`: `Ok`.
    /// Otherwise it stays off and a `Setting` fault names it (`check_range` made sure it fits
    /// on every path planned: this keeps the final gate from being the one to say no where a
    /// path was not, and a sensorless drive from going on without the probe it reads).
    pub(super) fn probe_back(&mut self, probe_volts: f32, max_volts: f32) -> Result<(), Fault> {
        // No probe asked for: nothing comes back, whatever the cap (a cap below the bias is
        // the way down's business, not the probe's).
        let swing = self.ac_volts + probe_volts;
        if !(probe_volts > 0.0) || self.bias_volts + swing <= max_volts {
            self.probe_volts = probe_volts;
            Ok(())
        } else {
            self.probe_volts = 0.0;
            Err(Fault::Swing {
                setting: Setting::ProbeVolts,
                value: probe_volts,
                low_volts: self.bias_volts - swing,
                high_volts: self.bias_volts + swing,
                max_volts,
            })
        }
    }

    /// The most the voltage swings about the bias: the AC and the probe, V.
    pub fn swing_volts(&self) -> f32 {
        self.ac_volts + self.probe_volts
    }

    /// The whole voltage range against [0, `max_volts`], before anything is driven: the ramp
    /// and the bias below the cap (else `AboveSafe`; a ramp may start above it when it comes
    /// down, from a voltage already sent to a cap since lowered), and the AC and the probe about the bias
    /// they will ride on (`ac_bias_volts`: the tuned bias, also while a trim probes lower)
    /// neither below 0 V (the amplifier is unipolar) nor above the cap (else a `Setting`
    /// fault naming the AC amplitude, or the probe's if the AC alone fits).
    pub(super) fn check_range(&self, ac_bias_volts: f32, max_volts: f32) -> Result<(), Fault> {
        let descends = self.start_volts > self.bias_volts;
        let bias_peak = if descends {
            self.bias_volts
        } else {
            self.start_volts.max(self.bias_volts)
        };
        if !(bias_peak <= max_volts && self.bias_volts >= 0.0) {
            return Err(Fault::AboveSafe {
                volts: bias_peak,
                max_volts,
            });
        }
        let fits = |setting: Setting, value: f32, swing: f32| {
            let (low_volts, high_volts) = (
                ac_bias_volts - swing,
                ac_bias_volts.max(self.bias_volts) + swing,
            );
            if low_volts >= 0.0 && high_volts <= max_volts {
                Ok(())
            } else {
                Err(Fault::Swing {
                    setting,
                    value,
                    low_volts,
                    high_volts,
                    max_volts,
                })
            }
        };
        fits(Setting::AcVolts, self.ac_volts, self.ac_volts)?;
        fits(Setting::ProbeVolts, self.probe_volts, self.swing_volts())
    }

    /// Run the plan through the model (RK4, f32, one step a tick, subdivided for stability)
    /// from rest at `start_stretch` (the equilibrium at the plan's first voltage), with the
    /// monitor at every tick, for `ticks` ticks. The stretch range swept, or the crossing.
    pub(super) fn run_in_model(
        &self,
        device: &Device<f32>,
        tick_hz: f32,
        ticks: u32,
        start_stretch: f32,
    ) -> Result<(f32, f32), Fault> {
        let start = State {
            stretch: start_stretch,
            velocity: 0.0,
        };
        // A tick the model cannot step stably, even in substeps, is too slow for this
        // device: the setting is at fault, not the plan.
        let mut model = Integrator::new(
            *device,
            Drive::constant(device, 0.0),
            Method::Rk4,
            1.0 / tick_hz,
            device.model_range(),
            start,
            true,
        )
        .map_err(|e| match e {
            StepError::Unstable { .. } | StepError::InvalidStep { .. } => Fault::Setting {
                setting: Setting::TickHz,
                value: tick_hz,
            },
            e => Fault::PlanFailed(e),
        })?;
        let mut monitor = Monitor::new();
        let (mut low, mut high) = (f32::INFINITY, f32::NEG_INFINITY);
        for k in 0..ticks {
            let volts = self.volts(k);
            let p = volts / device.volts_per_unit();
            let stretch = model.state().stretch;
            if let Some(mode) = monitor.observe(device, u64::from(k), stretch, p * p) {
                return Err(Fault::PlanCrosses {
                    mode,
                    seconds: k as f32 / tick_hz,
                });
            }
            low = low.min(stretch);
            high = high.max(stretch);
            model
                .set_drive(Drive::constant(device, volts))
                .map_err(Fault::PlanFailed)?;
            model.step().map_err(Fault::PlanFailed)?;
        }
        Ok((low, high))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plan from 3 kV to 4 kV with a 20 V probe, made by `ramp` at the default settings.
    fn probed(from_volts: f32, bias_volts: f32) -> Plan {
        let s = Settings {
            probe_volts: Some(20.0),
            ..Settings::for_target(44.0)
        };
        let (mut plan, _) = Plan::ramp(&s, from_volts, bias_volts, true)
            .unwrap_or_else(|_| unreachable!("the default settings make a plan"));
        plan.probe_volts = 20.0;
        plan
    }

    /// `start_under` then `probe_off_above`, as the controller calls them around its check.
    fn under(mut plan: Plan, max_volts: f32, last_volts: f32) -> Plan {
        plan.start_under(max_volts, last_volts);
        plan.probe_off_above(max_volts);
        plan
    }

    /// Under a cap it fits (ramp top 4 kV + 20 V ≤ 4.02 kV, to the volt), the plan is left as
    /// made; from a voltage sent above a lowered cap, the ramp starts there and the probe is
    /// off (5 kV + 20 V past 4.99 kV); a start above the cap from a plan made before (the
    /// voltage sent under it) starts from the voltage sent too.
    #[test]
    fn a_plan_under_a_lowered_cap_starts_from_the_voltage_sent_without_the_probe() {
        let fits = under(probed(3000.0, 4000.0), 4020.0, 3000.0);
        assert_eq!((fits.start_volts, fits.probe_volts), (3000.0, 20.0));
        let one_over = under(probed(3000.0, 4000.0), 4019.0, 3000.0);
        assert_eq!((one_over.start_volts, one_over.probe_volts), (3000.0, 0.0));
        let sent_above = under(probed(3000.0, 4000.0), 4990.0, 5000.0);
        assert_eq!(
            (sent_above.start_volts, sent_above.probe_volts),
            (5000.0, 0.0)
        );
        let start_above = under(probed(5000.0, 4000.0), 4990.0, 4500.0);
        assert_eq!(
            (start_above.start_volts, start_above.probe_volts),
            (4500.0, 20.0)
        );
    }

    /// The probe comes back where bias + AC + probe fits the cap (4000 + 30 + 20 V ≤ 4050 V),
    /// not a volt under it (a bias held at the cap has no room for it): a fault naming it.
    #[test]
    fn the_probe_comes_back_only_where_it_fits() {
        let mut plan = probed(3000.0, 4000.0);
        plan.ac_volts = 30.0;
        assert_eq!(plan.probe_back(20.0, 4050.0), Ok(()));
        assert_eq!(plan.probe_volts, 20.0);
        assert_eq!(
            plan.probe_back(20.0, 4049.0),
            Err(Fault::Swing {
                setting: Setting::ProbeVolts,
                value: 20.0,
                low_volts: 3950.0,
                high_volts: 4050.0,
                max_volts: 4049.0
            })
        );
        assert_eq!(plan.probe_volts, 0.0);
        // No probe asked for: nothing to bring back, whatever the cap (found by the fuzz test:
        // tampered results had lowered the cap below zero).
        assert_eq!(plan.probe_back(0.0, 4030.0), Ok(()));
        assert_eq!(plan.probe_back(0.0, -1.0), Ok(()));
        assert_eq!(plan.probe_volts, 0.0);
    }
}
