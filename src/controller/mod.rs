//! The resonator's controller, sans IO: the same code on the chip and in host-sim.
//!
//! `Controller::start` checks everything before anything is driven, in three stages a
//! firmware can also take one by one (leaving out, and not linking, what it does not need):
//! - `from_table`: the device parameters, the settings, the tuning table (CRC, order, made
//!   for this device); the bias for the target from the table, and commands capped below the
//!   table's top, which its maker put at (1 − margin)·limit;
//! - `cross_check`: the limit and the bias by the core's direct solve on the chip (model.md
//!   §6–§7), which must agree with the table; the cap becomes (1 − margin)·limit;
//! - `check_plan`: the whole plan (ramp at a bounded slew rate, hold, AC drive) run through
//!   the fixed-step model under the safety monitor (model.md §6).
//!
//! Then `tick`, at a fixed rate, gives the DAC code for that tick; every code passes one
//! final check (`gate`). The cap in force is the lowest of three: the ceiling fixed at boot
//! from the device flashed, at most (1 − margin)·Φlimit; the cap of the operator's plan in
//! force (a replan sets it, never above the ceiling); and the measured estimate's (a trim's
//! or tracking's result may lower it, never raise it). A plan above a cap just lowered comes
//! down to it at the slew rate first. A fault of any kind brings the output down from the
//! voltage last sent to 0 V at the slew rate (at once on a dead bus), whatever the cap,
//! never up; holds it there, and says what happened once. The tick never solves: a trim's
//! solve is handed out (`trim_job`) and its result given back (`trim_done`), taken only if
//! it answers the job still wanted.
//!
//! One idea a module: `settings` (what is asked, and its checks), `fault` (`Fault`, `Event`,
//! `Output`), `plan` (the voltage at every tick, its range, its model run), `boot` (the
//! stages), `watch` (sensor and amplifier checks), `gate` (the final check), `trim`
//! (request and response).

mod boot;
mod command;
mod envelope;
mod event;
mod fault;
mod gate;
mod plan;
#[cfg(feature = "probe")]
mod sensing;
mod settings;
#[cfg(feature = "track")]
mod tracking;
#[cfg(feature = "trim")]
mod trim;
mod watch;

pub use boot::{Boot, CapBy};
pub use command::{Refusal, ReplanJob, Replanned};
pub use envelope::Predicted;
pub use event::{Event, EventKind, Output, BUS_FAULT_SAID, EVENT_VALUES, FAULT_SAID};
pub use fault::{Fault, FaultStage, Figures, FAULT_KEYS};
pub use plan::{Plan, MAX_PLAN_TICKS};
pub use settings::{Held, Setting, SettingSet, Settings, F32_GUARD, MAX_TRIMS, TRIM_SECANT_STEP};
#[cfg(feature = "trim")]
pub use trim::{Ceiling, NextRing, TrimDone, TrimJob, TrimResult};
pub use watch::{Inputs, AMPLIFIER_TICKS, LEAKAGE_WINDOW_SECONDS};

use crate::acquire::{InputError, InputNoise};
use crate::drive::{Amplifier, DacCode};
#[cfg(feature = "trim")]
use crate::estimate::ring::RingInput;
use crate::estimate::ring::RingQuality;
use crate::model::device::Device;
use gate::gate;
use watch::{Leakage, LeakageLimits, Ring, Watch};

/// Where the controller is, for people and tests (the state without its data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    Ramping,
    Holding,
    /// The trim's pulse and the ring after it, measured.
    Measuring,
    /// The ring is measured; the bias holds while the trim's job is solved outside the tick.
    Solving,
    Driving,
    /// The plant needs a bias and AC above the cap in force (the trim's or tracking's
    /// estimate), or a lowered cap left the plan above it: the bias holds at or under the
    /// cap, no AC, no further trim (said once by `Event::AboveCeiling`).
    Held,
    Faulted,
}

impl Phase {
    /// The phase's name, as the command port's `status` says it.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Ramping => "ramping",
            Phase::Holding => "holding",
            Phase::Measuring => "measuring",
            Phase::Solving => "solving",
            Phase::Driving => "driving",
            Phase::Held => "held",
            Phase::Faulted => "faulted",
        }
    }
}

/// Every phase, in order: a phase's byte in the link's and the stream's records is its place.
const PHASES: [Phase; 7] = [
    Phase::Ramping,
    Phase::Holding,
    Phase::Measuring,
    Phase::Solving,
    Phase::Driving,
    Phase::Held,
    Phase::Faulted,
];

/// A phase as one byte: its place in `Phase`'s order, 0xFF for none (no controller). The
/// link's and the telemetry stream's records both carry it so.
pub(crate) fn phase_byte(phase: Option<Phase>) -> u8 {
    phase
        .and_then(|p| PHASES.iter().position(|&q| q == p))
        .map_or(0xFF, |i| i as u8)
}

/// The phase of `phase_byte`'s byte (`None`: no phase has it).
pub(crate) fn phase_of_byte(byte: u8) -> Option<Option<Phase>> {
    match byte {
        0xFF => Some(None),
        i => PHASES.get(usize::from(i)).copied().map(Some),
    }
}

/// Where the controller is, with what each place needs.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(feature = "trim"), allow(dead_code))]
enum State {
    /// On the ramp to the plan's bias; then hold, then measure (a trim) or drive.
    Ramping { then_measure: bool },
    /// At the bias until tick `until`; then measure, or drive once the AC's tick comes.
    Holding { until: u32, then_measure: bool },
    /// Recording the ring after the trim's pulse.
    Measuring,
    /// The window is full: its job is out, the bias holds until the result comes back.
    Solving,
    /// The AC drive on, until the next trim (none: `None`).
    Driving { next_trim: Option<u32> },
    /// The trim needs `needed_volts` (bias and AC) above the ceiling: the bias holds.
    Held { needed_volts: f32 },
    /// For this fault (the first): down the plan's ramp to 0 V (`Controller::ramp_down`),
    /// then 0 V for good.
    Faulted(Fault),
}

/// The controller, between ticks: its configuration, fixed at boot, apart from its state.
#[derive(Clone, Debug)]
pub struct Controller {
    // The monitor first: its fields within reach of the tick's short offsets (the tick's
    // budget).
    watch: Watch,
    // Configuration, fixed at boot.
    /// The device flashed: the monitor checks every sample against it, whatever the trim
    /// estimates.
    flashed: Device<f32>,
    amplifier: Amplifier,
    /// The inputs' noise the image's front end declares (the trim's ring is weighed against
    /// it before any voltage).
    inputs: InputNoise,
    /// Checked by `from_table`.
    settings: Settings,
    /// The cap fixed at boot from the device flashed, at most (1 − margin)·Φlimit, V.
    /// Nothing raises it.
    ceiling_volts: f32,
    /// The cap of the operator's plan in force (the boot's, or the last adopted replan's,
    /// at most the ceiling), V.
    operator_volts: f32,

    // State.
    state: State,
    /// The trim's estimate of the device, once it has one, in `estimates[estimate_at]`; the
    /// other slot takes the next, copied into it outside the tick (`trim_done`), so the tick
    /// that applies it only turns `estimate_at` (the tick's budget: a device is 92 bytes).
    estimates: [Option<Device<f32>>; 2],
    estimate_at: usize,
    /// Whether the estimate is the device flashed but for μ: the monitor then checks it on
    /// the flashed device's stretch terms (`Watch::stretch`). Worked out once, when it comes.
    estimate_shares_terms: bool,
    /// The lowest cap the measured estimates gave (trim, tracking; ∞ before any), V: it only
    /// falls.
    estimate_volts: f32,
    /// The shear modulus range of the batch the table was made for, Pa (model.md §10): a
    /// trim that measures μ outside it faults.
    batch_modulus: Option<(f32, f32)>,
    /// The cap in force: the lowest of the ceiling, the operator's and the estimate's, V.
    max_volts: f32,
    plan: Plan,
    tick: u32,
    /// The swing the membrane may carry into this plan from the drive before it (a replan's
    /// job made while driving), in stretch: counted in this plan's swing at boot.
    carried_ring_stretch: f32,
    /// The leakage watch's sums (model.md §8).
    leakage: Leakage,
    /// The voltage commanded at the last tick, V.
    last_volts: f32,
    /// The DAC code of `last_volts`, as sent.
    last_code: DacCode,
    /// The first tick at which an output dropped at once (a dead bus) has had the time to
    /// follow to 0 V at the slew rate (`at_rest`).
    settled_from_tick: u32,
    #[cfg(feature = "trim")]
    trim: trim::TrimState,
    /// The resonance tracker, while a tracked drive is on.
    #[cfg(feature = "track")]
    tracking: tracking::Tracking,
    /// The stretch from the capacitance, while the probe is on.
    #[cfg(feature = "probe")]
    sensing: sensing::Sensing,
}

impl Controller {
    /// A controller before its plan: what the boot stages fill in.
    fn new(
        device: Device<f32>,
        (amplifier, inputs): (Amplifier, InputNoise),
        settings: Settings,
        max_volts: f32,
    ) -> Self {
        Self {
            flashed: device,
            amplifier,
            inputs,
            settings,
            ceiling_volts: max_volts,
            operator_volts: max_volts,
            state: State::Ramping {
                then_measure: false,
            },
            estimates: [None, None],
            estimate_at: 0,
            estimate_shares_terms: false,
            estimate_volts: f32::INFINITY,
            batch_modulus: None,
            max_volts,
            plan: Plan::idle(),
            tick: 0,
            watch: Watch::new(settings.margin),
            carried_ring_stretch: 0.0,
            leakage: Leakage::default(),
            last_volts: 0.0,
            last_code: DacCode(0),
            settled_from_tick: 0,
            #[cfg(feature = "trim")]
            trim: trim::TrimState::new(*device.params(), true),
            #[cfg(feature = "track")]
            tracking: tracking::Tracking::default(),
            #[cfg(feature = "probe")]
            sensing: sensing::Sensing::default(),
        }
    }

    /// Where the controller is.
    pub fn phase(&self) -> Phase {
        match self.state {
            State::Ramping { .. } => Phase::Ramping,
            State::Holding { .. } => Phase::Holding,
            State::Measuring => Phase::Measuring,
            State::Solving => Phase::Solving,
            State::Driving { .. } => Phase::Driving,
            State::Held { .. } => Phase::Held,
            State::Faulted(_) => Phase::Faulted,
        }
    }

    /// The fault that brings the output down to 0 V and holds it there, if any (the first).
    pub fn latched_fault(&self) -> Option<Fault> {
        match self.state {
            State::Faulted(fault) => Some(fault),
            _ => None,
        }
    }

    /// What the trim needs (bias and AC, V) while it holds below the ceiling (`Phase::Held`).
    pub fn held_needing_volts(&self) -> Option<f32> {
        match self.state {
            State::Held { needed_volts } => Some(needed_volts),
            _ => None,
        }
    }

    /// The cap fixed at boot from the device flashed, V: no command ever goes above it.
    pub fn ceiling_volts(&self) -> f32 {
        self.ceiling_volts
    }

    /// The cap in force now: the lowest of the ceiling, the operator's plan's cap and the
    /// measured estimate's, V.
    pub fn max_volts(&self) -> f32 {
        self.max_volts
    }

    /// The cap of the operator's plan in force (at most the ceiling), V.
    pub fn operator_volts(&self) -> f32 {
        self.operator_volts
    }

    /// Tracking's last natural frequency (Hz) and quality factor, if it has them.
    pub fn tracking(&self) -> Option<(f32, f32)> {
        #[cfg(feature = "track")]
        return self.tracked().map(|l| (l.natural_hz, l.quality_factor));
        #[cfg(not(feature = "track"))]
        None
    }

    /// The measured natural frequency (Hz) and quality factor: tracking's, else the last
    /// trim window's ring's (its Q from the decay).
    pub fn resonance(&self) -> Option<(f32, f32)> {
        self.tracking()
            .or_else(|| self.ring_quality().map(|(hz, q)| (hz, q.quality_factor)))
    }

    /// The last trim window's ring: its frequency, Hz, and its Q from the decay (with the
    /// highest Q the window allows), if a window measured one.
    pub fn ring_quality(&self) -> Option<(f32, RingQuality)> {
        #[cfg(feature = "trim")]
        return self.trim.ring_quality;
        #[cfg(not(feature = "trim"))]
        None
    }

    /// The probe's last λ from C and its standard error, if it has them.
    pub fn sensing(&self) -> Option<(f32, f32)> {
        #[cfg(feature = "probe")]
        return self.sensed().map(|s| (s.stretch, s.sigma));
        #[cfg(not(feature = "probe"))]
        None
    }

    /// The leakage resistance the last window of the leakage watch measured, Ω, if one did.
    pub fn leakage_ohms(&self) -> Option<f32> {
        self.leakage.siemens().map(|siemens| 1.0 / siemens)
    }

    /// The lowest cap the measured estimates gave (∞ before any), V.
    pub fn estimate_volts(&self) -> f32 {
        self.estimate_volts
    }

    /// The one rule for the cap in force: the lowest of the three (a NaN is no cap: `min`
    /// keeps the number).
    fn set_caps(&mut self, operator_volts: f32, estimate_volts: f32) {
        self.operator_volts = operator_volts.min(self.ceiling_volts);
        self.estimate_volts = estimate_volts;
        self.max_volts = self
            .ceiling_volts
            .min(self.operator_volts)
            .min(self.estimate_volts);
    }

    /// A background result's cap (trim, tracking): it may lower the cap in force, never
    /// raise it. A plan that no longer fits under it comes down to it first (`hold`).
    #[cfg(feature = "track")]
    fn lower_estimate_cap(&mut self, k: u32, volts: f32) -> Option<Event> {
        self.take_estimate_cap(volts);
        let peak = self.plan.ramp_volts(k).max(self.plan.bias_volts) + self.plan.swing_volts();
        (!(peak <= self.max_volts)).then(|| self.hold(k, peak))
    }

    /// An estimate's own cap `volts` (trim, tracking): it may lower the cap in force, never
    /// raise it.
    #[cfg(feature = "trim")]
    fn take_estimate_cap(&mut self, volts: f32) {
        self.set_caps(self.operator_volts, volts.min(self.estimate_volts));
    }

    /// Hold below the cap in force, the AC and the probe off, the plant needing
    /// `needed_volts` (bias and swing): from the voltage last sent at the slew rate to the
    /// bias, or to the cap if the bias is above it; said as `Event::AboveCeiling`.
    #[cfg(feature = "trim")]
    fn hold(&mut self, k: u32, needed_volts: f32) -> Event {
        self.plan = Plan {
            start_tick: k,
            start_volts: self.last_volts,
            bias_volts: self.plan.bias_volts.min(self.max_volts).max(0.0),
            pulse_ticks: (0, 0),
            ac_tick: None,
            probe_volts: 0.0,
            ..self.plan
        };
        self.drop_job();
        self.state = State::Held { needed_volts };
        Event::AboveCeiling {
            needed_volts,
            cap_volts: self.max_volts,
        }
    }

    /// The trim's estimate of the device from now on: the waiting result's (a `Retune`'s),
    /// copied into the spare slot by `trim_done` with its comparison worked out.
    #[cfg(feature = "trim")]
    fn take_estimate(&mut self) {
        if let Some(TrimResult::Retune { .. }) = &self.trim.result {
            self.estimate_at = 1 - self.estimate_at.min(1);
            self.estimate_shares_terms = self.trim.result_shares_terms;
        }
    }

    /// The trim's estimate of the device, once it has one.
    #[cfg(any(feature = "probe", feature = "track"))]
    fn estimate(&self) -> Option<&Device<f32>> {
        self.estimates
            .get(self.estimate_at)
            .and_then(Option::as_ref)
    }

    /// No background job is wanted any more: a result of one handed out is dropped.
    fn drop_job(&mut self) {
        #[cfg(feature = "trim")]
        self.trim.drop_job();
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Ticks so far.
    pub fn ticks(&self) -> u32 {
        self.tick
    }

    /// One tick: the code to write now. `inputs` are this tick's measurements: the stretch
    /// is checked (`watch`) against model.md §6 at this tick's voltage, and for a stuck or
    /// implausible sensor; the amplifier's output against the last command.
    pub fn tick(&mut self, inputs: Inputs) -> Output {
        if matches!(self.state, State::Faulted(_)) {
            self.tick = self.tick.saturating_add(1);
            return self.descend(None);
        }
        let tolerance = self.settings.amplifier_tolerance_volts;
        if let Some(fault) =
            self.watch
                .amplifier(inputs.amplifier_volts, self.last_volts, tolerance)
        {
            return self.fault(fault);
        }
        if let Some(fault) = Watch::current(inputs.current_amps) {
            return self.fault(fault);
        }
        if let Some(fault) = self.watch_leakage(inputs.current_amps) {
            return self.fault(fault);
        }
        let k = self.tick;
        self.tick = self.tick.saturating_add(1);
        let phase = self.plan.phase(k);
        let volts = self.plan.volts_at(k, phase);
        // Above the cap in force only on the way down to a cap just lowered: never up.
        let bound = self.max_volts.max(self.last_volts);
        let code = match gate(&self.amplifier, volts, bound) {
            Ok(code) => code,
            Err(fault) => return self.fault(fault),
        };
        // The last voltage sent stays the previous tick's until this one passes every check:
        // a fault's descent starts from what was sent.
        let commanded_volts = self.amplifier.volts(code);
        if let Some(stretch) = inputs.stretch {
            let stuck = self.settings.stuck_samples;
            let estimate = (self.estimates.get(self.estimate_at))
                .and_then(Option::as_ref)
                .map(|device| (device, self.estimate_shares_terms));
            if let Some(fault) =
                self.watch
                    .stretch(k, stretch, volts, &self.flashed, estimate, stuck)
            {
                return self.fault(fault);
            }
            if let State::Driving { .. } = self.state {
                if let Some(fault) = self.watch.swing(k, phase, stretch) {
                    return self.fault(fault);
                }
            }
        }
        #[cfg(feature = "probe")]
        if let Some(fault) = self.sense(k, &inputs) {
            return self.fault(fault);
        }
        // While the tick decides what comes next, the voltage last sent is this tick's: a hold
        // or a plan under a lowered cap comes down from it (from the one before, the first
        // step down was larger than the slew's by the AC's last step). A fault's descent
        // starts from what was sent before.
        let sent_before = (self.last_volts, self.last_code);
        (self.last_volts, self.last_code) = (commanded_volts, code);
        match self.advance(k, Ring::of(&inputs), phase) {
            Ok(event) => Output {
                code,
                volts: commanded_volts,
                event,
            },
            Err(fault) => {
                (self.last_volts, self.last_code) = sent_before;
                self.fault(fault)
            }
        }
    }

    /// The leakage watch: the current against the last command, summed while the bias is
    /// steady (held, driven, or held below the ceiling), started again otherwise.
    fn watch_leakage(&mut self, amps: Option<f32>) -> Option<Fault> {
        let s = &self.settings;
        if s.leakage_floor_ohms.is_none() && s.leakage_fall_per_second.is_none() {
            return None;
        }
        let steady = matches!(
            self.state,
            State::Holding { .. } | State::Driving { .. } | State::Held { .. }
        );
        match amps.filter(|_| steady) {
            Some(amps) => {
                let window = (LEAKAGE_WINDOW_SECONDS * s.tick_hz) as u32;
                let limits = LeakageLimits {
                    window_ticks: window.max(1),
                    floor_ohms: s.leakage_floor_ohms,
                    fall: s
                        .leakage_fall_per_second
                        .map(|rate| rate * LEAKAGE_WINDOW_SECONDS),
                };
                self.leakage.observe(amps, self.last_volts, limits)
            }
            None => {
                self.leakage = Leakage::default();
                None
            }
        }
    }

    /// The state machine's step at tick `k`, and what it says; `ring` is what the trim
    /// records, `phase` the AC's phase at `k` (`Plan::phase`).
    fn advance(&mut self, k: u32, ring: Ring, phase: u32) -> Result<Option<Event>, Fault> {
        let _ = (ring, phase);
        match self.state {
            State::Ramping { then_measure } if self.plan.ramp_volts(k) == self.plan.bias_volts => {
                // The probe, off on a way down from above the cap (`adopt`), rides again.
                self.plan
                    .probe_back(self.settings.probe_volts.unwrap_or(0.0), self.max_volts)?;
                self.hold_from(k, then_measure);
                Ok(Some(Event::AtBias {
                    volts: self.plan.bias_volts,
                }))
            }
            #[cfg(feature = "trim")]
            State::Holding {
                until,
                then_measure: true,
            } if k >= until => {
                self.start_measuring(k)?;
                Ok(None)
            }
            #[cfg(feature = "trim")]
            State::Holding {
                until,
                then_measure: true,
            } => {
                // The monitor's noise, when the ring will come from the current, over the
                // hold's last three quarters (the probe's last edge, and the ramp's end,
                // settled before). The probe's edges would drown it: off until the trim is
                // applied, as for the window, while the noise is still to be heard.
                let settle = self.settings.settle_seconds * self.settings.tick_hz;
                let settled = (until.saturating_sub(k) as f32) < 0.75 * settle;
                match ring {
                    Ring::Current(amps) => {
                        if !self.trim.hold_noise.heard() {
                            self.plan.probe_volts = 0.0;
                        }
                        if settled && self.plan.probe_volts == 0.0 {
                            self.trim.hold_noise.observe(RingInput::Charge, amps);
                        }
                    }
                    Ring::Stretch(stretch) if settled => {
                        self.trim.hold_noise.observe(RingInput::Stretch, stretch);
                    }
                    _ => {}
                }
                Ok(None)
            }
            State::Holding {
                then_measure: false,
                ..
            } if self.plan.ac_tick.is_some_and(|at| k >= at) && self.plan.ac_volts > 0.0 => {
                self.state = State::Driving {
                    next_trim: self.next_trim(k),
                };
                self.watch.drive_on();
                // A drive (re)started tracks from scratch, at the plan's frequency: a tracker
                // of an earlier drive (before a trim, another plan) measures against a
                // frequency no longer driven.
                #[cfg(feature = "track")]
                {
                    self.tracking = tracking::Tracking::default();
                }
                Ok(Some(Event::DriveOn))
            }
            #[cfg(feature = "trim")]
            State::Driving {
                next_trim: Some(at),
            } if k >= at => {
                self.pause_for_trim(k);
                Ok(Some(Event::DriveOff))
            }
            #[cfg(feature = "trim")]
            State::Measuring => {
                self.record(k, ring)?;
                Ok(None)
            }
            #[cfg(feature = "trim")]
            State::Solving => self.apply_trim(k),
            #[cfg(feature = "track")]
            State::Driving { .. } if self.settings.track_seconds.is_some() => {
                self.track(k, ring, phase)
            }
            _ => Ok(None),
        }
    }

    /// Hold the bias from tick `k` for the settle time, then measure or drive.
    fn hold_from(&mut self, k: u32, then_measure: bool) {
        let settle = self.settings.settle_seconds * self.settings.tick_hz;
        // The noise is heard afresh in each hold before a pulse, but under a probe: then
        // only until it has been heard once (the probe is taken off for that, below).
        #[cfg(feature = "trim")]
        if then_measure && !(self.trim.hold_noise.heard() && self.plan.probe_volts > 0.0) {
            self.trim.hold_noise = trim::HoldNoise::default();
        }
        self.state = State::Holding {
            until: k.saturating_add(settle as u32),
            then_measure,
        };
    }

    /// Whether a trim was asked for.
    fn trim_wanted(&self) -> bool {
        self.settings.trim_tolerance.is_some()
    }

    /// Whether the AC's swing waits for the Q a trim's ring measures: no damping told, a
    /// trim asked for, and no tracked drive (whose tracker measures its own).
    fn quality_to_measure(&self) -> bool {
        cfg!(feature = "trim")
            && self.trim_wanted()
            && self.settings.track_seconds.is_none()
            && !(self.flashed.params().damping > 0.0)
    }

    /// The ring a trim's pulse at `bias_volts` leaves, in stretch, where a trim is wanted
    /// (the AC starts after its last pulse; 0 otherwise). Out of line: the boot's frame stays
    /// the smaller (the stack's budget).
    #[inline(never)]
    fn pulse_ring(&self, bias_volts: f32, limit_offset: f32) -> f32 {
        #[cfg(feature = "trim")]
        if self.trim_wanted() {
            return trim::pulse_ring(&self.flashed, limit_offset, bias_volts, &self.settings);
        }
        let _ = (bias_volts, limit_offset);
        0.0
    }

    /// When the next trim falls, the AC starting at tick `k`.
    fn next_trim(&self, k: u32) -> Option<u32> {
        let s = &self.settings;
        let every = s.trim_every_seconds.filter(|_| self.trim_wanted())?;
        Some(k.saturating_add(((every * s.tick_hz) as u32).max(1)))
    }

    /// Whether the bias held is the one tuned for the target (not a trim's probe bias;
    /// always without the trim).
    fn tuned(&self) -> bool {
        #[cfg(feature = "trim")]
        return self.trim.tuned;
        #[cfg(not(feature = "trim"))]
        true
    }

    /// What the trim expects of the ring its next pulse leaves (`NextRing::UNKNOWN`: none,
    /// or not known).
    #[cfg(feature = "trim")]
    fn next_ring(&self) -> trim::NextRing {
        self.trim.ring
    }

    /// Whether the bias planned is the one the estimate gives for the target.
    fn set_tuned(&mut self, tuned: bool) {
        #[cfg(feature = "trim")]
        {
            self.trim.tuned = tuned;
        }
        let _ = tuned;
    }

    /// One tick on the acquisition's result (`acquire`): an input that gave no reading trips
    /// the controller (`Fault::Input`); once it is faulted, the descent goes on whatever the
    /// inputs (an error at every tick must not stall it).
    pub fn tick_acquired(&mut self, inputs: Result<Inputs, InputError>) -> Output {
        match inputs {
            Ok(inputs) => self.tick(inputs),
            Err(e) if !matches!(self.state, State::Faulted(_)) => self.fault(Fault::Input(e)),
            Err(_) => self.tick(Inputs::NONE),
        }
    }

    /// A fault (the tick's own, or one the IO side reports): the output goes down from the
    /// last command at the slew rate, no faster (a step down rings the membrane below its
    /// equilibrium, toward loss of tension, model.md §6), then stays at 0 V until a new boot.
    /// A dead bus (`Fault::Bus`) cannot ramp: 0 V at once (the IO side drops the enable
    /// line). Only the first fault is latched and said.
    pub fn fault(&mut self, fault: Fault) -> Output {
        let event = match self.state {
            State::Faulted(_) => None,
            _ => {
                self.state = State::Faulted(fault);
                self.ramp_down(self.last_volts);
                Some(Event::Fault(fault))
            }
        };
        if fault == Fault::Bus {
            // The command drops at once; the output, through the amplifier, at best at the
            // slew rate: at rest only once the descent would have ended.
            let step = self.plan.ramp_volts_per_tick;
            let ticks = if step > 0.0 {
                libm::ceilf(self.plan.start_volts / step)
            } else {
                0.0
            };
            // `as` saturates: a NaN or a huge count keeps it from rest for good.
            let ticks = if ticks.is_nan() {
                u32::MAX
            } else {
                ticks as u32
            };
            self.settled_from_tick = self.settled_from_tick.max(self.tick.saturating_add(ticks));
            self.plan.start_volts = 0.0;
        }
        self.descend(event)
    }

    /// From this tick on, down from `from_volts` to 0 V at the slew rate and held there
    /// (`stop`, and a fault's descent). Counted from the start (`Plan::ramp_volts`), so no
    /// rounding can stall it; a rate that is not positive gives 0 V at once.
    fn ramp_down(&mut self, from_volts: f32) {
        let rate_ok = self.plan.ramp_volts_per_tick > 0.0;
        self.plan = Plan {
            start_tick: self.tick,
            start_volts: if rate_ok { from_volts } else { 0.0 },
            bias_volts: 0.0,
            pulse_ticks: (0, 0),
            ac_tick: None,
            ac_volts: 0.0,
            probe_volts: 0.0,
            ..self.plan
        };
    }

    /// The descent's output at this tick: the ramp down one step on from the last (the first
    /// a step below the voltage sent when the fault came), through the final gate bounded by
    /// the voltage last sent, not by the cap in force (which may have moved): never up.
    fn descend(&mut self, event: Option<Event>) -> Output {
        let volts = self.plan.ramp_volts(self.tick.saturating_add(1));
        let code = gate(&self.amplifier, volts, self.last_volts).unwrap_or(DacCode(0));
        (self.last_volts, self.last_code) = (self.amplifier.volts(code), code);
        Output {
            code,
            volts: self.last_volts,
            event,
        }
    }
}
