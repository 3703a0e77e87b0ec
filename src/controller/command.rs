//! What an operator asks of a running controller (the command port): a new plan (target, AC,
//! settings) checked outside the tick like a boot, a stop, a trim now; and why one is
//! refused (`Refusal`). The tick never solves: `replan` hands out a `ReplanJob`, whose
//! `solve` (a low-priority task) runs every boot check from the present bias, and `adopt`
//! takes its result at a tick.

use core::fmt;

use super::fault::Fault;
use super::plan::Plan;
use super::settings::Settings;
use super::watch::Guard;
use super::{Boot, Controller, Phase, State};
use crate::acquire::InputNoise;
use crate::drive::{Amplifier, DacCode};
use crate::model::device::DeviceParams;

/// Why a request to a running controller was not done. The controller runs on as before.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// Not while the bias moves or a trim measures: ask again once it holds.
    Busy { phase: Phase },
    /// A fault holds the output at 0 V.
    Faulted { fault: Fault },
    /// The checks refused the new plan (out of range, above the cap, a setting...).
    Checks(Fault),
    /// No trim is set (`trim_tolerance`), or this build has none.
    NoTrim,
    /// Stopped at 0 V: a trim would switch the high voltage back on; a new plan (`target`)
    /// does that, by name.
    Stopped,
    /// Held below the cap (`Phase::Held`): the plant needs `needed_volts` (bias and AC) above
    /// `cap_volts`; a trim would measure at the cap and ask for the same. A new plan
    /// (`target`) or `stop` leaves it.
    Held { needed_volts: f32, cap_volts: f32 },
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::Busy { phase } => {
                write!(f, "busy ({}): ask again once the bias holds", phase.name())
            }
            Refusal::Faulted { fault } => {
                write!(f, "faulted, down to 0 V ({fault}): `clear` once there")
            }
            Refusal::Checks(fault) => write!(f, "{fault}"),
            Refusal::NoTrim => write!(
                f,
                "no trim: set trim_tolerance (in a build with the trim: every firmware build)"
            ),
            Refusal::Stopped => write!(
                f,
                "stopped at 0 V: a trim would switch the high voltage on; `target` drives"
            ),
            Refusal::Held {
                needed_volts,
                cap_volts,
            } => write!(
                f,
                "held below the cap: the plant needs {needed_volts:.1} V, the cap is \
                 {cap_volts:.1} V; `target` a reachable frequency, or `stop`"
            ),
        }
    }
}

/// A new plan to check outside the tick: every boot stage, from the present bias.
#[derive(Clone, Copy, Debug)]
pub struct ReplanJob {
    params: DeviceParams<f32>,
    amplifier: Amplifier,
    inputs: InputNoise,
    settings: Settings,
    /// The plan in force when the job was made: `adopt` takes the result only if it still is.
    plan: Plan,
    /// The swing the membrane may still carry from the drive in force, in stretch: the new
    /// plan's swing counts it, undecayed.
    carried_ring_stretch: f32,
}

/// A checked new plan, for `adopt`: what the boot stages left in a fresh controller (its
/// plan, settings, cap and state), not the controller itself: its 3 KB stay in the solve's
/// frame instead of travelling on through the command task's.
#[derive(Clone, Copy, Debug)]
pub struct Replanned {
    plan: Plan,
    settings: Settings,
    max_volts: f32,
    /// Its monitor's margins (the band about its bias, the voltage's raise) and predicted
    /// swing.
    guard: Guard,
    state: State,
    /// Whether the fresh plan holds the tuned bias (not a trim's probe bias).
    tuned: bool,
    /// What the trim expects of its first pulse's ring.
    #[cfg(feature = "trim")]
    ring: super::NextRing,
    boot: Boot,
    /// The plan in force when the job was made.
    was: Plan,
    /// The ring the job counted as carried into the new plan, in stretch.
    carried_ring_stretch: f32,
}

impl Replanned {
    /// What its boot checks found.
    pub fn boot(&self) -> &Boot {
        &self.boot
    }
}

impl ReplanJob {
    /// Every boot check for the new settings (`from_table`, `cross_check`, `check_plan`),
    /// the ramp starting at the present bias; long work, for a low-priority task.
    pub fn solve(&self, table: &[u8]) -> Result<Replanned, Refusal> {
        let mut slot = None;
        let (fresh, boot) = Controller::checks_in(
            &mut slot,
            self.params,
            table,
            (self.amplifier, self.inputs),
            self.settings,
            (self.plan.bias_volts, self.carried_ring_stretch),
        )
        .map_err(Refusal::Checks)?;
        Ok(Replanned {
            plan: fresh.plan,
            settings: fresh.settings,
            max_volts: fresh.max_volts,
            guard: fresh.watch.guard(),
            state: fresh.state,
            tuned: fresh.tuned(),
            carried_ring_stretch: self.carried_ring_stretch,
            #[cfg(feature = "trim")]
            ring: fresh.next_ring(),
            boot,
            was: self.plan,
        })
    }
}

impl Controller {
    /// The settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The voltage commanded at the last tick, V.
    pub fn last_volts(&self) -> f32 {
        self.last_volts
    }

    /// The DAC code sent at the last tick (`last_volts` is its voltage).
    pub fn last_code(&self) -> DacCode {
        self.last_code
    }

    /// Whether the bias holds still (no ramp, no trim under way): when a new plan may start.
    fn steady(&self) -> Result<(), Refusal> {
        match self.state {
            State::Holding {
                then_measure: false,
                ..
            }
            | State::Driving { .. }
            | State::Held { .. } => Ok(()),
            State::Faulted(fault) => Err(Refusal::Faulted { fault }),
            _ => Err(Refusal::Busy {
                phase: self.phase(),
            }),
        }
    }

    /// A job to check `settings` as a new plan from the present bias (the tick rate stays the
    /// one booted with: a new rate takes a new boot).
    pub fn replan(&self, settings: Settings) -> Result<ReplanJob, Refusal> {
        self.steady()?;
        Ok(ReplanJob {
            params: *self.flashed.params(),
            amplifier: self.amplifier,
            inputs: self.inputs,
            settings: Settings {
                tick_hz: self.settings.tick_hz,
                ..settings
            },
            plan: self.plan,
            carried_ring_stretch: self.watch.ring_to_carry_stretch(),
        })
    }

    /// Take a checked new plan from the next tick: the ramp from the present bias, then the
    /// hold and the AC. Its cap becomes the operator's (never above the ceiling fixed at
    /// boot); the cap in force is the lowest of that, the ceiling and the measured
    /// estimate's. Where the voltage last sent is above the new cap in force (an AC peak, a
    /// larger margin), the ramp starts there instead, the probe off until the bias: down at
    /// the slew rate before anything else. Refused if the plan changed since the job was
    /// made.
    pub fn adopt(&mut self, replanned: Replanned) -> Result<Boot, Refusal> {
        self.steady()?;
        // The plan changed, or a drive came on since the job was made (its ring is not in
        // the new plan's swing): the job is stale.
        let carried = self.watch.ring_to_carry_stretch();
        if self.plan != replanned.was || !(carried <= replanned.carried_ring_stretch) {
            return Err(Refusal::Busy {
                phase: self.phase(),
            });
        }
        let max_volts = self
            .ceiling_volts
            .min(replanned.max_volts)
            .min(self.estimate_volts);
        let mut plan = replanned.plan.delayed(self.tick);
        // From the bias the last tick sent (a ramp in force may not be done: a hold's, a
        // tracked drive's), never a jump to the job's start.
        plan.start_volts = self.plan.ramp_volts(self.tick.saturating_sub(1));
        plan.start_under(max_volts, self.last_volts);
        plan.check_range(replanned.plan.bias_volts, max_volts)
            .map_err(Refusal::Checks)?;
        plan.probe_off_above(max_volts);
        self.settings = replanned.settings;
        self.set_caps(replanned.max_volts, self.estimate_volts);
        let settings = &replanned.settings;
        let with_ac = settings.ac_volts > 0.0 && settings.ac_hz > 0.0;
        self.watch.guard_as(&replanned.guard, with_ac);
        self.plan = plan;
        self.state = replanned.state;
        #[cfg(feature = "trim")]
        {
            self.trim.restart(*self.flashed.params());
            self.trim.ring = replanned.ring;
        }
        self.set_tuned(replanned.tuned);
        Ok(Boot {
            max_volts: self.max_volts,
            ..replanned.boot
        })
    }

    /// Whether the output is at rest at 0 V: stopped (a plan of 0 V, its ramp over) or
    /// faulted with its descent over, and, after a dead bus dropped the command at once,
    /// long enough for the output to have followed at the slew rate. Not in a trim's pulse
    /// or an AC trough, which may command 0 V for a tick. What `clear` and `reset` wait for.
    pub fn at_rest(&self) -> bool {
        let resting = match self.state {
            State::Faulted(_) => true,
            State::Ramping { .. } | State::Holding { .. } => self.plan.bias_volts == 0.0,
            _ => false,
        };
        resting
            && self.last_volts == 0.0
            && self.plan.ramp_volts(self.tick) == 0.0
            && self.tick >= self.settled_from_tick
    }

    /// Ramp from the voltage now to 0 V at the slew rate, no AC, and hold there (always
    /// allowed: the voltage only falls; a trim under way is dropped).
    pub fn stop(&mut self) {
        if matches!(self.state, State::Faulted(_)) {
            return;
        }
        self.ramp_down(self.last_volts);
        self.drop_job();
        self.set_tuned(false);
        self.state = State::Ramping {
            then_measure: false,
        };
    }

    /// Measure the natural frequency and trim now (AC paused), as a periodic trim does.
    #[inline]
    pub fn trim_now(&mut self) -> Result<(), Refusal> {
        self.steady()?;
        if let State::Held { needed_volts } = self.state {
            return Err(Refusal::Held {
                needed_volts,
                cap_volts: self.max_volts,
            });
        }
        if !self.trim_wanted() {
            return Err(Refusal::NoTrim);
        }
        if !(self.plan.bias_volts > 0.0) {
            return Err(Refusal::Stopped);
        }
        #[cfg(feature = "trim")]
        {
            self.pause_for_trim(self.tick);
            Ok(())
        }
        #[cfg(not(feature = "trim"))]
        Err(Refusal::NoTrim)
    }
}
