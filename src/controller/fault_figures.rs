//! A fault as the fault log keeps it ([`Figures`]): its number, a few indices (which variant,
//! which setting, mode or input) and its numbers: all it takes to write its sentence again,
//! whole, with every figure in it (the reading, the limit, the voltage), in 32 bytes, where
//! the sentence itself (up to a few hundred bytes) would not fit a log entry.
//!
//! `Fault::figures` and `Fault::from_figures` are each other's inverse on every fault the
//! controller makes (tested on one of each kind); a model run's step count is kept to 2³² − 1.
//!
//! Flash holds positions: in `Setting::ALL`, `Field::ALL`, `FailureMode::ALL`, `Channel::ALL`,
//! `Stall::ALL`, `Method::ALL`, `Resonance::ALL`, `RingInput::ALL`, `NoiseFrom::ALL`,
//! `device::SCALES`, and each error's variant numbers below. They are part of the log's
//! layout: a list only grows at its end (a test pins each order), or an older entry would
//! read as another fault.

use crate::acquire::{Channel, InputError, Stall};
use crate::drive::CodeError;
use crate::estimate::ring::{NoiseFrom, RingInput, TrimError};
use crate::model::device::{Field, ParamError, Problem, SCALES};
use crate::model::motion::{Drive, Method, StepError};
use crate::model::safety::FailureMode;
use crate::model::swing::{Resonance, SwingError};
use crate::table::TableError;
use crate::tuning::TuneError;

use super::{Fault, Setting};

/// The indices a fault's figures hold, at most.
pub const DETAILS: usize = 4;
/// The numbers (f32 or u32, as their bits) a fault's figures hold, at most.
pub const VALUES: usize = 7;

/// A fault's number (`Fault::number`), its indices and its numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Figures {
    pub number: u8,
    pub details: [u8; DETAILS],
    pub values: [u32; VALUES],
}

/// Writes a fault's indices and numbers in order (past the room: dropped, and the round
/// trip's test fails).
struct Put(Figures, usize, usize);

impl Put {
    fn d(&mut self, x: u8) -> &mut Self {
        if let Some(slot) = self.0.details.get_mut(self.1) {
            *slot = x;
        }
        self.1 += 1;
        self
    }
    fn at<T: PartialEq>(&mut self, all: &[T], x: &T) -> &mut Self {
        let k = all.iter().position(|a| a == x).unwrap_or(usize::MAX);
        self.d(u8::try_from(k).unwrap_or(u8::MAX))
    }
    fn u(&mut self, x: u32) -> &mut Self {
        if let Some(slot) = self.0.values.get_mut(self.2) {
            *slot = x;
        }
        self.2 += 1;
        self
    }
    fn f(&mut self, x: f32) -> &mut Self {
        self.u(x.to_bits())
    }
    fn n(&mut self, x: usize) -> &mut Self {
        self.u(u32::try_from(x).unwrap_or(u32::MAX))
    }
}

/// Reads them back in the same order: `None` past the room or for an index no value has
/// (bytes of another version, or damaged); zero past what was written.
struct Take<'a>(&'a Figures, usize, usize);

impl Take<'_> {
    fn d(&mut self) -> Option<u8> {
        let x = self.0.details.get(self.1).copied();
        self.1 += 1;
        x
    }
    fn at<T: Copy>(&mut self, all: &[T]) -> Option<T> {
        all.get(usize::from(self.d()?)).copied()
    }
    fn u(&mut self) -> Option<u32> {
        let x = self.0.values.get(self.2).copied();
        self.2 += 1;
        x
    }
    fn f(&mut self) -> Option<f32> {
        self.u().map(f32::from_bits)
    }
    fn u16(&mut self) -> Option<u16> {
        u16::try_from(self.u()?).ok()
    }
    fn n(&mut self) -> Option<usize> {
        usize::try_from(self.u()?).ok()
    }
}

impl Fault {
    /// What the fault log keeps of this fault.
    pub fn figures(&self) -> Figures {
        let mut p = Put(
            Figures {
                number: self.number(),
                ..Figures::default()
            },
            0,
            0,
        );
        match *self {
            Fault::Device(ParamError { field, problem }) => {
                p.at(&Field::ALL, &field);
                match problem {
                    Problem::NotFinite => p.d(0),
                    Problem::NotPositive => p.d(1),
                    Problem::Negative => p.d(2),
                    Problem::NoTension1AtZeroBias => p.d(3),
                    Problem::NoTension2AtZeroBias => p.d(4),
                    Problem::StretchLimitAtZeroBias => p.d(5),
                    Problem::UnsafeAtZeroBias { mode } => p.d(6).at(&FailureMode::ALL, &mode),
                    Problem::DerivedNotFinite { scale } => p.d(7).at(&SCALES, &scale),
                };
            }
            Fault::Setting { setting, value } => {
                p.at(&Setting::ALL, &setting).f(value);
            }
            Fault::Swing {
                setting,
                value,
                low_volts,
                high_volts,
                max_volts,
            } => {
                p.at(&Setting::ALL, &setting)
                    .f(value)
                    .f(low_volts)
                    .f(high_volts)
                    .f(max_volts);
            }
            Fault::Table(e) => table(&mut p, e),
            Fault::Tune(e) => match e {
                TuneError::InvalidTarget { target_hz } => {
                    p.d(0).f(target_hz);
                }
                TuneError::InvalidMargin { margin } => {
                    p.d(1).f(margin);
                }
                TuneError::OutOfRange {
                    target_hz,
                    low_hz,
                    high_hz,
                } => {
                    p.d(2).f(target_hz).f(low_hz).f(high_hz);
                }
            },
            Fault::Disagree {
                table_volts,
                table_hz,
                solved_volts,
                solved_hz,
            } => {
                p.f(table_volts).f(table_hz).f(solved_volts).f(solved_hz);
            }
            Fault::AboveSafe { volts, max_volts } | Fault::Gate { volts, max_volts } => {
                p.f(volts).f(max_volts);
            }
            Fault::PlanCrosses { mode, seconds } => {
                p.at(&FailureMode::ALL, &mode).f(seconds);
            }
            Fault::PlanFailed(e) => step(&mut p, e),
            Fault::Amplifier(e) => match e {
                CodeError::BadFullScale { volts } => {
                    p.d(0).f(volts);
                }
                CodeError::OutOfRange { volts, max_volts } => {
                    p.d(1).f(volts).f(max_volts);
                }
                CodeError::BadRail { volts } => {
                    p.d(2).f(volts);
                }
            },
            Fault::Sensor { value } => {
                p.f(value);
            }
            Fault::SensorImplausible { value, low, high } => {
                p.f(value).f(low).f(high);
            }
            Fault::SensorStuck { samples, value } => {
                p.u(samples).f(value);
            }
            Fault::Leakage { ohms, floor_ohms } => {
                p.f(ohms).f(floor_ohms);
            }
            Fault::LeakageFalling {
                ohms,
                previous_ohms,
            } => {
                p.f(ohms).f(previous_ohms);
            }
            Fault::TrackLost {
                drive_hz,
                target_hz,
            } => {
                p.f(drive_hz).f(target_hz);
            }
            Fault::AmplifierDisagrees {
                commanded_volts,
                measured_volts,
            } => {
                p.f(commanded_volts).f(measured_volts);
            }
            Fault::Limit { mode, tick } => {
                p.at(&FailureMode::ALL, &mode).u(tick);
            }
            Fault::Bus => {}
            Fault::Input(e) => input(&mut p, e),
            Fault::Trim(e) => trim(&mut p, e),
            Fault::DriveSwing(e) => swing(&mut p, e),
            Fault::NearLimit {
                mode,
                tick,
                stretch,
                volts,
            } => {
                p.at(&FailureMode::ALL, &mode).u(tick).f(stretch).f(volts);
            }
            Fault::OutsideBatch {
                stretch,
                sigma,
                low,
                high,
                volts,
            } => {
                p.f(stretch).f(sigma).f(low).f(high).f(volts);
            }
            Fault::SwingOutgrown {
                tick,
                half_span,
                growth,
                allowed,
                quality_factor,
            } => {
                p.u(tick)
                    .f(half_span)
                    .f(growth)
                    .f(allowed)
                    .f(quality_factor);
            }
            Fault::Steeper {
                setting,
                volts_per_second,
                amplifier_volts_per_second,
            } => {
                p.at(&Setting::ALL, &setting)
                    .f(volts_per_second)
                    .f(amplifier_volts_per_second);
            }
            Fault::DropRings { from_volts, mode } => {
                p.at(&FailureMode::ALL, &mode).f(from_volts);
            }
            Fault::AmplifierLags {
                setting,
                following_volts,
                tolerance_volts,
            } => {
                p.at(&Setting::ALL, &setting)
                    .f(following_volts)
                    .f(tolerance_volts);
            }
        }
        p.0
    }

    /// The fault its figures were made of; `None` if they are not a fault's.
    pub fn from_figures(fig: &Figures) -> Option<Fault> {
        let mut t = Take(fig, 0, 0);
        let t = &mut t;
        Some(match fig.number {
            1 => {
                let field = t.at(&Field::ALL)?;
                let problem = match t.d()? {
                    0 => Problem::NotFinite,
                    1 => Problem::NotPositive,
                    2 => Problem::Negative,
                    3 => Problem::NoTension1AtZeroBias,
                    4 => Problem::NoTension2AtZeroBias,
                    5 => Problem::StretchLimitAtZeroBias,
                    6 => Problem::UnsafeAtZeroBias {
                        mode: t.at(&FailureMode::ALL)?,
                    },
                    7 => Problem::DerivedNotFinite {
                        scale: t.at(&SCALES)?,
                    },
                    _ => return None,
                };
                Fault::Device(ParamError { field, problem })
            }
            2 => Fault::Setting {
                setting: t.at(&Setting::ALL)?,
                value: t.f()?,
            },
            3 => Fault::Swing {
                setting: t.at(&Setting::ALL)?,
                value: t.f()?,
                low_volts: t.f()?,
                high_volts: t.f()?,
                max_volts: t.f()?,
            },
            4 => Fault::Table(table_back(t)?),
            5 => Fault::Tune(match t.d()? {
                0 => TuneError::InvalidTarget { target_hz: t.f()? },
                1 => TuneError::InvalidMargin { margin: t.f()? },
                2 => TuneError::OutOfRange {
                    target_hz: t.f()?,
                    low_hz: t.f()?,
                    high_hz: t.f()?,
                },
                _ => return None,
            }),
            6 => Fault::Disagree {
                table_volts: t.f()?,
                table_hz: t.f()?,
                solved_volts: t.f()?,
                solved_hz: t.f()?,
            },
            7 => Fault::AboveSafe {
                volts: t.f()?,
                max_volts: t.f()?,
            },
            8 => Fault::PlanCrosses {
                mode: t.at(&FailureMode::ALL)?,
                seconds: t.f()?,
            },
            9 => Fault::PlanFailed(step_back(t)?),
            10 => Fault::Amplifier(match t.d()? {
                0 => CodeError::BadFullScale { volts: t.f()? },
                1 => CodeError::OutOfRange {
                    volts: t.f()?,
                    max_volts: t.f()?,
                },
                2 => CodeError::BadRail { volts: t.f()? },
                _ => return None,
            }),
            11 => Fault::Gate {
                volts: t.f()?,
                max_volts: t.f()?,
            },
            12 => Fault::Sensor { value: t.f()? },
            13 => Fault::SensorImplausible {
                value: t.f()?,
                low: t.f()?,
                high: t.f()?,
            },
            14 => Fault::SensorStuck {
                samples: t.u()?,
                value: t.f()?,
            },
            15 => Fault::Leakage {
                ohms: t.f()?,
                floor_ohms: t.f()?,
            },
            16 => Fault::LeakageFalling {
                ohms: t.f()?,
                previous_ohms: t.f()?,
            },
            17 => Fault::TrackLost {
                drive_hz: t.f()?,
                target_hz: t.f()?,
            },
            18 => Fault::AmplifierDisagrees {
                commanded_volts: t.f()?,
                measured_volts: t.f()?,
            },
            19 => Fault::Limit {
                mode: t.at(&FailureMode::ALL)?,
                tick: t.u()?,
            },
            20 => Fault::Bus,
            21 => Fault::Input(input_back(t)?),
            22 => Fault::Trim(trim_back(t)?),
            23 => Fault::DriveSwing(swing_back(t)?),
            24 => Fault::NearLimit {
                mode: t.at(&FailureMode::ALL)?,
                tick: t.u()?,
                stretch: t.f()?,
                volts: t.f()?,
            },
            25 => Fault::OutsideBatch {
                stretch: t.f()?,
                sigma: t.f()?,
                low: t.f()?,
                high: t.f()?,
                volts: t.f()?,
            },
            26 => Fault::Steeper {
                setting: t.at(&Setting::ALL)?,
                volts_per_second: t.f()?,
                amplifier_volts_per_second: t.f()?,
            },
            27 => Fault::SwingOutgrown {
                tick: t.u()?,
                half_span: t.f()?,
                growth: t.f()?,
                allowed: t.f()?,
                quality_factor: t.f()?,
            },
            28 => Fault::DropRings {
                mode: t.at(&FailureMode::ALL)?,
                from_volts: t.f()?,
            },
            29 => Fault::AmplifierLags {
                setting: t.at(&Setting::ALL)?,
                following_volts: t.f()?,
                tolerance_volts: t.f()?,
            },
            _ => return None,
        })
    }
}

fn table(p: &mut Put, e: TableError) {
    match e {
        TableError::TooShort { bytes } => p.d(0).n(bytes),
        TableError::BadMagic => p.d(1),
        TableError::UnsupportedVersion { version } => p.d(2).u(version.into()),
        TableError::BadCount { points } => p.d(3).u(points.into()),
        TableError::WrongLength { expected, bytes } => p.d(4).n(expected).n(bytes),
        TableError::BadCrc { stored, computed } => p.d(5).u(stored).u(computed),
        TableError::NotFinite { index } => p.d(6).u(index.into()),
        TableError::NotMonotone { index } => p.d(7).u(index.into()),
        TableError::OtherDevice { field } => p.d(8).at(&Field::ALL, &field),
        TableError::OutOfRange {
            target_hz,
            low_hz,
            high_hz,
        } => p.d(9).f(target_hz).f(low_hz).f(high_hz),
        TableError::BufferTooSmall { needed } => p.d(10).n(needed),
        // The field by its place in `Field::ALL`, u32::MAX for the guaranteed limit.
        TableError::BadBatch { field } => p.d(11).u(field
            .and_then(|f| Field::ALL.iter().position(|&g| g == f))
            .map_or(u32::MAX, |k| k as u32)),
        TableError::BadCapacitance { index } => p.d(12).u(index.into()),
    };
}

fn table_back(t: &mut Take) -> Option<TableError> {
    Some(match t.d()? {
        0 => TableError::TooShort { bytes: t.n()? },
        1 => TableError::BadMagic,
        2 => TableError::UnsupportedVersion { version: t.u16()? },
        3 => TableError::BadCount { points: t.u16()? },
        4 => TableError::WrongLength {
            expected: t.n()?,
            bytes: t.n()?,
        },
        5 => TableError::BadCrc {
            stored: t.u()?,
            computed: t.u()?,
        },
        6 => TableError::NotFinite { index: t.u16()? },
        7 => TableError::NotMonotone { index: t.u16()? },
        8 => TableError::OtherDevice {
            field: t.at(&Field::ALL)?,
        },
        9 => TableError::OutOfRange {
            target_hz: t.f()?,
            low_hz: t.f()?,
            high_hz: t.f()?,
        },
        10 => TableError::BufferTooSmall { needed: t.n()? },
        11 => TableError::BadBatch {
            field: match t.u()? {
                u32::MAX => None,
                k => Some(*Field::ALL.get(usize::try_from(k).ok()?)?),
            },
        },
        12 => TableError::BadCapacitance { index: t.u16()? },
        _ => return None,
    })
}

/// A model run's step count, kept to 2³² − 1.
fn tick32(tick: u64) -> u32 {
    u32::try_from(tick).unwrap_or(u32::MAX)
}

fn step(p: &mut Put, e: StepError<f32>) {
    match e {
        StepError::InvalidStep { step_seconds } => p.d(0).f(step_seconds),
        StepError::InvalidDrive { drive } => p.d(1).f(drive.bias).f(drive.ac).f(drive.omega),
        StepError::InvalidRange { low, high } => p.d(2).f(low).f(high),
        StepError::Unstable {
            method,
            step_seconds,
            max_step_seconds,
        } => p
            .d(3)
            .at(&Method::ALL, &method)
            .f(step_seconds)
            .f(max_step_seconds),
        StepError::LeftGuardedRange { tick, stretch } => p.d(4).u(tick32(tick)).f(stretch),
        StepError::NewtonFailed { tick } => p.d(5).u(tick32(tick)),
        StepError::NonFinite { tick } => p.d(6).u(tick32(tick)),
        StepError::DriveNotGuarded {
            least_bias_dimless_squared,
            guarded_bias_dimless_squared,
        } => p
            .d(7)
            .f(least_bias_dimless_squared)
            .f(guarded_bias_dimless_squared),
    };
}

fn step_back(t: &mut Take) -> Option<StepError<f32>> {
    Some(match t.d()? {
        0 => StepError::InvalidStep {
            step_seconds: t.f()?,
        },
        1 => StepError::InvalidDrive {
            drive: Drive {
                bias: t.f()?,
                ac: t.f()?,
                omega: t.f()?,
            },
        },
        2 => StepError::InvalidRange {
            low: t.f()?,
            high: t.f()?,
        },
        3 => StepError::Unstable {
            method: t.at(&Method::ALL)?,
            step_seconds: t.f()?,
            max_step_seconds: t.f()?,
        },
        4 => StepError::LeftGuardedRange {
            tick: t.u()?.into(),
            stretch: t.f()?,
        },
        5 => StepError::NewtonFailed {
            tick: t.u()?.into(),
        },
        6 => StepError::NonFinite {
            tick: t.u()?.into(),
        },
        7 => StepError::DriveNotGuarded {
            least_bias_dimless_squared: t.f()?,
            guarded_bias_dimless_squared: t.f()?,
        },
        _ => return None,
    })
}

fn input(p: &mut Put, e: InputError) {
    match e {
        InputError::NoSamples { channel } => p.d(0).at(&Channel::ALL, &channel),
        InputError::Stalled { stall, recovered } => p.d(1).at(&Stall::ALL, &stall).u(recovered),
        InputError::NotACode { channel, code } => p.d(2).at(&Channel::ALL, &channel).u(code.into()),
        InputError::AtRail { channel, mean_code } => {
            p.d(3).at(&Channel::ALL, &channel).f(mean_code)
        }
        InputError::Implausible {
            channel,
            reading,
            low,
            high,
        } => p.d(4).at(&Channel::ALL, &channel).f(reading).f(low).f(high),
    };
}

fn input_back(t: &mut Take) -> Option<InputError> {
    Some(match t.d()? {
        0 => InputError::NoSamples {
            channel: t.at(&Channel::ALL)?,
        },
        1 => InputError::Stalled {
            stall: t.at(&Stall::ALL)?,
            recovered: t.u()?,
        },
        2 => InputError::NotACode {
            channel: t.at(&Channel::ALL)?,
            code: t.u16()?,
        },
        3 => InputError::AtRail {
            channel: t.at(&Channel::ALL)?,
            mean_code: t.f()?,
        },
        4 => InputError::Implausible {
            channel: t.at(&Channel::ALL)?,
            reading: t.f()?,
            low: t.f()?,
            high: t.f()?,
        },
        _ => return None,
    })
}

fn trim(p: &mut Put, e: TrimError) {
    match e {
        TrimError::NoRing { crossings } => p.d(0).u(crossings.into()),
        TrimError::NoEstimate { measured_hz, volts } => p.d(1).f(measured_hz).f(volts),
        TrimError::NotConverged {
            measured_hz,
            target_hz,
        } => p.d(2).f(measured_hz).f(target_hz),
        TrimError::Unresolvable {
            input,
            from,
            resolution,
            needed,
            ring,
            noise,
        } => p
            .d(3)
            .at(&RingInput::ALL, &input)
            .at(&NoiseFrom::ALL, &from)
            .f(resolution)
            .f(needed)
            .f(ring)
            .f(noise),
        TrimError::OutsideBatch {
            shear_modulus,
            low,
            high,
        } => p.d(4).f(shear_modulus).f(low).f(high),
    };
}

fn trim_back(t: &mut Take) -> Option<TrimError> {
    Some(match t.d()? {
        0 => TrimError::NoRing {
            crossings: t.u16()?,
        },
        1 => TrimError::NoEstimate {
            measured_hz: t.f()?,
            volts: t.f()?,
        },
        2 => TrimError::NotConverged {
            measured_hz: t.f()?,
            target_hz: t.f()?,
        },
        4 => TrimError::OutsideBatch {
            shear_modulus: t.f()?,
            low: t.f()?,
            high: t.f()?,
        },
        3 => TrimError::Unresolvable {
            input: t.at(&RingInput::ALL)?,
            from: t.at(&NoiseFrom::ALL)?,
            resolution: t.f()?,
            needed: t.f()?,
            ring: t.f()?,
            noise: t.f()?,
        },
        _ => return None,
    })
}

fn swing(p: &mut Put, e: SwingError<f32>) {
    match e {
        SwingError::NoEquilibrium { bias_volts } => p.d(0).f(bias_volts),
        SwingError::Unbounded {
            resonance,
            natural_hz,
            quality_factor,
            largest_ac_volts,
        } => p
            .d(1)
            .at(&Resonance::ALL, &resonance)
            .f(natural_hz)
            .f(quality_factor)
            .f(largest_ac_volts),
        SwingError::Crosses {
            mode,
            resonance,
            low_stretch,
            high_stretch,
            natural_hz,
            quality_factor,
            largest_ac_volts,
        } => {
            p.d(2).at(&FailureMode::ALL, &mode);
            // No resonance: one past the list.
            match resonance {
                Some(r) => p.at(&Resonance::ALL, &r),
                None => p.d(Resonance::ALL.len() as u8),
            }
            .f(low_stretch)
            .f(high_stretch)
            .f(natural_hz)
            .f(quality_factor)
            .f(largest_ac_volts)
        }
    };
}

fn swing_back(t: &mut Take) -> Option<SwingError<f32>> {
    Some(match t.d()? {
        0 => SwingError::NoEquilibrium { bias_volts: t.f()? },
        1 => SwingError::Unbounded {
            resonance: t.at(&Resonance::ALL)?,
            natural_hz: t.f()?,
            quality_factor: t.f()?,
            largest_ac_volts: t.f()?,
        },
        2 => SwingError::Crosses {
            mode: t.at(&FailureMode::ALL)?,
            resonance: match t.d()? {
                k if usize::from(k) == Resonance::ALL.len() => None,
                k => Some(*Resonance::ALL.get(usize::from(k))?),
            },
            low_stretch: t.f()?,
            high_stretch: t.f()?,
            natural_hz: t.f()?,
            quality_factor: t.f()?,
            largest_ac_volts: t.f()?,
        },
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::format;
    use std::string::{String, ToString};
    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::controller::FAULT_KEYS;

    /// One fault of every kind and sub-kind, its figures' numbers all different.
    fn every_fault() -> Vec<Fault> {
        let (a, b, c, d, e) = (1.25f32, -2.5e-3, 7449.878, 9361.898, 44.0);
        let mode = FailureMode::LossOfTension2b;
        let mut all = vec![
            Fault::Setting {
                setting: Setting::ALL[7],
                value: a,
            },
            Fault::Swing {
                setting: Setting::ALL[6],
                value: a,
                low_volts: b,
                high_volts: c,
                max_volts: d,
            },
            Fault::Disagree {
                table_volts: a,
                table_hz: b,
                solved_volts: c,
                solved_hz: d,
            },
            Fault::AboveSafe {
                volts: c,
                max_volts: d,
            },
            Fault::PlanCrosses { mode, seconds: a },
            Fault::Gate {
                volts: c,
                max_volts: d,
            },
            Fault::Sensor { value: f32::NAN },
            Fault::SensorImplausible {
                value: a,
                low: b,
                high: c,
            },
            Fault::SensorStuck {
                samples: 100,
                value: 2.211351,
            },
            Fault::Leakage {
                ohms: 7.8e9,
                floor_ohms: 1e10,
            },
            Fault::LeakageFalling {
                ohms: 7.8e9,
                previous_ohms: 1e11,
            },
            Fault::TrackLost {
                drive_hz: a,
                target_hz: e,
            },
            Fault::AmplifierDisagrees {
                commanded_volts: c,
                measured_volts: d,
            },
            Fault::Limit {
                mode,
                tick: 123_456,
            },
            Fault::Bus,
            Fault::NearLimit {
                mode,
                tick: 99,
                stretch: a,
                volts: c,
            },
            Fault::OutsideBatch {
                stretch: a,
                sigma: 1.5e-4,
                low: b,
                high: e,
                volts: c,
            },
            Fault::Steeper {
                setting: Setting::AcVolts,
                volts_per_second: 25_132.7,
                amplifier_volts_per_second: 20_000.0,
            },
            Fault::SwingOutgrown {
                tick: 1352,
                half_span: b,
                growth: 3.5e-5,
                allowed: 1.5e-3,
                quality_factor: 201.0,
            },
            Fault::DropRings {
                from_volts: c,
                mode,
            },
            Fault::AmplifierLags {
                setting: Setting::AcVolts,
                following_volts: 214.6,
                tolerance_volts: 200.0,
            },
        ];
        let problems = [
            Problem::NotFinite,
            Problem::NotPositive,
            Problem::Negative,
            Problem::NoTension1AtZeroBias,
            Problem::NoTension2AtZeroBias,
            Problem::StretchLimitAtZeroBias,
            Problem::UnsafeAtZeroBias { mode },
            Problem::DerivedNotFinite { scale: SCALES[4] },
        ];
        all.extend(problems.map(|problem| {
            Fault::Device(ParamError {
                field: Field::ALL[12],
                problem,
            })
        }));
        all.extend(
            [
                TableError::TooShort { bytes: 12 },
                TableError::BadMagic,
                TableError::UnsupportedVersion { version: 9 },
                TableError::BadCount { points: 1 },
                TableError::WrongLength {
                    expected: 400,
                    bytes: 399,
                },
                TableError::BadCrc {
                    stored: 0xDEAD_BEEF,
                    computed: 0x0123_4567,
                },
                TableError::NotFinite { index: 3 },
                TableError::NotMonotone { index: 4 },
                TableError::OtherDevice {
                    field: Field::ALL[5],
                },
                TableError::OutOfRange {
                    target_hz: 55.9,
                    low_hz: 42.99,
                    high_hz: 45.95,
                },
                TableError::BufferTooSmall { needed: 4096 },
                TableError::BadBatch {
                    field: Some(Field::Thickness),
                },
                TableError::BadBatch { field: None },
                TableError::BadCapacitance { index: 15 },
            ]
            .map(Fault::Table),
        );
        all.extend(
            [
                TuneError::InvalidTarget { target_hz: b },
                TuneError::InvalidMargin { margin: 1.5 },
                TuneError::OutOfRange {
                    target_hz: 55.9,
                    low_hz: 42.99,
                    high_hz: 45.95,
                },
            ]
            .map(Fault::Tune),
        );
        all.extend(
            [
                StepError::InvalidStep { step_seconds: b },
                StepError::InvalidDrive {
                    drive: Drive {
                        bias: a,
                        ac: b,
                        omega: c,
                    },
                },
                StepError::InvalidRange { low: a, high: b },
                StepError::Unstable {
                    method: Method::ALL[2],
                    step_seconds: a,
                    max_step_seconds: b,
                },
                StepError::LeftGuardedRange {
                    tick: 77,
                    stretch: a,
                },
                StepError::NewtonFailed { tick: 78 },
                StepError::NonFinite { tick: 79 },
                StepError::DriveNotGuarded {
                    least_bias_dimless_squared: a,
                    guarded_bias_dimless_squared: b,
                },
            ]
            .map(Fault::PlanFailed),
        );
        all.extend(
            [
                CodeError::BadFullScale { volts: b },
                CodeError::OutOfRange {
                    volts: c,
                    max_volts: d,
                },
                CodeError::BadRail { volts: b },
            ]
            .map(Fault::Amplifier),
        );
        all.extend(
            [
                InputError::NoSamples {
                    channel: Channel::ALL[1],
                },
                InputError::Stalled {
                    stall: Stall::ALL[1],
                    recovered: 2,
                },
                InputError::NotACode {
                    channel: Channel::ALL[2],
                    code: 4097,
                },
                InputError::AtRail {
                    channel: Channel::ALL[0],
                    mean_code: 4095.5,
                },
                InputError::Implausible {
                    channel: Channel::ALL[2],
                    reading: a,
                    low: b,
                    high: c,
                },
            ]
            .map(Fault::Input),
        );
        all.extend(
            [
                TrimError::NoRing { crossings: 3 },
                TrimError::NoEstimate {
                    measured_hz: a,
                    volts: c,
                },
                TrimError::NotConverged {
                    measured_hz: a,
                    target_hz: e,
                },
                TrimError::Unresolvable {
                    input: RingInput::ALL[1],
                    from: NoiseFrom::ALL[2],
                    resolution: a,
                    needed: b,
                    ring: c,
                    noise: d,
                },
                TrimError::OutsideBatch {
                    shear_modulus: a,
                    low: b,
                    high: c,
                },
            ]
            .map(Fault::Trim),
        );
        all.extend(
            [
                SwingError::NoEquilibrium { bias_volts: c },
                SwingError::Unbounded {
                    resonance: Resonance::ALL[2],
                    natural_hz: e,
                    quality_factor: 200.0,
                    largest_ac_volts: a,
                },
                SwingError::Crosses {
                    mode,
                    resonance: Some(Resonance::ALL[3]),
                    low_stretch: a,
                    high_stretch: b,
                    natural_hz: c,
                    quality_factor: d,
                    largest_ac_volts: e,
                },
                SwingError::Crosses {
                    mode,
                    resonance: None,
                    low_stretch: a,
                    high_stretch: b,
                    natural_hz: c,
                    quality_factor: d,
                    largest_ac_volts: e,
                },
            ]
            .map(Fault::DriveSwing),
        );
        all
    }

    /// Each fault's key is its variant's name in snake case (read from `Debug`): two keys
    /// swapped in the declaration fail here (their numbers' order fails at compile time).
    #[test]
    fn each_faults_key_is_its_variants_name() {
        for fault in every_fault() {
            let debug = format!("{fault:?}");
            let name: String = debug.chars().take_while(|c| c.is_alphanumeric()).collect();
            let mut snake = String::new();
            for (k, c) in name.chars().enumerate() {
                if c.is_uppercase() && k > 0 {
                    snake.push('_');
                }
                snake.push(c.to_ascii_lowercase());
            }
            assert_eq!(
                Fault::key_of(fault.number()),
                Some(snake.as_str()),
                "{debug}"
            );
        }
    }

    #[test]
    fn every_fault_comes_back_from_its_figures_with_its_sentence_whole() {
        let all = every_fault();
        // Every kind of fault is among them.
        for number in 1..=FAULT_KEYS.len() as u8 {
            assert!(all.iter().any(|f| f.number() == number), "fault {number}");
        }
        for fault in all {
            let back = Fault::from_figures(&fault.figures());
            // NaN is not equal to itself: compared by its sentence, as the log shows it.
            assert_eq!(
                back.map(|b| b.to_string()),
                Some(fault.to_string()),
                "{fault:?}"
            );
            if let Fault::Sensor { .. } = fault {
                continue;
            }
            assert_eq!(back, Some(fault));
        }
    }

    /// The lists whose positions flash holds, in their order: a reorder would read an older
    /// entry as another fault (the names written out here, not taken from the code).
    #[test]
    fn the_positions_flash_holds_keep_their_order() {
        // `Setting::ALL`'s order is pinned where the settings are (tests/controller.rs,
        // `every_setting_by_its_key`).
        let fields: Vec<&str> = Field::ALL.iter().map(|f| f.key()).collect();
        assert_eq!(
            fields,
            [
                "shear_modulus",
                "jlim",
                "relative_permittivity",
                "density",
                "breakdown_field",
                "thickness",
                "length_active",
                "length_passive",
                "width",
                "bar_mass",
                "prestretch_1",
                "prestretch_2",
                "damping",
            ]
        );
        assert_eq!(
            FailureMode::ALL,
            [
                FailureMode::DeviceInstability,
                FailureMode::Emi,
                FailureMode::LossOfTension1,
                FailureMode::LossOfTension2a,
                FailureMode::LossOfTension2b,
                FailureMode::Breakdown,
                FailureMode::StretchLimit,
            ]
        );
        assert_eq!(
            Channel::ALL,
            [Channel::Current, Channel::Amplifier, Channel::Stretch]
        );
        assert_eq!(Stall::ALL, [Stall::Overrun, Stall::TransferError]);
        assert_eq!(
            Method::ALL,
            [Method::Rk4, Method::Verlet, Method::ImplicitMidpoint]
        );
        assert_eq!(
            Resonance::ALL,
            [
                Resonance::Harmonic,
                Resonance::SuperHarmonic,
                Resonance::Parametric,
                Resonance::Static
            ]
        );
        assert_eq!(RingInput::ALL, [RingInput::Stretch, RingInput::Charge]);
        assert_eq!(
            NoiseFrom::ALL,
            [NoiseFrom::Image, NoiseFrom::Hold, NoiseFrom::Window]
        );
        assert_eq!(
            SCALES,
            ["H·√(μ/ε)", "μ·L2·H/M", "E_B·√(ε/μ)", "L1A/L1B", "c·T0/M"]
        );
        // A fault's figures as the layout has them: number 14, no index, the count and the
        // sample's bits.
        let stuck = Fault::SensorStuck {
            samples: 100,
            value: 2.5,
        }
        .figures();
        assert_eq!(
            stuck,
            Figures {
                number: 14,
                details: [0; DETAILS],
                values: [100, 0x4020_0000, 0, 0, 0, 0, 0],
            }
        );
        // An outgrown swing logged before its Q was kept (four numbers): Q 0, the sentence
        // as it was then, without a Q.
        let before = Figures {
            number: 27,
            details: [0; DETAILS],
            values: [1352, 0x3a80_0000, 0, 0x3a80_0000, 0, 0, 0],
        };
        let read = Fault::from_figures(&before);
        assert!(
            matches!(read, Some(Fault::SwingOutgrown { tick: 1352, quality_factor, .. })
                if quality_factor == 0.0),
            "{read:?}"
        );
        let said = read.map(|f| f.to_string()).unwrap_or_default();
        assert!(!said.contains(" Q "), "{said}");
        let now = Fault::SwingOutgrown {
            tick: 1352,
            half_span: 1e-3,
            growth: 0.0,
            allowed: 1e-3,
            quality_factor: 201.0,
        };
        assert!(format!("{now}").contains("at Q 201 widened"), "{now}");
    }

    #[test]
    fn any_bytes_give_a_fault_or_none_never_a_panic() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut read = 0;
        for _ in 0..200_000 {
            let r = next();
            let fig = Figures {
                number: (r % 27) as u8,
                details: [
                    (r >> 8) as u8 % 14,
                    (r >> 16) as u8 % 14,
                    (r >> 24) as u8,
                    0,
                ],
                values: [next() as u32; VALUES].map(|v| v ^ next() as u32),
            };
            if let Some(fault) = Fault::from_figures(&fig) {
                read += 1;
                let _ = fault.to_string();
            }
        }
        assert!(read > 10_000, "{read}");
    }
}
