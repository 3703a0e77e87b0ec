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
//! final check against the cap. The cap is fixed at boot from the device flashed, at most
//! (1 − margin)·Φlimit: nothing measured ever raises it (a trim may only lower it). A fault
//! of any kind gives code 0 from then on, and says what happened once.

use core::f32::consts::TAU;
use core::fmt;

use crate::device::{Device, DeviceParams, ParamError};
use crate::drive::{Amplifier, CodeError, DacCode};
use crate::integration::{Drive, Integrator, Method, State, StepError};
use crate::real::Real;
use crate::safety::{FailureMode, Limit, Monitor};
use crate::table::{Table, TableError};
#[cfg(feature = "trim")]
use crate::trim::{estimate_shear_modulus, ring_frequency_hz};
use crate::trim::{TrimError, MAX_WINDOW};
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
    /// Closed-loop trim: the relative frequency error to reach (0: no trim). Needs the
    /// stretch sensor and the `cross_check` stage (the model is re-solved on the chip).
    pub trim_tolerance: f32,
    /// The ring measured after each pulse, s (at most `MAX_WINDOW` ticks).
    pub trim_window_seconds: f32,
    /// The pulse's drop below the bias, V, for half a period of the target.
    pub trim_pulse_volts: f32,
    /// The first bias the trim measures at, as a fraction of the nominal cap at most: a
    /// plant softer than the model by a factor r has its limit √r lower, so a fraction p
    /// covers plants down to r = p².
    pub trim_probe_fraction: f32,
    /// Trim again after this long of AC drive, s (0: once): for a plant that drifts, as a
    /// viscoelastic membrane creeps. The AC pauses while the ring is measured.
    pub trim_every_seconds: f32,
}

/// The f32 solve's allowance: the cap is (1 − margin)·(1 − F32_GUARD)·Φlimit in f32, so it
/// stays below (1 − margin)·Φlimit in f64. The f32 limit was within 6.7e-7 of the f64 limit
/// of the same parameters on 28,726 random devices (`tests/safety.rs` holds it to 1e-6).
pub const F32_GUARD: f32 = 1e-5;

/// The margin the f32 solve runs with: (1 − margin)·(1 − F32_GUARD) = 1 − that.
fn guarded(margin: f32) -> f32 {
    1.0 - (1.0 - margin) * (1.0 - F32_GUARD)
}

/// Most trims (measure, estimate, retune) before the controller gives up.
pub const MAX_TRIMS: u8 = 8;

/// Largest change of the bias a secant step may make, as a fraction of the bias.
pub const TRIM_SECANT_STEP: f32 = 0.1;

/// The trim's window in the controller: none without the `trim` feature (saves 2 KB).
const WINDOW: usize = if cfg!(feature = "trim") {
    MAX_WINDOW
} else {
    0
};

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
            trim_tolerance: 0.0,
            trim_window_seconds: 0.5,
            trim_pulse_volts: 200.0,
            trim_probe_fraction: 0.5,
            trim_every_seconds: 0.0,
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
    TrimTolerance,
    TrimWindowSeconds,
    TrimPulseVolts,
    TrimProbeFraction,
    TrimEverySeconds,
}

impl Setting {
    /// The setting's key, as in `Settings` and a scene's `[controller]` table.
    pub fn key(self) -> &'static str {
        match self {
            Setting::SlewVoltsPerSecond => "slew_volts_per_second",
            Setting::TickHz => "tick_hz",
            Setting::SettleSeconds => "settle_seconds",
            Setting::AcVolts => "ac_volts",
            Setting::AcHz => "ac_hz",
            Setting::CheckSeconds => "check_seconds",
            Setting::Agreement => "agreement",
            Setting::AmplifierToleranceVolts => "amplifier_tolerance_volts",
            Setting::TrimTolerance => "trim_tolerance",
            Setting::TrimWindowSeconds => "trim_window_seconds",
            Setting::TrimPulseVolts => "trim_pulse_volts",
            Setting::TrimProbeFraction => "trim_probe_fraction",
            Setting::TrimEverySeconds => "trim_every_seconds",
        }
    }
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
    /// A stretch sample no device could give: the bars more than a frame's length outside
    /// the frame (see `Device::plausible_stretch`).
    SensorImplausible { value: f32, low: f32, high: f32 },
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
    /// The trim could not measure, estimate or converge.
    Trim(TrimError),
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::Device(e) => write!(f, "device: {e}"),
            Fault::Setting { setting, value } => {
                write!(f, "setting `{}` = {value} is invalid", setting.key())
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
            Fault::SensorImplausible { value, low, high } => write!(
                f,
                "stretch sample {value} is outside ({low}, {high}), where no device can be: \
                 sensor fault"
            ),
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
            Fault::Trim(e) => write!(f, "trim: {e}"),
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
    /// The tick at which the AC starts (`u32::MAX`: not planned yet).
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
            start_tick: 0,
            start_volts: 0.0,
            bias_volts: 0.0,
            ramp_volts_per_tick: 0.0,
            pulse_ticks: (0, 0),
            pulse_volts: 0.0,
            ac_tick: 0,
            ac_volts: 0.0,
            ac_phase_step: 0,
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

    /// The voltage at tick `k`.
    pub fn volts(&self, k: u32) -> f32 {
        if k < self.ac_tick {
            let ramp = self.ramp_volts(k);
            let (from, to) = self.pulse_ticks;
            return if k >= from && k < to {
                (ramp - self.pulse_volts).max(0.0)
            } else {
                ramp
            };
        }
        let phase = (k - self.ac_tick).wrapping_mul(self.ac_phase_step);
        let angle = phase as f32 * (TAU / 4_294_967_296.0);
        self.bias_volts + self.ac_volts * Real::sin(angle)
    }

    /// The highest voltage the plan reaches, V.
    pub fn peak_volts(&self) -> f32 {
        self.start_volts.max(self.bias_volts) + self.ac_volts
    }
}

/// Where the controller is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    Ramping,
    Holding,
    /// The trim's pulse and the ring after it, measured.
    Measuring,
    Driving,
    /// The trim found the plant needs a bias above the ceiling fixed at boot: the bias holds
    /// where it is, no AC, no further trim (said once by `Event::AboveCeiling`).
    Held,
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
    /// The AC drive paused, to trim again.
    DriveOff,
    /// The trim measured the natural frequency at the bias and re-estimated μ; the next bias
    /// is the one its estimate gives for the target (equal to `bias_volts` once converged).
    Trimmed {
        bias_volts: f32,
        measured_hz: f32,
        shear_modulus: f32,
        next_bias_volts: f32,
    },
    /// The trim's next bias (with the AC on top) would be `needed_volts`, above the ceiling
    /// fixed at boot from the device flashed: the controller holds the present bias instead
    /// (`Phase::Held`). A plant stiffer than the device flashed is not driven past that
    /// device's limit on the strength of a measurement.
    AboveCeiling {
        needed_volts: f32,
        ceiling_volts: f32,
    },
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
    /// The cap in force: the ceiling, or lower after a trim found a softer plant, V.
    max_volts: f32,
    /// The cap fixed at boot from the device flashed, at most (1 − margin)·Φlimit, V.
    /// Nothing measured raises it.
    ceiling_volts: f32,
    /// The device flashed: the monitor checks every sample against it (and against the
    /// trim's estimate, when there is one), whatever the trim estimates.
    flashed: Device<f32>,
    /// Whether `device` is the trim's estimate (not the device flashed).
    estimated: bool,
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
    /// The tick the hold at the bias ends.
    hold_until: u32,
    trim: Trim,
}

/// What a retune decided.
#[cfg(feature = "trim")]
enum Retune {
    /// Ramp to this bias and measure again.
    To { bias_volts: f32 },
    /// The bias (and AC) needed lies above the ceiling: hold.
    AboveCeiling { needed_volts: f32 },
}

/// The trim's state: the model as estimated so far and the window being measured.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(not(feature = "trim"), allow(dead_code))]
struct Trim {
    /// The device as estimated (μ re-estimated; the rest as told).
    params: DeviceParams<f32>,
    /// Whether the bias held is the one the estimate gives for the target.
    tuned: bool,
    /// Trims done.
    count: u8,
    /// Converged (or no trim asked): the AC may start.
    done: bool,
    /// The last measurement: (bias², measured f), for the secant step.
    previous: Option<(f32, f32)>,
    /// The tick of the next trim while driving (`u32::MAX`: none).
    next_trim: u32,
    /// The first tick of the window, and the samples in it (NaN: no sample that tick).
    window_from: u32,
    window: [f32; WINDOW],
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
        let trim = non_negative(Setting::TrimTolerance, settings.trim_tolerance)?;
        if trim > 0.0 && !cfg!(feature = "trim") {
            // Built without the trim: asking for it is an error, not a silent no.
            return Err(Fault::Setting {
                setting: Setting::TrimTolerance,
                value: trim,
            });
        }
        non_negative(Setting::TrimPulseVolts, settings.trim_pulse_volts)?;
        let window = positive(Setting::TrimWindowSeconds, settings.trim_window_seconds)?;
        if trim > 0.0 && !(window * tick_hz <= WINDOW as f32) {
            return Err(Fault::Setting {
                setting: Setting::TrimWindowSeconds,
                value: window,
            });
        }
        non_negative(Setting::TrimEverySeconds, settings.trim_every_seconds)?;
        let probe = positive(Setting::TrimProbeFraction, settings.trim_probe_fraction)?;
        if !(probe <= 1.0) {
            return Err(Fault::Setting {
                setting: Setting::TrimProbeFraction,
                value: probe,
            });
        }
        // Below Nyquist; and AC volts without a frequency would drive nothing, silently.
        if !(ac_hz < 0.5 * tick_hz) || (settings.ac_volts > 0.0 && ac_hz == 0.0) {
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
            ceiling_volts: max_volts,
            flashed: device,
            estimated: false,
            tick: 0,
            phase: Phase::Ramping,
            monitor: Monitor::new(),
            last_volts: 0.0,
            amplifier_off_ticks: 0,
            last_stretch: f32::NAN,
            same_stretch: 0,
            hold_until: 0,
            trim: Trim {
                params,
                tuned: true,
                count: 0,
                done: settings.trim_tolerance == 0.0,
                previous: None,
                next_trim: u32::MAX,
                window_from: 0,
                window: [f32::NAN; WINDOW],
            },
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

    /// Find the limit and the bias on the chip by the direct solve: the table's cap (its top,
    /// scaled down to a larger margin than the table's) must lie below (1 − margin)·limit,
    /// and the natural frequencies at the two biases must agree. The controller then drives
    /// the solve's bias, capped at (1 − margin)·limit.
    pub fn cross_check(mut self, boot: Boot) -> Result<(Self, Boot), Fault> {
        let settings = self.settings;
        let tuner = Tuner::new(self.device);
        let limit = tuner.limit();
        let margin = guarded(settings.margin);
        let max_volts = tuner.max_bias(margin).map_err(Fault::Tune)?.volts;
        if !(boot.max_volts <= max_volts) {
            return Err(Fault::AboveSafe {
                volts: boot.max_volts,
                max_volts,
            });
        }
        let solved = tuner
            .tune(settings.target_hz, margin)
            .map_err(Fault::Tune)?;
        let table_hz = self
            .device
            .offset_for_bias(boot.table_volts, limit.at.offset)
            .map(|offset| self.device.natural_frequency_hz_at(offset))
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
        self.ceiling_volts = max_volts;
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
    fn set_plan(&mut self, tuned_volts: f32) -> Result<u32, Fault> {
        let s = self.settings;
        // With trim, measure first at a probe bias low enough for a softer plant.
        let bias_volts = if self.trim.done {
            tuned_volts
        } else {
            tuned_volts.min(s.trim_probe_fraction * self.max_volts)
        };
        self.trim.tuned = bias_volts == tuned_volts;
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
            start_tick: 0,
            start_volts: 0.0,
            bias_volts,
            ramp_volts_per_tick: s.slew_volts_per_second / s.tick_hz,
            pulse_ticks: (0, 0),
            pulse_volts: 0.0,
            ac_tick: if self.trim.done {
                ac_tick as u32
            } else {
                u32::MAX
            },
            ac_volts: if s.ac_hz > 0.0 { s.ac_volts } else { 0.0 },
            ac_phase_step: ((s.ac_hz / s.tick_hz) as f64 * 4_294_967_296.0) as u32,
        };
        self.check_range(&plan, tuned_volts)?;
        // The amplifier must give the highest voltage: the ramp's, or the AC's on the bias.
        let peak_volts = plan.peak_volts().max(tuned_volts + plan.ac_volts);
        self.amplifier.code(peak_volts).map_err(Fault::Amplifier)?;
        self.plan = plan;
        // Without trim the model check covers the AC; with it, the ramp and the hold.
        Ok(ac_tick as u32 + check_ticks as u32 + 1)
    }

    /// The plan's whole voltage range against [0, cap], before anything is driven: the ramp
    /// and the bias below the cap (else `AboveSafe`), and the AC about the bias it will ride
    /// on (`ac_bias_volts`: the tuned bias, also while a trim probes lower) neither below
    /// 0 V (the amplifier is unipolar) nor above the cap (else a `Setting` fault naming the
    /// AC amplitude).
    fn check_range(&self, plan: &Plan, ac_bias_volts: f32) -> Result<(), Fault> {
        let bias_peak = plan.start_volts.max(plan.bias_volts);
        if !(bias_peak <= self.max_volts && plan.bias_volts >= 0.0) {
            return Err(Fault::AboveSafe {
                volts: bias_peak,
                max_volts: self.max_volts,
            });
        }
        let ac = plan.ac_volts;
        let ac_peak = ac_bias_volts.max(plan.bias_volts) + ac;
        if !(ac_bias_volts - ac >= 0.0 && ac_peak <= self.max_volts) {
            return Err(Fault::Setting {
                setting: Setting::AcVolts,
                value: ac,
            });
        }
        Ok(())
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The cap fixed at boot from the device flashed, V: no command ever goes above it.
    pub fn ceiling_volts(&self) -> f32 {
        self.ceiling_volts
    }

    /// The cap in force now (the ceiling, or lower after a trim found a softer plant), V.
    pub fn max_volts(&self) -> f32 {
        self.max_volts
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
            if let Some(fault) = self.check_stretch(k, stretch, volts) {
                return self.fault(fault);
            }
        }
        let event = match self.phase {
            Phase::Ramping if self.plan.ramp_volts(k) == self.plan.bias_volts => {
                self.hold_from(k);
                Some(Event::AtBias { volts })
            }
            #[cfg(feature = "trim")]
            Phase::Holding if !self.trim.done && k >= self.hold_until => {
                self.start_measuring(k);
                None
            }
            Phase::Holding if k >= self.plan.ac_tick && self.plan.ac_volts > 0.0 => {
                self.phase = Phase::Driving;
                Some(Event::DriveOn)
            }
            #[cfg(feature = "trim")]
            Phase::Driving if k >= self.trim.next_trim => {
                self.pause_for_trim(k);
                Some(Event::DriveOff)
            }
            #[cfg(feature = "trim")]
            Phase::Measuring => match self.measure(k, inputs.stretch) {
                Ok(event) => event,
                Err(fault) => return self.fault(fault),
            },
            _ => None,
        };
        Output {
            code,
            volts: self.last_volts,
            event,
        }
    }

    /// Pulse now; measure the ring from the pulse's end.
    #[cfg(feature = "trim")]
    fn start_measuring(&mut self, k: u32) {
        let s = self.settings;
        let pulse = libm::roundf(0.5 * s.tick_hz / s.target_hz).max(1.0) as u32;
        let from = k.saturating_add(1);
        self.plan.pulse_ticks = (from, from.saturating_add(pulse));
        self.plan.pulse_volts = s.trim_pulse_volts;
        self.trim.window_from = from.saturating_add(pulse);
        self.trim.window = [f32::NAN; WINDOW];
        self.phase = Phase::Measuring;
    }

    /// Pause the AC and trim again from the bias held (the old secant pair is stale: the
    /// plant has drifted since).
    #[cfg(feature = "trim")]
    fn pause_for_trim(&mut self, k: u32) {
        self.plan.ac_tick = u32::MAX;
        self.trim.done = false;
        self.trim.tuned = true;
        self.trim.count = 0;
        self.trim.previous = None;
        self.trim.next_trim = u32::MAX;
        self.hold_from(k);
    }

    /// Hold the bias from tick `k` for the settle time.
    fn hold_from(&mut self, k: u32) {
        let settle = self.settings.settle_seconds * self.settings.tick_hz;
        self.hold_until = k.saturating_add(settle as u32);
        self.phase = Phase::Holding;
    }

    /// Record this tick's sample; at the window's end, estimate μ and retune, or finish.
    #[cfg(feature = "trim")]
    fn measure(&mut self, k: u32, stretch: Option<f32>) -> Result<Option<Event>, Fault> {
        let s = self.settings;
        let len = (s.trim_window_seconds * s.tick_hz) as usize;
        let Some(at) = k.checked_sub(self.trim.window_from) else {
            return Ok(None);
        };
        let at = at as usize;
        if let (Some(x), Some(slot)) = (stretch, self.trim.window.get_mut(at)) {
            *slot = x;
        }
        if at + 1 < len {
            return Ok(None);
        }
        let bias_volts = self.plan.bias_volts;
        let window = self.trim.window.get(..len).unwrap_or(&self.trim.window);
        let measured_hz = ring_frequency_hz(window, s.tick_hz).map_err(Fault::Trim)?;
        let mu = estimate_shear_modulus(&self.trim.params, bias_volts, measured_hz)
            .map_err(Fault::Trim)?;
        self.trim.params.shear_modulus = mu;
        self.trim.count += 1;
        let converged =
            self.trim.tuned && (measured_hz - s.target_hz).abs() <= s.trim_tolerance * s.target_hz;
        let mut next_bias_volts = bias_volts;
        if converged {
            self.trim.done = true;
            self.plan.ac_tick = k.saturating_add(1);
            self.phase = Phase::Holding;
            if s.trim_every_seconds > 0.0 {
                let every = (s.trim_every_seconds * s.tick_hz) as u32;
                self.trim.next_trim = k.saturating_add(every.max(1));
            }
        } else if self.trim.count >= MAX_TRIMS {
            return Err(Fault::Trim(TrimError::NotConverged {
                measured_hz,
                target_hz: s.target_hz,
            }));
        } else {
            match self.retune(k, measured_hz)? {
                Retune::To { bias_volts } => next_bias_volts = bias_volts,
                Retune::AboveCeiling { needed_volts } => {
                    return Ok(Some(Event::AboveCeiling {
                        needed_volts,
                        ceiling_volts: self.ceiling_volts,
                    }));
                }
            }
        }
        Ok(Some(Event::Trimmed {
            bias_volts,
            measured_hz,
            shear_modulus: mu,
            next_bias_volts,
        }))
    }

    /// The next bias: by the secant through the last two measurements in (Φ², f) once there
    /// are two (it needs no model, so it converges where μ alone cannot describe the plant,
    /// as with viscoelastic networks), else the estimated device's bias for the target. The
    /// cap becomes the estimated device's (1 − margin)·limit. Then ramp there from the bias
    /// now.
    #[cfg(feature = "trim")]
    fn retune(&mut self, k: u32, measured_hz: f32) -> Result<Retune, Fault> {
        let s = self.settings;
        let device = Device::new(self.trim.params).map_err(Fault::Device)?;
        let tuner = Tuner::new(device);
        // The estimate may lower the cap (a softer plant), never raise it past the ceiling.
        let max_volts = tuner
            .max_bias(guarded(s.margin))
            .map_err(Fault::Tune)?
            .volts
            .min(self.ceiling_volts);
        let from = self.plan.bias_volts;
        let squared = from * from;
        let secant = self.trim.previous.and_then(|(p2, pf)| {
            let next = squared + (s.target_hz - measured_hz) * (squared - p2) / (measured_hz - pf);
            // A trust region: a drifting plant (creep) makes a poor secant, and a wild step
            // up is what the model's region cannot vouch for.
            let step = TRIM_SECANT_STEP * from;
            let volts = libm::sqrtf(next).clamp(from - step, from + step);
            (volts > 0.0 && volts + s.ac_volts <= max_volts).then_some(volts)
        });
        self.trim.previous = Some((squared, measured_hz));
        let bias_volts = match secant {
            Some(volts) => volts,
            None => {
                tuner
                    .tune(s.target_hz, guarded(s.margin))
                    .map_err(Fault::Tune)?
                    .volts
            }
        };
        if !(from <= max_volts) {
            return Err(Fault::AboveSafe {
                volts: from,
                max_volts,
            });
        }
        let needed_volts = bias_volts + s.ac_volts;
        if !(needed_volts <= max_volts) && max_volts == self.ceiling_volts {
            // The estimate asks for more than the device flashed allows: say so, and hold.
            self.phase = Phase::Held;
            return Ok(Retune::AboveCeiling { needed_volts });
        }
        let plan = Plan {
            start_tick: k.saturating_add(1),
            start_volts: from,
            bias_volts,
            pulse_ticks: (0, 0),
            ..self.plan
        };
        let cap = self.max_volts;
        self.max_volts = max_volts;
        if let Err(fault) = self.check_range(&plan, bias_volts) {
            self.max_volts = cap;
            return Err(fault);
        }
        self.device = device;
        self.estimated = true;
        self.trim.tuned = true;
        self.plan = plan;
        self.phase = Phase::Ramping;
        Ok(Retune::To { bias_volts })
    }

    /// A stretch sample: a number (`Sensor`), one a device could give (`SensorImplausible`),
    /// not stuck, and inside MODEL.md §6 at this tick's voltage for the device flashed and
    /// for the trim's estimate of it (`Limit`; a state outside the model is loss of tension
    /// 1).
    fn check_stretch(&mut self, k: u32, stretch: f32, volts: f32) -> Option<Fault> {
        if !stretch.is_finite() {
            return Some(Fault::Sensor { value: stretch });
        }
        let (low, high) = self.flashed.plausible_stretch();
        if !(stretch > low && stretch < high) {
            return Some(Fault::SensorImplausible {
                value: stretch,
                low,
                high,
            });
        }
        if let Some(fault) = self.check_stuck(stretch) {
            return Some(fault);
        }
        let tick = u64::from(k);
        let p = volts / self.flashed.volts_per_unit();
        let mut mode = self.monitor.observe(&self.flashed, tick, stretch, p * p);
        if self.estimated && mode.is_none() {
            let p = volts / self.device.volts_per_unit();
            mode = self.monitor.observe(&self.device, tick, stretch, p * p);
        }
        mode.map(|mode| Fault::Limit { mode, tick: k })
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
    // A tick the model cannot step stably, even in substeps, is too slow for this device:
    // the setting is at fault, not the plan.
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
