//! The board's keeper on a flash (`Keeper`): the saved settings (`store`) and the fault log
//! (`fault_log`, through [`FlashLog`]) in their ranges of one flash, each call blocking until
//! it is done. Here, above both, so that neither persistence layer knows the board.

use core::ops::Range;

use embedded_storage::nor_flash::NorFlash;

use super::{FaultKeeper, Keeper, SettingsKeeper};
use crate::controller::{Held, Settings};
use crate::fault_log::{self, Entry};
use crate::store::{load, save, StoreError};

/// A flash and the ranges of it the settings and the fault log use, as the board keeps them
/// ([`Keeper`]): each call blocking until it is done (RAM, or the STM32F4's flash
/// controller, which waits in each call), in a frame of its own (out of line: its buffers are
/// not carried, in the caller's frame, under the boot's checks, RAM's deepest path).
pub struct FlashKeeper<F> {
    pub flash: F,
    pub range: Range<u32>,
    /// The fault log's (`crate::fault_log`; `None`: none kept).
    pub log: Option<Range<u32>>,
    /// Whether an erase stalls the chip (its code runs from this flash bank, for longer than
    /// the watchdog waits): the log then erases only at boot (`FaultKeeper::prepare`), never
    /// while running, and `save` and `faults clear` wait for rest at 0 V. The chip, and the
    /// firmware's QEMU stand-in that stalls as the chip does: `true`; host-sim's RAM: `false`.
    pub erase_stalls: bool,
}

impl<F: NorFlash> SettingsKeeper for FlashKeeper<F> {
    type Error = StoreError;

    #[inline(never)]
    fn load(&mut self) -> Result<Option<Held>, StoreError> {
        load(&mut self.flash, self.range.clone())
    }

    #[inline(never)]
    fn save(&mut self, settings: &Settings) -> Result<(), StoreError> {
        save(&mut self.flash, self.range.clone(), settings)
    }
}

impl<F: NorFlash> Keeper for FlashKeeper<F> {
    type Log<'a>
        = FlashLog<'a, F>
    where
        F: 'a;

    fn erase_stalls(&self) -> bool {
        self.erase_stalls
    }

    fn fault_log(&mut self) -> Option<FlashLog<'_, F>> {
        Some(FlashLog {
            range: self.log.clone()?,
            may_erase: !self.erase_stalls,
            flash: &mut self.flash,
        })
    }
}

/// The fault log's range of a [`FlashKeeper`]'s flash, borrowed from it.
pub struct FlashLog<'a, F> {
    flash: &'a mut F,
    range: Range<u32>,
    /// Whether an entry may erase a full page (never where an erase stalls the chip: the log
    /// then erases at boot only, in `prepare`).
    may_erase: bool,
}

impl<F: NorFlash> FaultKeeper for FlashLog<'_, F> {
    type Error = StoreError;

    #[inline(never)]
    fn log(&mut self, entry: &Entry) -> Result<u32, StoreError> {
        let (range, may_erase) = (self.range.clone(), self.may_erase);
        fault_log::append(&mut *self.flash, range, entry, may_erase)
    }

    #[inline(never)]
    fn prepare(&mut self) -> Result<bool, StoreError> {
        fault_log::prepare(&mut *self.flash, self.range.clone())
    }

    #[inline(never)]
    fn each(&mut self, each: &mut dyn FnMut(Entry)) -> Result<(), StoreError> {
        fault_log::each(&mut *self.flash, self.range.clone(), each)
    }

    #[inline(never)]
    fn clear(&mut self) -> Result<(), StoreError> {
        fault_log::clear(&mut *self.flash, self.range.clone())
    }
}
