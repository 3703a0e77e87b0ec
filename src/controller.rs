//! The resonator's controller, sans IO: the same code on the chip and in host-sim.
//!
//! `Controller::start` checks everything before anything is driven, in three stages a
//! firmware can also take one by one (leaving out, and not linking, what it does not need):
//! - `from_table`: the device parameters, the settings, the tuning table (CRC, order, made
//!   for this device); the bias for the target from the table, and commands capped below the
//!   table's top, which its maker put at (1 − margin)·limit;
//! - `cross_check`: the limit and the bias by the core's direct solve on the chip (MODEL.md
//!   §6–§7), which must agree with the table; the cap becomes (1 − margin)·limit;
//! - `check_plan`: the whole plan (ramp at a bounded slew rate, hold, AC drive) run through
//!   the fixed-step model under the safety monitor (MODEL.md §6).
//!
//! Then `tick`, at a fixed rate, gives the DAC code for that tick; every code passes one
//! final check against the cap. A fault of any kind gives code 0 from then on, and says what
//! happened once.

use core::f32::consts::TAU;
use core::fmt;

use crate::device::{Device, DeviceParams, ParamError};
use crate::drive::{Amplifier, CodeError, DacCode};
use crate::integration::{Drive, Integrator, Method, State, StepError};
use crate::real::Real;
use crate::safety::{FailureMode, Limit, Monitor};
use crate::table::{Table, TableError};
use crate::tuning::{TuneError, Tuner};

/// What the controller is asked to do, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// The natural frequency to tune to, Hz.
    pub target_hz: f32,
    /// Voltage margin: every commanded voltage stays at most (1 − margin)·Φlimit.
    pub margin: f32,
    /// Bias ramp rate, V/s.
    pub slew_volts_per_second: f32,
    /// The controller's fixed rate, Hz.
    pub tick_hz: f32,
    /// Hold at the bias before the AC drive starts, s.
    pub settle_seconds: f32,
    /// AC drive amplitude, V (0: none).
    pub ac_volts: f32,
    /// AC drive frequency, Hz.
    pub ac_hz: f32,
    /// How long the model follows the AC drive after it starts, s.
    pub check_seconds: f32,
    /// Largest relative difference allowed between the natural frequency at the table's bias
    /// and at the direct solve's (the two biases differ by the table's interpolation).
    pub agreement: f32,
    /// Largest difference between the amplifier's monitored output and the last command,
    /// V, for more than `AMPLIFIER_TICKS` ticks in a row (a saturated or failed amplifier).
    pub amplifier_tolerance_volts: f32,
    /// Bit-identical sensor samples in a row that mean a stuck sensor (0: no such check; a
    /// real sensor's noise never repeats that long).
    pub stuck_samples: u32,
}

impl Settings {
    /// Defaults for a target: 5% margin, 10 kV/s, 1 kHz, 0.25 s hold, no AC, 0.5 s of
    /// model after the AC starts, table and solve within 1e-4 in frequency, the amplifier
    /// within 200 V of its command, 100 equal sensor samples in a row a stuck sensor.
    pub const fn for_target(target_hz: f32) -> Self {
        Self {
            target_hz,
            margin: 0.05,
            slew_volts_per_second: 10_000.0,
            tick_hz: 1_000.0,
            settle_seconds: 0.25,
            ac_volts: 0.0,
            ac_hz: 0.0,
            check_seconds: 0.5,
            agreement: 1e-4,
            amplifier_tolerance_volts: 200.0,
            stuck_samples: 100,
        }
    }
}

/// A setting, for errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Setting {
    SlewVoltsPerSecond,
    TickHz,
    SettleSeconds,
    AcVolts,
    AcHz,
    CheckSeconds,
    Agreement,
    AmplifierToleranceVolts,
}

/// Ticks in a row the amplifier may be off its command before it is a fault (its bandwidth
/// and slew limit lag a step by a tick or two).
pub const AMPLIFIER_TICKS: u32 = 3;

/// What the IO side measured this tick, if anything.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inputs {
    /// The displacement sensor's stretch λ.
    pub stretch: Option<f32>,
    /// The amplifier's monitor output, V.
    pub amplifier_volts: Option<f32>,
}

impl Inputs {
    /// Nothing measured.
    pub const NONE: Inputs = Inputs {
        stretch: None,
        amplifier_volts: None,
    };

    /// A stretch sample only.
    pub const fn stretch(stretch: f32) -> Self {
        Inputs {
            stretch: Some(stretch),
            amplifier_volts: None,
        }
    }
}

/// The longest plan, in ticks (about 18 hours at 1 kHz before the AC starts).
pub const MAX_PLAN_TICKS: f32 = 6.4e7;

/// Why the controller will not drive, or stopped driving. Each leaves the output at 0 V.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The device parameters are invalid, or not safe at zero bias.
    Device(ParamError),
    /// A setting is NaN, out of range, or makes the plan too long.
    Setting { setting: Setting, value: f32 },
    /// The tuning table is corrupted, out of order, for another device, or misses the target.
    Table(TableError),
    /// The direct solve cannot reach the target (out of range, bad target or margin).
    Tune(TuneError<f32>),
    /// The natural frequencies at the table's bias and at the direct solve's differ by more
    /// than the agreement.
    Disagree {
        table_volts: f32,
        table_hz: f32,
        solved_volts: f32,
        solved_hz: f32,
    },
    /// A voltage of the plan or the table is above the safe maximum.
    AboveSafe { volts: f32, max_volts: f32 },
    /// The model run of the plan crossed a limit (ramp too fast, AC too strong).
    PlanCrosses { mode: FailureMode, seconds: f32 },
    /// The model run of the plan could not go on (left the model's range, NaN).
    PlanFailed(StepError<f32>),
    /// The amplifier cannot give a voltage of the plan.
    Amplifier(CodeError),
    /// A commanded voltage failed the final check (never expected: a guard of last resort).
    Gate { volts: f32, max_volts: f32 },
    /// A sensor sample (stretch or amplifier monitor) is NaN or infinite.
    Sensor { value: f32 },
    /// The stretch sensor gave the same sample `samples` times in a row.
    SensorStuck { samples: u32, value: f32 },
    /// The amplifier's output stayed off the command for `AMPLIFIER_TICKS` ticks.
    AmplifierDisagrees {
        commanded_volts: f32,
        measured_volts: f32,
    },
    /// The measured motion crossed a limit of MODEL.md §6.
    Limit { mode: FailureMode, tick: u32 },
    /// The DAC bus failed (reported by the IO side).
    Bus,
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::Device(e) => write!(f, "device: {e}"),
            Fault::Setting { setting, value } => {
                write!(f, "setting {setting:?} = {value} is invalid")
            }
            Fault::Table(e) => write!(f, "table: {e}"),
            Fault::Tune(e) => write!(f, "tuning: {e}"),
            Fault::Disagree {
                table_volts,
                table_hz,
                solved_volts,
                solved_hz,
            } => write!(
                f,
                "table gives {table_volts} V ({table_hz} Hz), the direct solve {solved_volts} V \
                 ({solved_hz} Hz): they disagree"
            ),
            Fault::AboveSafe { volts, max_volts } => {
                write!(f, "{volts} V is above the safe maximum {max_volts} V")
            }
            Fault::PlanCrosses { mode, seconds } => write!(
                f,
                "the plan crosses a limit in the model at {seconds} s: {}",
                mode.description()
            ),
            Fault::PlanFailed(e) => write!(f, "the model run of the plan stopped: {e}"),
            Fault::Amplifier(e) => write!(f, "amplifier: {e}"),
            Fault::Gate { volts, max_volts } => {
                write!(
                    f,
                    "final check refused {volts} V (safe maximum {max_volts} V)"
                )
            }
            Fault::Sensor { value } => write!(f, "sensor sample {value} is not a number"),
            Fault::SensorStuck { samples, value } => {
                write!(f, "stretch sensor stuck at {value} for {samples} samples")
            }
            Fault::AmplifierDisagrees {
                commanded_volts,
                measured_volts,
            } => write!(
                f,
                "amplifier gives {measured_volts} V for a command of {commanded_volts} V \
                 (saturated or failed)"
            ),
            Fault::Limit { mode, tick } => {
                write!(f, "measured motion at tick {tick}: {}", mode.description())
            }
            Fault::Bus => write!(f, "DAC bus error"),
        }
    }
}

/// What the boot stages found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Boot {
    /// The bias the controller drives (the direct solve's once cross-checked), V.
    pub bias_volts: f32,
    /// The table's interpolated bias for the target, V.
    pub table_volts: f32,
    /// The table's highest bias, V.
    pub table_top_volts: f32,
    /// The cap: no command goes above it, V.
    pub max_volts: f32,
    /// The first failure on the loading branch, found on the chip (`cross_check`).
    pub limit: Option<Limit<f32>>,
    /// The ticks of the plan up to the end of its model check.
    pub plan_ticks: u32,
    /// The stretch range the model run of the plan swept (`check_plan`).
    pub plan_stretch: Option<(f32, f32)>,
}

/// The plan: ramp to the bias, hold, then the AC drive; the voltage at every tick.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plan {
    pub bias_volts: f32,
    /// Bias step per tick on the ramp, V.
    pub ramp_volts_per_tick: f32,
    /// The tick at which the AC starts.
    pub ac_tick: u32,
    pub ac_volts: f32,
    /// AC phase advance per tick, in units of 2π/2³²: the phase is an exact integer, so it
    /// neither drifts nor loses precision however long the drive runs.
    pub ac_phase_step: u32,
}

impl Plan {
    /// No voltage at all (before a plan is made).
    const fn idle() -> Self {
        Self {
            bias_volts: 0.0,
            ramp_volts_per_tick: 0.0,
            ac_tick: 0,
            ac_volts: 0.0,
            ac_phase_step: 0,
        }
    }

    /// The voltage at tick `k`.
    pub fn volts(&self, k: u32) -> f32 {
        let ramp = self.ramp_volts_per_tick * k as f32;
        if k < self.ac_tick {
            return ramp.min(self.bias_volts);
        }
        let phase = (k - self.ac_tick).wrapping_mul(self.ac_phase_step);
        let angle = phase as f32 * (TAU / 4_294_967_296.0);
        self.bias_volts + self.ac_volts * Real::sin(angle)
    }

    /// The highest voltage the plan reaches, V.
    pub fn peak_volts(&self) -> f32 {
        self.bias_volts + self.ac_volts
    }
}

/// Where the controller is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    Ramping,
    Holding,
    Driving,
    Faulted,
}

/// Something that happened at a tick, said once.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The ramp reached the bias.
    AtBias { volts: f32 },
    /// The AC drive started.
    DriveOn,
    /// A fault: from now on 0 V.
    Fault(Fault),
}

/// One tick's output: the DAC code, the voltage it gives, and what happened.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    pub code: DacCode,
    pub volts: f32,
    pub event: Option<Event>,
}

/// The controller, between ticks.
#[derive(Clone, Copy, Debug)]
pub struct Controller {
    device: Device<f32>,
    amplifier: Amplifier,
    /// Checked by `from_table`.
    settings: Settings,
    plan: Plan,
    max_volts: f32,
    tick: u32,
    phase: Phase,
    monitor: Monitor<f32>,
    /// The voltage commanded at the last tick, V.
    last_volts: f32,
    /// Ticks in a row the amplifier has been off its command.
    amplifier_off_ticks: u32,
    /// The last stretch sample and how many times in a row it came.
    last_stretch: f32,
    same_stretch: u32,
}

fn positive(setting: Setting, value: f32) -> Result<f32, Fault> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Fault::Setting { setting, value })
    }
}

fn non_negative(setting: Setting, value: f32) -> Result<f32, Fault> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Fault::Setting { setting, value })
    }
}

impl Controller {
    /// Every check: `from_table`, then `cross_check`, then `check_plan`.
    pub fn start(
        params: DeviceParams<f32>,
        table: &[u8],
        amplifier: Amplifier,
        settings: Settings,
    ) -> Result<(Self, Boot), Fault> {
        let (controller, boot) = Self::from_table(params, table, amplifier, settings)?;
        let (controller, boot) = controller.cross_check(boot)?;
        controller.check_plan(boot)
    }

    /// Check the device, the settings and the table, and plan from the table alone: the bias
    /// by interpolation, commands capped at the table's top scaled to the settings' margin,
    /// top·min(1, (1 − margin)/(1 − table margin)), which is at most (1 − margin)·limit.
    pub fn from_table(
        params: DeviceParams<f32>,
        table: &[u8],
        amplifier: Amplifier,
        settings: Settings,
    ) -> Result<(Self, Boot), Fault> {
        let device = Device::new(params).map_err(Fault::Device)?;
        let tick_hz = positive(Setting::TickHz, settings.tick_hz)?;
        positive(Setting::SlewVoltsPerSecond, settings.slew_volts_per_second)?;
        non_negative(Setting::SettleSeconds, settings.settle_seconds)?;
        non_negative(Setting::AcVolts, settings.ac_volts)?;
        let ac_hz = non_negative(Setting::AcHz, settings.ac_hz)?;
        non_negative(Setting::CheckSeconds, settings.check_seconds)?;
        positive(Setting::Agreement, settings.agreement)?;
        positive(
            Setting::AmplifierToleranceVolts,
            settings.amplifier_tolerance_volts,
        )?;
        if !(ac_hz < 0.5 * tick_hz) {
            return Err(Fault::Setting {
                setting: Setting::AcHz,
                value: ac_hz,
            });
        }
        if !(settings.margin >= 0.0 && settings.margin < 1.0) {
            return Err(Fault::Tune(TuneError::InvalidMargin {
                margin: settings.margin,
            }));
        }

        let table = Table::parse(table).map_err(Fault::Table)?;
        table.check_device(&params).map_err(Fault::Table)?;
        let top = table.max_volts();
        let max_volts = top * ((1.0 - settings.margin) / (1.0 - table.margin())).min(1.0);
        let table_volts = table.bias_volts(settings.target_hz).map_err(Fault::Table)?;
        let mut controller = Controller {
            device,
            amplifier,
            settings,
            plan: Plan::idle(),
            max_volts,
            tick: 0,
            phase: Phase::Ramping,
            monitor: Monitor::new(),
            last_volts: 0.0,
            amplifier_off_ticks: 0,
            last_stretch: f32::NAN,
            same_stretch: 0,
        };
        let plan_ticks = controller.set_plan(table_volts)?;
        let boot = Boot {
            bias_volts: table_volts,
            table_volts,
            table_top_volts: top,
            max_volts,
            limit: None,
            plan_ticks,
            plan_stretch: None,
        };
        Ok((controller, boot))
    }

    /// Find the limit and the bias on the chip by the direct solve: the table's top must lie
    /// below (1 − margin)·limit, and the natural frequencies at the two biases must agree.
    /// The controller then drives the solve's bias, capped at (1 − margin)·limit.
    pub fn cross_check(mut self, boot: Boot) -> Result<(Self, Boot), Fault> {
        let settings = self.settings;
        let tuner = Tuner::new(self.device);
        let limit = tuner.limit();
        let max_volts = tuner.max_bias(settings.margin).map_err(Fault::Tune)?.volts;
        if !(boot.table_top_volts <= max_volts) {
            return Err(Fault::AboveSafe {
                volts: boot.table_top_volts,
                max_volts,
            });
        }
        let solved = tuner
            .tune(settings.target_hz, settings.margin)
            .map_err(Fault::Tune)?;
        let table_hz = self
            .device
            .stretch_for_bias(boot.table_volts, limit.at.stretch)
            .map(|stretch| self.device.natural_frequency_hz(stretch))
            .unwrap_or(f32::NAN);
        let solved_hz = solved.natural_frequency_hz;
        if !((table_hz - solved_hz).abs() <= settings.agreement * solved_hz) {
            return Err(Fault::Disagree {
                table_volts: boot.table_volts,
                table_hz,
                solved_volts: solved.volts,
                solved_hz,
            });
        }
        self.max_volts = max_volts;
        let plan_ticks = self.set_plan(solved.volts)?;
        let boot = Boot {
            bias_volts: solved.volts,
            max_volts,
            limit: Some(*limit),
            plan_ticks,
            ..boot
        };
        Ok((self, boot))
    }

    /// Run the whole plan through the model (f32 RK4 under the monitor, from rest at the
    /// pre-stretch) and refuse it if a limit is crossed on the way.
    pub fn check_plan(self, boot: Boot) -> Result<(Self, Boot), Fault> {
        let stretch = check_plan(
            &self.device,
            &self.plan,
            self.settings.tick_hz,
            boot.plan_ticks,
        )?;
        let boot = Boot {
            plan_stretch: Some(stretch),
            ..boot
        };
        Ok((self, boot))
    }

    /// Plan a ramp to `bias_volts`, the hold and the AC drive, under the cap; the ticks up to
    /// the end of the model check.
    fn set_plan(&mut self, bias_volts: f32) -> Result<u32, Fault> {
        let s = self.settings;
        let ramp_ticks = bias_volts / s.slew_volts_per_second * s.tick_hz;
        let ac_tick = libm::ceilf(ramp_ticks) + s.settle_seconds * s.tick_hz;
        let check_ticks = s.check_seconds * s.tick_hz;
        if !(ac_tick + check_ticks < MAX_PLAN_TICKS) {
            return Err(Fault::Setting {
                setting: Setting::SlewVoltsPerSecond,
                value: s.slew_volts_per_second,
            });
        }
        let plan = Plan {
            bias_volts,
            ramp_volts_per_tick: s.slew_volts_per_second / s.tick_hz,
            ac_tick: ac_tick as u32,
            ac_volts: if s.ac_hz > 0.0 { s.ac_volts } else { 0.0 },
            ac_phase_step: ((s.ac_hz / s.tick_hz) as f64 * 4_294_967_296.0) as u32,
        };
        if !(plan.peak_volts() <= self.max_volts) {
            return Err(Fault::AboveSafe {
                volts: plan.peak_volts(),
                max_volts: self.max_volts,
            });
        }
        self.amplifier
            .code(plan.peak_volts())
            .map_err(Fault::Amplifier)?;
        self.plan = plan;
        Ok(plan.ac_tick + check_ticks as u32 + 1)
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Ticks so far.
    pub fn ticks(&self) -> u32 {
        self.tick
    }

    /// One tick: the code to write now. `inputs` are this tick's measurements: the stretch
    /// is checked against MODEL.md §6 at this tick's voltage by the monitor, and for a stuck
    /// sensor; the amplifier's output against the last command.
    pub fn tick(&mut self, inputs: Inputs) -> Output {
        if self.phase == Phase::Faulted {
            return self.zero(None);
        }
        if let Some(fault) = self.check_amplifier(inputs.amplifier_volts) {
            return self.fault(fault);
        }
        let k = self.tick;
        self.tick = self.tick.saturating_add(1);
        let volts = self.plan.volts(k);
        let code = match self.gate(volts) {
            Ok(code) => code,
            Err(fault) => return self.fault(fault),
        };
        self.last_volts = self.amplifier.volts(code);
        if let Some(stretch) = inputs.stretch {
            if !stretch.is_finite() {
                return self.fault(Fault::Sensor { value: stretch });
            }
            if let Some(fault) = self.check_stuck(stretch) {
                return self.fault(fault);
            }
            let p = volts / self.device.volts_per_unit();
            self.monitor
                .observe(&self.device, u64::from(k), stretch, p * p);
            if let Some(crossing) = self.monitor.first_crossing() {
                return self.fault(Fault::Limit {
                    mode: crossing.mode,
                    tick: k,
                });
            }
        }
        let event = match self.phase {
            Phase::Ramping if volts >= self.plan.bias_volts => {
                self.phase = Phase::Holding;
                Some(Event::AtBias { volts })
            }
            Phase::Holding if k >= self.plan.ac_tick && self.plan.ac_volts > 0.0 => {
                self.phase = Phase::Driving;
                Some(Event::DriveOn)
            }
            _ => None,
        };
        Output {
            code,
            volts: self.amplifier.volts(code),
            event,
        }
    }

    /// The amplifier's monitored output against the last command.
    fn check_amplifier(&mut self, measured: Option<f32>) -> Option<Fault> {
        let measured = measured?;
        if !measured.is_finite() {
            return Some(Fault::Sensor { value: measured });
        }
        if (measured - self.last_volts).abs() <= self.settings.amplifier_tolerance_volts {
            self.amplifier_off_ticks = 0;
            return None;
        }
        self.amplifier_off_ticks += 1;
        (self.amplifier_off_ticks > AMPLIFIER_TICKS).then_some(Fault::AmplifierDisagrees {
            commanded_volts: self.last_volts,
            measured_volts: measured,
        })
    }

    /// The same stretch sample too many times in a row.
    fn check_stuck(&mut self, stretch: f32) -> Option<Fault> {
        if stretch.to_bits() == self.last_stretch.to_bits() {
            self.same_stretch += 1;
        } else {
            self.same_stretch = 1;
            self.last_stretch = stretch;
        }
        let limit = self.settings.stuck_samples;
        (limit > 0 && self.same_stretch >= limit).then_some(Fault::SensorStuck {
            samples: self.same_stretch,
            value: stretch,
        })
    }

    /// The IO side reports a fault (a DAC bus error): 0 V from now on.
    pub fn fault(&mut self, fault: Fault) -> Output {
        let first = self.phase != Phase::Faulted;
        self.phase = Phase::Faulted;
        self.zero(first.then_some(Event::Fault(fault)))
    }

    fn zero(&self, event: Option<Event>) -> Output {
        Output {
            code: DacCode(0),
            volts: 0.0,
            event,
        }
    }

    /// The final check every code passes: the voltage is a number in [0, max], and so is
    /// what its code gives.
    fn gate(&self, volts: f32) -> Result<DacCode, Fault> {
        let refuse = Fault::Gate {
            volts,
            max_volts: self.max_volts,
        };
        if !(volts >= 0.0 && volts <= self.max_volts) {
            return Err(refuse);
        }
        let code = self.amplifier.code(volts).map_err(Fault::Amplifier)?;
        if !(self.amplifier.volts(code) <= self.max_volts) {
            return Err(refuse);
        }
        Ok(code)
    }
}

/// Run the plan through the model (RK4, f32, one step a tick, subdivided for stability)
/// from rest at the pre-stretch, with the monitor at every tick. The stretch range swept, or
/// the crossing.
fn check_plan(
    device: &Device<f32>,
    plan: &Plan,
    tick_hz: f32,
    ticks: u32,
) -> Result<(f32, f32), Fault> {
    let start = State {
        stretch: device.prestretch_1(),
        velocity: 0.0,
    };
    let mut model = Integrator::new(
        *device,
        Drive::constant(device, 0.0),
        Method::Rk4,
        1.0 / tick_hz,
        device.model_range(),
        start,
        true,
    )
    .map_err(Fault::PlanFailed)?;
    let mut monitor = Monitor::new();
    let (mut low, mut high) = (f32::INFINITY, f32::NEG_INFINITY);
    for k in 0..ticks {
        let volts = plan.volts(k);
        let p = volts / device.volts_per_unit();
        let stretch = model.state().stretch;
        monitor.observe(device, u64::from(k), stretch, p * p);
        if let Some(crossing) = monitor.first_crossing() {
            return Err(Fault::PlanCrosses {
                mode: crossing.mode,
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
