//! What the controller says at a tick (`Event`), and what a tick gives (`Output`).

use core::fmt;

use super::fault::Fault;
use crate::drive::DacCode;
use crate::estimate::ring::RingQuality;

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
