//! What the board keeps across a reset or a power cut, split by what it is: the saved
//! settings ([`SettingsKeeper`]: flash on the chip, RAM a reset keeps under QEMU, memory in
//! host-sim's virtual board) and the fault log ([`FaultKeeper`]), often on one flash, which
//! is why one value, the board's [`Keeper`], holds both.

use core::fmt;

use crate::controller::{Held, Settings};
use crate::fault_log::Entry;

/// Where `save` keeps the settings.
pub trait SettingsKeeper {
    type Error: fmt::Display;
    /// The settings saved last, if any (an older firmware's lack the settings added since).
    fn load(&mut self) -> Result<Option<Held>, Self::Error>;
    fn save(&mut self, settings: &Settings) -> Result<(), Self::Error>;
}

/// Where the fault log's entries are kept (`crate::fault_log`'s on a flash).
pub trait FaultKeeper {
    type Error: fmt::Display;
    /// Append `entry`; its sequence number.
    fn log(&mut self, entry: &Entry) -> Result<u32, Self::Error>;
    /// At boot, before anything is driven: ready for a run's entries (an erase, if one is
    /// due); whether it erased.
    fn prepare(&mut self) -> Result<bool, Self::Error>;
    /// Every entry, in flash order.
    fn each(&mut self, each: &mut dyn FnMut(Entry)) -> Result<(), Self::Error>;
    /// Empty the log.
    fn clear(&mut self) -> Result<(), Self::Error>;
}

/// What a board keeps: its settings, and beside them its fault log if it has one.
pub trait Keeper: SettingsKeeper {
    /// The fault log, borrowed from the keeper (the two often share a flash).
    type Log<'a>: FaultKeeper<Error = Self::Error>
    where
        Self: 'a;
    /// Whether a flash erase stalls the chip (past its watchdog): `save` then waits for the
    /// output at rest at 0 V, and the log erases at boot only (`faults clear` waits for rest
    /// on every board).
    fn erase_stalls(&self) -> bool {
        false
    }
    /// The fault log; `None`: none kept here.
    fn fault_log(&mut self) -> Option<Self::Log<'_>>;
}

/// The keeper of a board that keeps nothing (`None::<NoKeeper>`: `save` then answers that
/// the board has no settings storage, `faults` no fault log). There is no value of it.
#[derive(Clone, Copy, Debug)]
pub enum NoKeeper {}

impl SettingsKeeper for NoKeeper {
    type Error = &'static str;
    fn load(&mut self) -> Result<Option<Held>, Self::Error> {
        match *self {}
    }
    fn save(&mut self, _: &Settings) -> Result<(), Self::Error> {
        match *self {}
    }
}

impl Keeper for NoKeeper {
    type Log<'a> = NoLog;
    fn fault_log(&mut self) -> Option<NoLog> {
        match *self {}
    }
}

/// The fault log of a keeper that keeps none: there is no value of it.
#[derive(Clone, Copy, Debug)]
pub enum NoLog {}

impl FaultKeeper for NoLog {
    type Error = &'static str;
    fn log(&mut self, _: &Entry) -> Result<u32, Self::Error> {
        match *self {}
    }
    fn prepare(&mut self) -> Result<bool, Self::Error> {
        match *self {}
    }
    fn each(&mut self, _: &mut dyn FnMut(Entry)) -> Result<(), Self::Error> {
        match *self {}
    }
    fn clear(&mut self) -> Result<(), Self::Error> {
        match *self {}
    }
}
