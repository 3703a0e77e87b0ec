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

use super::super::settings::Setting;

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

/// Writes a fault's indices and numbers, each in order (past the room: dropped, and the
/// round trip's test fails).
pub(super) struct Put {
    figures: Figures,
    details: usize,
    values: usize,
}

impl Put {
    pub(super) fn new(number: u8) -> Put {
        Put {
            figures: Figures {
                number,
                ..Figures::default()
            },
            details: 0,
            values: 0,
        }
    }
    pub(super) fn figures(self) -> Figures {
        self.figures
    }
    fn detail(&mut self, x: u8) {
        if let Some(slot) = self.figures.details.get_mut(self.details) {
            *slot = x;
        }
        self.details += 1;
    }
    /// `x` by its position in `all` (`u8::MAX` if it is not there: read back as none).
    fn position<T: PartialEq>(&mut self, all: &[T], x: &T) {
        let k = all.iter().position(|a| a == x).unwrap_or(usize::MAX);
        self.detail(u8::try_from(k).unwrap_or(u8::MAX));
    }
    fn value(&mut self, x: u32) {
        if let Some(slot) = self.figures.values.get_mut(self.values) {
            *slot = x;
        }
        self.values += 1;
    }
}

/// Reads them back in the same order: `None` past the room or for an index no value has
/// (bytes of another version, or damaged); zero past what was written.
pub(super) struct Take<'a> {
    figures: &'a Figures,
    details: usize,
    values: usize,
}

impl Take<'_> {
    pub(super) fn new(figures: &Figures) -> Take<'_> {
        Take {
            figures,
            details: 0,
            values: 0,
        }
    }
    fn detail(&mut self) -> Option<u8> {
        let x = self.figures.details.get(self.details).copied();
        self.details += 1;
        x
    }
    fn position<T: Copy>(&mut self, all: &[T]) -> Option<T> {
        all.get(usize::from(self.detail()?)).copied()
    }
    fn value(&mut self) -> Option<u32> {
        let x = self.figures.values.get(self.values).copied();
        self.values += 1;
        x
    }
}

/// What a fault's figures hold of a field: a number among the values (f32 as its bits, an
/// integer as u32), a choice among the indices (its position in its list, which flash
/// therefore holds: a list only grows at its end), a nested error as its variant's index and
/// then its own fields.
pub(super) trait Figure: Sized {
    fn put(&self, put: &mut Put);
    fn take(take: &mut Take) -> Option<Self>;
}

impl Figure for f32 {
    fn put(&self, put: &mut Put) {
        put.value(self.to_bits());
    }
    fn take(take: &mut Take) -> Option<f32> {
        take.value().map(f32::from_bits)
    }
}

impl Figure for u32 {
    fn put(&self, put: &mut Put) {
        put.value(*self);
    }
    fn take(take: &mut Take) -> Option<u32> {
        take.value()
    }
}

impl Figure for u16 {
    fn put(&self, put: &mut Put) {
        put.value(u32::from(*self));
    }
    fn take(take: &mut Take) -> Option<u16> {
        u16::try_from(take.value()?).ok()
    }
}

/// A byte count, kept to 2³² − 1.
impl Figure for usize {
    fn put(&self, put: &mut Put) {
        put.value(u32::try_from(*self).unwrap_or(u32::MAX));
    }
    fn take(take: &mut Take) -> Option<usize> {
        usize::try_from(take.value()?).ok()
    }
}

/// A model run's step count, kept to 2³² − 1.
impl Figure for u64 {
    fn put(&self, put: &mut Put) {
        put.value(u32::try_from(*self).unwrap_or(u32::MAX));
    }
    fn take(take: &mut Take) -> Option<u64> {
        take.value().map(u64::from)
    }
}

/// Choices held by their position in their list.
macro_rules! by_position {
    ($($ty:ty => $all:expr,)*) => {$(
        impl Figure for $ty {
            fn put(&self, put: &mut Put) {
                put.position(&$all, self);
            }
            fn take(take: &mut Take) -> Option<$ty> {
                take.position(&$all)
            }
        }
    )*};
}

by_position! {
    Setting => Setting::ALL,
    Field => Field::ALL,
    FailureMode => FailureMode::ALL,
    Channel => Channel::ALL,
    Stall => Stall::ALL,
    Method => Method::ALL,
    Resonance => Resonance::ALL,
    RingInput => RingInput::ALL,
    NoiseFrom => NoiseFrom::ALL,
    // A derived scale's name (`Problem::DerivedNotFinite`), by its place in `SCALES`.
    &'static str => SCALES,
}

/// A swing's resonance, if any: an index, one past the list for none.
impl Figure for Option<Resonance> {
    fn put(&self, put: &mut Put) {
        match self {
            Some(r) => r.put(put),
            None => put.detail(Resonance::ALL.len() as u8),
        }
    }
    fn take(take: &mut Take) -> Option<Option<Resonance>> {
        match take.detail()? {
            k if usize::from(k) == Resonance::ALL.len() => Some(None),
            k => Some(Some(*Resonance::ALL.get(usize::from(k))?)),
        }
    }
}

/// A batch's field, if any (`TableError::BadBatch`): a number, its place in `Field::ALL`,
/// u32::MAX for the guaranteed limit.
impl Figure for Option<Field> {
    fn put(&self, put: &mut Put) {
        put.value(
            self.and_then(|f| Field::ALL.iter().position(|&g| g == f))
                .map_or(u32::MAX, |k| k as u32),
        );
    }
    fn take(take: &mut Take) -> Option<Option<Field>> {
        match take.value()? {
            u32::MAX => Some(None),
            k => Some(Some(*Field::ALL.get(usize::try_from(k).ok()?)?)),
        }
    }
}

/// Structs by their fields, in the order written.
macro_rules! by_fields {
    ($($ty:ident $(<$param:ty>)? { $($field:ident),* },)*) => {$(
        impl Figure for $ty $(<$param>)? {
            fn put(&self, put: &mut Put) {
                $( self.$field.put(put); )*
            }
            fn take(take: &mut Take) -> Option<Self> {
                Some($ty { $( $field: Figure::take(take)? ),* })
            }
        }
    )*};
}

by_fields! {
    ParamError { field, problem },
    Drive<f32> { bias, ac, omega },
}

/// Nested errors by their variant's index (an index, part of the log's layout: a new variant
/// takes the next) and then their fields, in the order written. A variant added to one of
/// these errors fails to compile until it is given its index here.
macro_rules! by_variant {
    ($($ty:ident $(<$param:ty>)? {
        $( $index:literal $variant:ident $( { $($field:ident),* } )?, )*
    })*) => {$(
        impl Figure for $ty $(<$param>)? {
            fn put(&self, put: &mut Put) {
                match self {
                    $(
                        $ty::$variant $( { $($field),* } )? => {
                            put.detail($index);
                            $( $( $field.put(put); )* )?
                        }
                    )*
                }
            }
            fn take(take: &mut Take) -> Option<Self> {
                Some(match take.detail()? {
                    $( $index => $ty::$variant $( { $( $field: Figure::take(take)? ),* } )?, )*
                    _ => return None,
                })
            }
        }
    )*};
}

by_variant! {
    Problem {
        0 NotFinite,
        1 NotPositive,
        2 Negative,
        3 NoTension1AtZeroBias,
        4 NoTension2AtZeroBias,
        5 StretchLimitAtZeroBias,
        6 UnsafeAtZeroBias { mode },
        7 DerivedNotFinite { scale },
    }
    TableError {
        0 TooShort { bytes },
        1 BadMagic,
        2 UnsupportedVersion { version },
        3 BadCount { points },
        4 WrongLength { expected, bytes },
        5 BadCrc { stored, computed },
        6 NotFinite { index },
        7 NotMonotone { index },
        8 OtherDevice { field },
        9 OutOfRange { target_hz, low_hz, high_hz },
        10 BufferTooSmall { needed },
        11 BadBatch { field },
        12 BadCapacitance { index },
    }
    TuneError<f32> {
        0 InvalidTarget { target_hz },
        1 InvalidMargin { margin },
        2 OutOfRange { target_hz, low_hz, high_hz },
    }
    StepError<f32> {
        0 InvalidStep { step_seconds },
        1 InvalidDrive { drive },
        2 InvalidRange { low, high },
        3 Unstable { method, step_seconds, max_step_seconds },
        4 LeftGuardedRange { tick, stretch },
        5 NewtonFailed { tick },
        6 NonFinite { tick },
        7 DriveNotGuarded { least_bias_dimless_squared, guarded_bias_dimless_squared },
    }
    CodeError {
        0 BadFullScale { volts },
        1 OutOfRange { volts, max_volts },
        2 BadRail { volts },
    }
    InputError {
        0 NoSamples { channel },
        1 Stalled { stall, recovered },
        2 NotACode { channel, code },
        3 AtRail { channel, mean_code },
        4 Implausible { channel, reading, low, high },
    }
    TrimError {
        0 NoRing { crossings },
        1 NoEstimate { measured_hz, volts },
        2 NotConverged { measured_hz, target_hz },
        3 Unresolvable { input, from, resolution, needed, ring, noise },
        4 OutsideBatch { shear_modulus, low, high },
    }
    SwingError<f32> {
        0 NoEquilibrium { bias_volts },
        1 Unbounded { resonance, natural_hz, quality_factor, largest_ac_volts },
        2 Crosses {
            mode, resonance, low_stretch, high_stretch, natural_hz, quality_factor,
            largest_ac_volts
        },
    }
}
