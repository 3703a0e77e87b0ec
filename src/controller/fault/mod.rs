//! Why the controller will not drive or stopped driving (`Fault`): each fault declared once,
//! below, with its number, key, stage, words and the figures the fault log keeps of it.

mod declare;
mod figures;
#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)] // a test fails by panicking
mod tests;

use crate::numerics::decimal::Decimal;

use super::settings::{Setting, SettingError};
use crate::acquire::InputError;
use crate::drive::CodeError;
use crate::estimate::ring::TrimError;
use crate::model::device::ParamError;
use crate::model::motion::StepError;
use crate::model::safety::FailureMode;
use crate::model::swing::SwingError;
use crate::table::TableError;
use crate::tuning::TuneError;

use declare::declare_faults;
pub use figures::Figures;
use figures::{Figure, Put, Take};
#[cfg(test)]
use tests::Sample;

/// When a fault can arise: at boot (a refusal, before anything is driven) or while running
/// (a trip, from 0 V on).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultStage {
    Boot,
    Running,
}

declare_faults! {
    /// Why the controller will not drive, or stopped driving. Each leaves the output at 0 V.
    ///
    /// Each entry: the variant, `= number "key" Stage` (the number and key are what the
    /// telemetry record and the fault log keep: a new fault takes the next number), and its
    /// words. Boot faults are refusals before anything is driven (a trim's retune runs them
    /// again while running, and they stop the drive); running ones are trips.
    #[derive(Clone, Copy, Debug, PartialEq)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub enum Fault {
        /// The device parameters are invalid, or not safe at zero bias.
        Device(e: ParamError) = 1 "device" Boot
            => |f| write!(f, "device: {e}");

        /// A setting is NaN, out of range, or makes the plan too long.
        Setting { setting: Setting, value: f32 } = 2 "setting" Boot
            => |f| write!(
                f,
                "setting `{}` = {} is invalid: it must be {}",
                setting.key(),
                Decimal(*value),
                setting.rule()
            );

        /// The AC (`ac_volts`) or the AC and the probe (`probe_volts`) about the bias reach
        /// outside [0 V, the cap in force]: the span they would drive, V.
        Swing {
            setting: Setting,
            value: f32,
            low_volts: f32,
            high_volts: f32,
            max_volts: f32,
        } = 3 "swing" Boot
            => |f| {
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
            };

        /// The tuning table is corrupted, out of order, for another device, or misses the
        /// target.
        Table(e: TableError) = 4 "table" Boot
            => |f| write!(f, "table: {e}");

        /// The direct solve cannot reach the target (out of range, bad target or margin).
        Tune(e: TuneError<f32>) = 5 "tune" Boot
            => |f| write!(f, "tuning: {e}");

        /// The natural frequencies at the table's bias and at the direct solve's differ by
        /// more than the agreement.
        Disagree {
            table_volts: f32,
            table_hz: f32,
            solved_volts: f32,
            solved_hz: f32,
        } = 6 "disagree" Boot
            => |f| write!(
                f,
                "table gives {} V ({} Hz), the direct solve {} V ({} Hz): they disagree",
                Decimal(*table_volts),
                Decimal(*table_hz),
                Decimal(*solved_volts),
                Decimal(*solved_hz)
            );

        /// A voltage of the plan or the table is above the safe maximum.
        AboveSafe { volts: f32, max_volts: f32 } = 7 "above_safe" Boot
            => |f| write!(
                f,
                "{} V is above the safe maximum {} V",
                Decimal(*volts),
                Decimal(*max_volts)
            );

        /// The model run of the plan crossed a limit (ramp too fast, AC too strong).
        PlanCrosses { mode: FailureMode, seconds: f32 } = 8 "plan_crosses" Boot
            => |f| write!(
                f,
                "the plan crosses a limit in the model at {} s: {}",
                Decimal(*seconds),
                mode.description()
            );

        /// The model run of the plan could not go on (left the model's range, NaN).
        PlanFailed(e: StepError<f32>) = 9 "plan_failed" Boot
            => |f| write!(f, "the model run of the plan stopped: {e}");

        /// The amplifier cannot give a voltage of the plan.
        Amplifier(e: CodeError) = 10 "amplifier" Boot
            => |f| write!(f, "amplifier: {e}");

        /// A commanded voltage failed the final check (never expected: a guard of last
        /// resort).
        Gate { volts: f32, max_volts: f32 } = 11 "gate" Running
            => |f| write!(
                f,
                "final check refused {} V (safe maximum {} V)",
                Decimal(*volts),
                Decimal(*max_volts)
            );

        /// A sensor sample (stretch, amplifier monitor or current monitor) is NaN or
        /// infinite.
        Sensor { value: f32 } = 12 "sensor" Running
            => |f| write!(f, "sensor sample {} is not a number", Decimal(*value));

        /// A stretch sample no device could give: the bars more than a frame's length
        /// outside the frame (see `Device::plausible_stretch`).
        SensorImplausible { value: f32, low: f32, high: f32 } = 13 "sensor_implausible" Running
            => |f| write!(
                f,
                "stretch sample {} is outside ({}, {}), where no device can be: sensor fault",
                Decimal(*value),
                Decimal(*low),
                Decimal(*high)
            );

        /// The stretch sensor gave the same sample `samples` times in a row.
        SensorStuck { samples: u32, value: f32 } = 14 "sensor_stuck" Running
            => |f| write!(
                f,
                "stretch sensor stuck at {} for {samples} samples",
                Decimal(*value)
            );

        /// The membrane's leakage resistance, measured over a window at a steady bias, fell
        /// below the `leakage_floor_ohms` setting: conduction rising before breakdown.
        Leakage { ohms: f32, floor_ohms: f32 } = 15 "leakage" Running
            => |f| write!(
                f,
                "leakage resistance {} Ω is below the floor {} Ω: breakdown may be near",
                Decimal(*ohms),
                Decimal(*floor_ohms)
            );

        /// The leakage resistance fell from one window to the next faster than
        /// `leakage_fall_per_second` allows, beyond the current's scatter.
        LeakageFalling { ohms: f32, previous_ohms: f32 } = 16 "leakage_falling" Running
            => |f| write!(
                f,
                "leakage resistance fell from {} Ω to {} Ω in one window, faster than \
                 leakage_fall_per_second allows: breakdown may be near",
                Decimal(*previous_ohms),
                Decimal(*ohms)
            );

        /// The tracked drive left the target by more than `estimate::lockin::MAX_DETUNING`
        /// (the lock is lost, or the plant is far from the model): Hz.
        TrackLost { drive_hz: f32, target_hz: f32 } = 17 "track_lost" Running
            => |f| write!(
                f,
                "tracked drive at {} Hz, too far from the target {} Hz: lock lost",
                Decimal(*drive_hz),
                Decimal(*target_hz)
            );

        /// The amplifier's output stayed off the command for `AMPLIFIER_TICKS` ticks.
        AmplifierDisagrees {
            commanded_volts: f32,
            measured_volts: f32,
        } = 18 "amplifier_disagrees" Running
            => |f| write!(
                f,
                "amplifier gives {} V for a command of {} V (saturated or failed)",
                Decimal(*measured_volts),
                Decimal(*commanded_volts)
            );

        /// The measured motion crossed a limit of model.md §6.
        Limit { mode: FailureMode, tick: u32 } = 19 "limit" Running
            => |f| write!(f, "measured motion at tick {tick}: {}", mode.description());

        /// The DAC bus failed (reported by the IO side).
        Bus = 20 "bus" Running
            => |f| write!(f, "DAC bus error");

        /// An analog input gave no usable reading this tick (`acquire`): no sample, at a
        /// rail, or outside its plausible range.
        Input(e: InputError) = 21 "input" Running
            => |f| write!(f, "sensor fault: {e}");

        /// The trim could not measure, estimate or converge.
        Trim(e: TrimError) = 22 "trim" Running
            => |f| write!(f, "trim: {e}");

        /// The drive's predicted swing about its bias (model.md §7), widened by the margin,
        /// crosses a check of §6, or has no bound in the model: the drive is refused (before
        /// it is on: at boot, `ac`, `target`, a trim's or tracking's new bias).
        DriveSwing(e: SwingError<f32>) = 23 "drive_swing" Boot
            => |f| write!(f, "drive refused: {e}");

        /// The measured motion came within the margin of a limit of model.md §6: the stretch
        /// sample fails a check under the tick's voltage raised by 1/(1 − margin). Taken off
        /// before the limit itself.
        NearLimit {
            mode: FailureMode,
            tick: u32,
            stretch: f32,
            volts: f32,
        } = 24 "near_limit" Running
            => |f| write!(
                f,
                "measured motion near a limit at tick {tick}: λ {} under {} V is within the \
                 margin of {}",
                Decimal(*stretch),
                Decimal(*volts),
                mode.description()
            );

        /// The self-sensed stretch at a steady bias (`volts`), widened by the probe's
        /// uncertainty, lies outside the stretches every device of the table's batch has
        /// there (model.md §10, its capacitance band through the flashed device's C1): the
        /// membrane is not what the image declares.
        OutsideBatch {
            stretch: f32,
            sigma: f32,
            low: f32,
            high: f32,
            volts: f32,
        } = 25 "outside_batch" Running
            => |f| write!(
                f,
                "the membrane is not what the image declares: its capacitance at {} V gives \
                 stretch {} (standard error {}), outside the batch's {} .. {} there",
                Decimal(*volts),
                Decimal(*stretch),
                Decimal(*sigma),
                Decimal(*low),
                Decimal(*high)
            );

        /// The drive `setting` asks for (the AC's slope, or the bias ramp) is steeper than
        /// the amplifier's declared slew rate (`amplifier_slew_volts_per_second`): both, V/s.
        Steeper {
            setting: Setting,
            volts_per_second: f32,
            amplifier_volts_per_second: f32,
        } = 26 "steeper" Boot
            => |f| {
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
            };

        /// The measured swing of a drive outgrew its prediction (model.md §7): the window's
        /// half-span (with a growth that has not slowed, carried a window ahead) is above the
        /// predicted amplitude widened by 1/(1 − margin) and the sensor's noise (`allowed`),
        /// all in stretch: taken off at the edge of the box the checks passed.
        SwingOutgrown {
            tick: u32,
            half_span: f32,
            growth: f32,
            allowed: f32,
            /// The Q the prediction was made with (0: an entry logged before it was kept).
            quality_factor: f32,
        } = 27 "swing_outgrown" Running
            => |f| {
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
            };

        /// A dead DAC bus drops the output to 0 V at once (the enable line down): from the
        /// plan's highest voltage `from_volts`, the membrane's rebound below its rest
        /// (`Device::check_drop`) comes within the margin of `mode` (model.md §6).
        DropRings { from_volts: f32, mode: FailureMode } = 28 "drop_rings" Boot
            => |f| write!(
                f,
                "a dead DAC bus would drop {} V to 0 V at once, and the membrane's rebound \
                 would come within the margin of {}: lower the target or the AC",
                Decimal(*from_volts),
                mode.description()
            );

        /// The amplifier's output, of its declared bandwidth (`amplifier_bandwidth_hz`),
        /// would follow the drive `setting` asks for (the AC, or the bias ramp) further off
        /// its command than `amplifier_tolerance_volts`: both, V (the watch would fault it
        /// running).
        AmplifierLags {
            setting: Setting,
            following_volts: f32,
            tolerance_volts: f32,
        } = 29 "amplifier_lags" Boot
            => |f| {
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
            };
    }
}

impl core::error::Error for Fault {}

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
