//! Why the controller will not drive or stopped driving (`Fault`), what it says at a tick
//! (`Event`), and what a tick gives (`Output`).

use core::fmt;

use crate::numerics::decimal::Decimal;

use super::settings::{Setting, SettingError};
use crate::acquire::InputError;
use crate::drive::{CodeError, DacCode};
use crate::estimate::ring::{RingQuality, TrimError};
use crate::model::device::ParamError;
use crate::model::motion::StepError;
use crate::model::safety::FailureMode;
use crate::model::swing::SwingError;
use crate::table::TableError;
use crate::tuning::TuneError;

/// Why the controller will not drive, or stopped driving. Each leaves the output at 0 V.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The device parameters are invalid, or not safe at zero bias.
    Device(ParamError),
    /// A setting is NaN, out of range, or makes the plan too long.
    Setting { setting: Setting, value: f32 },
    /// The AC (`ac_volts`) or the AC and the probe (`probe_volts`) about the bias reach
    /// outside [0 V, the cap in force]: the span they would drive, V.
    Swing {
        setting: Setting,
        value: f32,
        low_volts: f32,
        high_volts: f32,
        max_volts: f32,
    },
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
    /// A sensor sample (stretch, amplifier monitor or current monitor) is NaN or infinite.
    Sensor { value: f32 },
    /// A stretch sample no device could give: the bars more than a frame's length outside
    /// the frame (see `Device::plausible_stretch`).
    SensorImplausible { value: f32, low: f32, high: f32 },
    /// The stretch sensor gave the same sample `samples` times in a row.
    SensorStuck { samples: u32, value: f32 },
    /// The membrane's leakage resistance, measured over a window at a steady bias, fell
    /// below the `leakage_floor_ohms` setting: conduction rising before breakdown.
    Leakage { ohms: f32, floor_ohms: f32 },
    /// The leakage resistance fell from one window to the next faster than
    /// `leakage_fall_per_second` allows, beyond the current's scatter.
    LeakageFalling { ohms: f32, previous_ohms: f32 },
    /// The tracked drive left the target by more than `estimate::lockin::MAX_DETUNING` (the lock is
    /// lost, or the plant is far from the model): Hz.
    TrackLost { drive_hz: f32, target_hz: f32 },
    /// The amplifier's output stayed off the command for `AMPLIFIER_TICKS` ticks.
    AmplifierDisagrees {
        commanded_volts: f32,
        measured_volts: f32,
    },
    /// The measured motion crossed a limit of model.md §6.
    Limit { mode: FailureMode, tick: u32 },
    /// The DAC bus failed (reported by the IO side).
    Bus,
    /// An analog input gave no usable reading this tick (`acquire`): no sample, at a rail,
    /// or outside its plausible range.
    Input(InputError),
    /// The trim could not measure, estimate or converge.
    Trim(TrimError),
    /// The drive's predicted swing about its bias (model.md §7), widened by the margin,
    /// crosses a check of §6, or has no bound in the model: the drive is refused (before it
    /// is on: at boot, `ac`, `target`, a trim's or tracking's new bias).
    DriveSwing(SwingError<f32>),
    /// The measured motion came within the margin of a limit of model.md §6: the stretch
    /// sample fails a check under the tick's voltage raised by 1/(1 − margin). Taken off
    /// before the limit itself.
    NearLimit {
        mode: FailureMode,
        tick: u32,
        stretch: f32,
        volts: f32,
    },
    /// The self-sensed stretch at a steady bias (`volts`), widened by the probe's
    /// uncertainty, lies outside the stretches every device of the table's batch has there
    /// (model.md §10, its capacitance band through the flashed device's C1): the membrane is
    /// not what the image declares.
    OutsideBatch {
        stretch: f32,
        sigma: f32,
        low: f32,
        high: f32,
        volts: f32,
    },
    /// The measured swing of a drive outgrew its prediction (model.md §7): the window's
    /// half-span (with a growth that has not slowed, carried a window ahead) is above the
    /// predicted amplitude widened by 1/(1 − margin) and the sensor's noise (`allowed`), all
    /// in stretch: taken off at the edge of the box the checks passed.
    SwingOutgrown {
        tick: u32,
        half_span: f32,
        growth: f32,
        allowed: f32,
        /// The Q the prediction was made with (0: an entry logged before it was kept).
        quality_factor: f32,
    },
    /// The drive `setting` asks for (the AC's slope, or the bias ramp) is steeper than the
    /// amplifier's declared slew rate (`amplifier_slew_volts_per_second`): both, V/s.
    Steeper {
        setting: Setting,
        volts_per_second: f32,
        amplifier_volts_per_second: f32,
    },
    /// A dead DAC bus drops the output to 0 V at once (the enable line down): from the
    /// plan's highest voltage `from_volts`, the membrane's rebound below its rest
    /// (`Device::check_drop`) comes within the margin of `mode` (model.md §6).
    DropRings { from_volts: f32, mode: FailureMode },
    /// The amplifier's output, of its declared bandwidth (`amplifier_bandwidth_hz`), would
    /// follow the drive `setting` asks for (the AC, or the bias ramp) further off its
    /// command than `amplifier_tolerance_volts`: both, V (the watch would fault it running).
    AmplifierLags {
        setting: Setting,
        following_volts: f32,
        tolerance_volts: f32,
    },
}

impl Fault {
    /// A dead bus's drop from `from_volts` refused by `Device::check_drop`: the check it
    /// comes within the margin of (`DropRings`), or why there is no drop to check.
    pub fn of_drop(from_volts: f32, error: SwingError<f32>) -> Fault {
        match error {
            SwingError::Crosses { mode, .. } => Fault::DropRings { from_volts, mode },
            other => Fault::DriveSwing(other),
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::Device(e) => write!(f, "device: {e}"),
            Fault::Setting { setting, value } => {
                write!(
                    f,
                    "setting `{}` = {} is invalid: it must be {}",
                    setting.key(),
                    Decimal(*value),
                    setting.rule()
                )
            }
            Fault::Swing {
                setting,
                value,
                low_volts,
                high_volts,
                max_volts,
            } => {
                write!(
                    f,
                    "`{}` = {} V about the bias spans {} .. {} V: ",
                    setting.key(),
                    Decimal(*value),
                    Decimal(*low_volts),
                    Decimal(*high_volts)
                )?;
                if *high_volts > *max_volts {
                    write!(f, "above the cap {} V", Decimal(*max_volts))
                } else if *low_volts < 0.0 {
                    write!(f, "below 0 V (the amplifier is unipolar): raise the bias")
                } else {
                    write!(f, "not within [0 V, the cap {} V]", Decimal(*max_volts))
                }
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
                "table gives {} V ({} Hz), the direct solve {} V ({} Hz): they disagree",
                Decimal(*table_volts),
                Decimal(*table_hz),
                Decimal(*solved_volts),
                Decimal(*solved_hz)
            ),
            Fault::AboveSafe { volts, max_volts } => {
                write!(
                    f,
                    "{} V is above the safe maximum {} V",
                    Decimal(*volts),
                    Decimal(*max_volts)
                )
            }
            Fault::PlanCrosses { mode, seconds } => write!(
                f,
                "the plan crosses a limit in the model at {} s: {}",
                Decimal(*seconds),
                mode.description()
            ),
            Fault::PlanFailed(e) => write!(f, "the model run of the plan stopped: {e}"),
            Fault::Amplifier(e) => write!(f, "amplifier: {e}"),
            Fault::Gate { volts, max_volts } => {
                write!(
                    f,
                    "final check refused {} V (safe maximum {} V)",
                    Decimal(*volts),
                    Decimal(*max_volts)
                )
            }
            Fault::Sensor { value } => {
                write!(f, "sensor sample {} is not a number", Decimal(*value))
            }
            Fault::Leakage { ohms, floor_ohms } => write!(
                f,
                "leakage resistance {} Ω is below the floor {} Ω: breakdown may be near",
                Decimal(*ohms),
                Decimal(*floor_ohms)
            ),
            Fault::LeakageFalling {
                ohms,
                previous_ohms,
            } => write!(
                f,
                "leakage resistance fell from {} Ω to {} Ω in one window, faster than \
                 leakage_fall_per_second allows: breakdown may be near",
                Decimal(*previous_ohms),
                Decimal(*ohms)
            ),
            Fault::TrackLost {
                drive_hz,
                target_hz,
            } => write!(
                f,
                "tracked drive at {} Hz, too far from the target {} Hz: lock lost",
                Decimal(*drive_hz),
                Decimal(*target_hz)
            ),
            Fault::Steeper {
                setting,
                volts_per_second,
                amplifier_volts_per_second,
            } => {
                let what = if *setting == Setting::SlewVoltsPerSecond {
                    "the bias ramp (`slew_volts_per_second`)"
                } else {
                    "the AC drive's steepest slope (2π·ac_hz·ac_volts)"
                };
                write!(
                    f,
                    "{what} is {} V/s, steeper than the amplifier's declared slew rate {} V/s \
                     (`amplifier_slew_volts_per_second`): lower `{}`",
                    Decimal(*volts_per_second),
                    Decimal(*amplifier_volts_per_second),
                    setting.key()
                )
            }
            Fault::AmplifierLags {
                setting,
                following_volts,
                tolerance_volts,
            } => {
                let what = if *setting == Setting::SlewVoltsPerSecond {
                    "the bias ramp (`slew_volts_per_second`)"
                } else {
                    "the AC drive (`ac_volts` at `ac_hz`)"
                };
                write!(
                    f,
                    "the amplifier's output (`amplifier_bandwidth_hz`) would follow {what} {} V \
                     off its command, more than `amplifier_tolerance_volts` {} V: lower `{}`",
                    Decimal(*following_volts),
                    Decimal(*tolerance_volts),
                    setting.key()
                )
            }
            Fault::DropRings { from_volts, mode } => write!(
                f,
                "a dead DAC bus would drop {} V to 0 V at once, and the membrane's rebound \
                 would come within the margin of {}: lower the target or the AC",
                Decimal(*from_volts),
                mode.description()
            ),
            Fault::SwingOutgrown {
                tick,
                half_span,
                growth,
                allowed,
                quality_factor,
            } => {
                write!(
                    f,
                    "measured swing outgrew its prediction at tick {tick}: half-span λ {} \
                     (growing {} a window) against {} allowed (the predicted swing",
                    Decimal(*half_span),
                    Decimal(*growth),
                    Decimal(*allowed)
                )?;
                // (0: logged before the Q was kept; NaN: none.)
                if *quality_factor > 0.0 {
                    write!(f, " at Q {}", Decimal(*quality_factor))?;
                }
                write!(
                    f,
                    " widened by the margin): the membrane, its damping or the drive is not \
                     what the image says"
                )
            }
            Fault::OutsideBatch {
                stretch,
                sigma,
                low,
                high,
                volts,
            } => write!(
                f,
                "the membrane is not what the image declares: its capacitance at {} V gives \
                 stretch {} (standard error {}), outside the batch's {} .. {} there",
                Decimal(*volts),
                Decimal(*stretch),
                Decimal(*sigma),
                Decimal(*low),
                Decimal(*high)
            ),
            Fault::SensorImplausible { value, low, high } => write!(
                f,
                "stretch sample {} is outside ({}, {}), where no device can be: sensor fault",
                Decimal(*value),
                Decimal(*low),
                Decimal(*high)
            ),
            Fault::SensorStuck { samples, value } => {
                write!(
                    f,
                    "stretch sensor stuck at {} for {samples} samples",
                    Decimal(*value)
                )
            }
            Fault::AmplifierDisagrees {
                commanded_volts,
                measured_volts,
            } => write!(
                f,
                "amplifier gives {} V for a command of {} V (saturated or failed)",
                Decimal(*measured_volts),
                Decimal(*commanded_volts)
            ),
            Fault::Limit { mode, tick } => {
                write!(f, "measured motion at tick {tick}: {}", mode.description())
            }
            Fault::Bus => write!(f, "DAC bus error"),
            Fault::Input(e) => write!(f, "sensor fault: {e}"),
            Fault::Trim(e) => write!(f, "trim: {e}"),
            Fault::DriveSwing(e) => write!(f, "drive refused: {e}"),
            Fault::NearLimit {
                mode,
                tick,
                stretch,
                volts,
            } => write!(
                f,
                "measured motion near a limit at tick {tick}: λ {} under {} V is within the \
                 margin of {}",
                Decimal(*stretch),
                Decimal(*volts),
                mode.description()
            ),
        }
    }
}

impl core::error::Error for Fault {}

/// When a fault can arise: at boot (a refusal, before anything is driven) or while running
/// (a trip, from 0 V on).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultStage {
    Boot,
    Running,
}

/// Each fault's stable number (from 1: 0 is no fault, in a record) and key, declared once:
/// `Fault::number`, `Fault::key_of` and `FAULT_KEYS` all come from this list. The numbers are
/// what the telemetry record and the fault log keep: a new fault takes the next one, none is
/// ever renumbered (the const check below fails on a gap or a swap).
macro_rules! declare_fault_kinds {
    ($($variant:pat => $number:literal $key:literal,)*) => {
        /// Each fault's key, in the order of its number: `Fault::number` − 1 indexes it (the
        /// telemetry record and the fault log carry the number, a reader shows the key).
        pub const FAULT_KEYS: [&str; [$($number),*].len()] = [$($key),*];

        // The numbers run 1, 2, 3, … in the list's order.
        const _: () = {
            let numbers: &[u8] = &[$($number),*];
            let mut rest = numbers;
            let mut next = 1;
            while let [first, more @ ..] = rest {
                assert!(*first == next, "fault numbers out of order");
                next += 1;
                rest = more;
            }
        };

        impl Fault {
            /// The fault's kind as a number from 1 (0: no fault, in a record).
            pub fn number(&self) -> u8 {
                match self {
                    $($variant => $number,)*
                }
            }

            /// The key of fault number `number` (`Fault::number`), if one has it.
            pub fn key_of(number: u8) -> Option<&'static str> {
                FAULT_KEYS.get(usize::from(number).checked_sub(1)?).copied()
            }
        }
    };
}

declare_fault_kinds! {
    Fault::Device(_) => 1 "device",
    Fault::Setting { .. } => 2 "setting",
    Fault::Swing { .. } => 3 "swing",
    Fault::Table(_) => 4 "table",
    Fault::Tune(_) => 5 "tune",
    Fault::Disagree { .. } => 6 "disagree",
    Fault::AboveSafe { .. } => 7 "above_safe",
    Fault::PlanCrosses { .. } => 8 "plan_crosses",
    Fault::PlanFailed(_) => 9 "plan_failed",
    Fault::Amplifier(_) => 10 "amplifier",
    Fault::Gate { .. } => 11 "gate",
    Fault::Sensor { .. } => 12 "sensor",
    Fault::SensorImplausible { .. } => 13 "sensor_implausible",
    Fault::SensorStuck { .. } => 14 "sensor_stuck",
    Fault::Leakage { .. } => 15 "leakage",
    Fault::LeakageFalling { .. } => 16 "leakage_falling",
    Fault::TrackLost { .. } => 17 "track_lost",
    Fault::AmplifierDisagrees { .. } => 18 "amplifier_disagrees",
    Fault::Limit { .. } => 19 "limit",
    Fault::Bus => 20 "bus",
    Fault::Input(_) => 21 "input",
    Fault::Trim(_) => 22 "trim",
    Fault::DriveSwing(_) => 23 "drive_swing",
    Fault::NearLimit { .. } => 24 "near_limit",
    Fault::OutsideBatch { .. } => 25 "outside_batch",
    Fault::Steeper { .. } => 26 "steeper",
    Fault::SwingOutgrown { .. } => 27 "swing_outgrown",
    Fault::DropRings { .. } => 28 "drop_rings",
    Fault::AmplifierLags { .. } => 29 "amplifier_lags",
}

impl From<SettingError> for Fault {
    fn from(refused: SettingError) -> Self {
        match refused {
            SettingError::Setting { setting, value } => Fault::Setting { setting, value },
            SettingError::Margin { margin } => Fault::Tune(TuneError::InvalidMargin { margin }),
            SettingError::Steeper {
                setting,
                volts_per_second,
                amplifier_volts_per_second,
            } => Fault::Steeper {
                setting,
                volts_per_second,
                amplifier_volts_per_second,
            },
            SettingError::Lags {
                setting,
                following_volts,
                tolerance_volts,
            } => Fault::AmplifierLags {
                setting,
                following_volts,
                tolerance_volts,
            },
        }
    }
}

impl Fault {
    /// Whether this is a boot refusal or a trip while running. A trim's retune runs the boot's
    /// checks again while running: its `Setting`, `Tune`, `Device` and `AboveSafe` faults are
    /// boot-kind refusals that stop a running drive.
    pub fn stage(&self) -> FaultStage {
        match self {
            Fault::Device(_)
            | Fault::Setting { .. }
            | Fault::Swing { .. }
            | Fault::Table(_)
            | Fault::Tune(_)
            | Fault::Disagree { .. }
            | Fault::AboveSafe { .. }
            | Fault::PlanCrosses { .. }
            | Fault::PlanFailed(_)
            | Fault::Amplifier(_)
            | Fault::DriveSwing(_)
            | Fault::Steeper { .. }
            | Fault::DropRings { .. }
            | Fault::AmplifierLags { .. } => FaultStage::Boot,
            Fault::Gate { .. }
            | Fault::Sensor { .. }
            | Fault::SensorImplausible { .. }
            | Fault::SensorStuck { .. }
            | Fault::Leakage { .. }
            | Fault::LeakageFalling { .. }
            | Fault::TrackLost { .. }
            | Fault::AmplifierDisagrees { .. }
            | Fault::Limit { .. }
            | Fault::Bus
            | Fault::Input(_)
            | Fault::Trim(_)
            | Fault::NearLimit { .. }
            | Fault::OutsideBatch { .. }
            | Fault::SwingOutgrown { .. } => FaultStage::Running,
        }
    }
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
        /// How well the ring was resolved, where it was timed with one
        /// (`crate::estimate::ring::RingFit::resolution`; its relative timing error is about
        /// `TIMING_ERROR_TIMES_RESOLUTION` over it).
        resolution: Option<f32>,
        /// The ring's Q from its decay, with the highest its window allows (`None`: a
        /// tracked drive's solve, no window).
        quality: Option<RingQuality>,
    },
    /// The plant needs `needed_volts` (bias and swing: the trim's next bias, tracking's, or
    /// the plan in force under a cap a measurement just lowered), above the cap in force:
    /// the controller holds below it instead (`Phase::Held`), the AC and the probe off. A
    /// plant stiffer than the device flashed is not driven past that device's limit, nor
    /// past the operator's cap, on the strength of a measurement.
    AboveCeiling { needed_volts: f32, cap_volts: f32 },
    /// A fault: from now on down to 0 V at the slew rate (at once for `Bus`), and held there.
    Fault(Fault),
}

/// What kind of thing an `Event` is, for a reader that wants fields rather than words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EventKind {
    AtBias = 1,
    DriveOn = 2,
    DriveOff = 3,
    Trimmed = 4,
    AboveCeiling = 5,
    /// A fault, down to 0 V at the slew rate.
    Fault = 6,
    /// The DAC bus's fault, the amplifier disabled at once.
    BusFault = 7,
}

/// The most numbers an event carries (`Event::values`).
pub const EVENT_VALUES: usize = 7;

impl EventKind {
    pub const ALL: [EventKind; 7] = [
        EventKind::AtBias,
        EventKind::DriveOn,
        EventKind::DriveOff,
        EventKind::Trimmed,
        EventKind::AboveCeiling,
        EventKind::Fault,
        EventKind::BusFault,
    ];

    /// The kind's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            EventKind::AtBias => "at_bias",
            EventKind::DriveOn => "drive_on",
            EventKind::DriveOff => "drive_off",
            EventKind::Trimmed => "trimmed",
            EventKind::AboveCeiling => "above_ceiling",
            EventKind::Fault => "fault",
            EventKind::BusFault => "bus_fault",
        }
    }

    /// The names of `Event::values`, in order, with their units in them.
    pub fn value_names(self) -> &'static [&'static str] {
        match self {
            EventKind::AtBias => &["volts"],
            EventKind::Trimmed => &[
                "bias_volts",
                "measured_hz",
                "shear_modulus_pa",
                "next_bias_volts",
                "resolution",
                "quality_factor",
                "quality_high",
            ],
            EventKind::AboveCeiling => &["needed_volts", "cap_volts"],
            EventKind::DriveOn | EventKind::DriveOff | EventKind::Fault | EventKind::BusFault => {
                &[]
            }
        }
    }

    /// The kind with this number (`kind as u8`).
    pub fn of(number: u8) -> Option<EventKind> {
        EventKind::ALL.into_iter().find(|k| *k as u8 == number)
    }
}

impl Event {
    pub fn kind(&self) -> EventKind {
        match self {
            Event::AtBias { .. } => EventKind::AtBias,
            Event::DriveOn => EventKind::DriveOn,
            Event::DriveOff => EventKind::DriveOff,
            Event::Trimmed { .. } => EventKind::Trimmed,
            Event::AboveCeiling { .. } => EventKind::AboveCeiling,
            Event::Fault(Fault::Bus) => EventKind::BusFault,
            Event::Fault(_) => EventKind::Fault,
        }
    }

    /// Its numbers in the order of `kind().value_names()`, NaN past them (and for a
    /// resolution or a Q not measured); a fault's are in its words.
    pub fn values(&self) -> [f32; EVENT_VALUES] {
        let mut v = [f32::NAN; EVENT_VALUES];
        let given: &[f32] = match *self {
            Event::AtBias { volts } => &[volts],
            Event::Trimmed {
                bias_volts,
                measured_hz,
                shear_modulus,
                next_bias_volts,
                resolution,
                quality,
            } => &[
                bias_volts,
                measured_hz,
                shear_modulus,
                next_bias_volts,
                resolution.unwrap_or(f32::NAN),
                quality.map_or(f32::NAN, |q| q.quality_factor),
                quality.map_or(f32::NAN, |q| q.high),
            ],
            Event::AboveCeiling {
                needed_volts,
                cap_volts,
            } => &[needed_volts, cap_volts],
            _ => &[],
        };
        for (slot, value) in v.iter_mut().zip(given) {
            *slot = *value;
        }
        v
    }
}

/// The words before a fault's own in `Event::Fault`'s: the descent, or (the DAC's bus) the
/// stage off at once.
pub const FAULT_SAID: &str = "fault, down to 0 V at the slew rate";
pub const BUS_FAULT_SAID: &str = "fault, amplifier disabled at once";

/// What the controller said, in words: host-sim's reports and the firmware's link (one
/// wording for both).
impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            // A ramp down to 0 V (`stop`, `clear`, a power-up that waits) ends at rest, not
            // at a bias.
            Event::AtBias { volts: 0.0 } => write!(f, "at rest, 0 V"),
            Event::AtBias { volts } => write!(f, "at bias, {volts} V"),
            Event::DriveOn => write!(f, "AC drive on"),
            Event::DriveOff => write!(f, "AC drive paused, to trim again"),
            Event::Trimmed {
                bias_volts,
                measured_hz,
                shear_modulus,
                next_bias_volts,
                resolution,
                quality,
            } => {
                write!(f, "trim: {measured_hz:.4} Hz measured at {bias_volts:.1} V")?;
                if let Some(r) = resolution {
                    write!(f, " (resolution {r:.0})")?;
                }
                if let Some(q) = quality {
                    write!(f, ", Q {:.0} (at most {:.0})", q.quality_factor, q.high)?;
                }
                write!(
                    f,
                    ", μ estimated {:.2} kPa, next bias {next_bias_volts:.1} V",
                    shear_modulus / 1e3
                )
            }
            Event::AboveCeiling {
                needed_volts,
                cap_volts,
            } => write!(
                f,
                "trim needs {needed_volts:.1} V, above the cap in force {cap_volts:.1} V of the \
                 device flashed: holding the bias"
            ),
            Event::Fault(fault) => {
                let what = if fault == Fault::Bus {
                    BUS_FAULT_SAID
                } else {
                    FAULT_SAID
                };
                write!(f, "{what}: {fault}")
            }
        }
    }
}

/// One tick's output: the DAC code, the voltage it gives, and what happened.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    pub code: DacCode,
    pub volts: f32,
    pub event: Option<Event>,
}
