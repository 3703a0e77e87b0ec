//! The watchdog's hardware; when to start and feed it is the core's `board::watchdog` (the
//! tick feeds it only while the low-priority tasks check in).
//!
//! On the chip it is the IWDG (its own oscillator: it resets a stuck tick too); QEMU does not
//! emulate it, and its builds have the stand-in `qemu::dog`. After a watchdog reset the
//! firmware comes up refusing to drive, says so, and starts the dog again at `clear`.

pub use de_resonator::board::watchdog::TIMEOUT_MS;

/// A 128 KB sector's erase at the HAL's 8-bit parallelism, typical, ms (STM32F405
/// datasheet, t_ERASE128KB; 4 s at most): every fetch from the single bank stalls that long,
/// the tick's too, past the dog's `TIMEOUT_MS`. QEMU's flash stand-in stalls this long.
pub const SECTOR_ERASE_MS: u32 = 2_000;
/// The dog's window through an erase at its shortest, ms: prescaler /256 and the largest
/// reload (0xFFF) at the LSI's fastest (47 kHz, datasheet): 4096 · 256 / 47 kHz. Past the
/// longest erase the firmware runs in one call (two sectors, 8 s at most).
pub const STALL_WINDOW_MS: u32 = 4096 * 256 / 47;

/// A watchdog: started once, then fed.
pub trait Watchdog {
    fn start(&mut self, timeout_ms: u32);
    fn feed(&mut self);
}

/// The IWDG.
#[cfg(not(feature = "qemu"))]
pub struct Dog(stm32f4xx_hal::watchdog::IndependentWatchdog);

#[cfg(not(feature = "qemu"))]
impl Dog {
    /// The IWDG, set to stop while a debugger halts the core (DBGMCU_APB1_FZ): a breakpoint
    /// must not reset the board under the probe.
    pub fn new(iwdg: stm32f4xx_hal::pac::IWDG, dbgmcu: &stm32f4xx_hal::pac::DBGMCU) -> Self {
        let dog = stm32f4xx_hal::watchdog::IndependentWatchdog::new(iwdg);
        dog.stop_on_debug(dbgmcu, true);
        Self(dog)
    }
}

/// Run `erase`, a flash erase that stalls every fetch (the tick's too) for seconds, with the
/// IWDG's window lengthened past it (prescaler /256, reload 0xFFF: `STALL_WINDOW_MS` at the
/// shortest), then the window it had restored and the dog fed. Before the dog has started
/// (the boot's erases, a board refusing after a watchdog reset) there is nothing to lengthen.
#[cfg(not(feature = "qemu"))]
pub fn through_stall<R>(erase: impl FnOnce() -> R) -> R {
    let before = STARTED
        .load(core::sync::atomic::Ordering::Relaxed)
        .then(iwdg::window)
        .flatten();
    let lengthened =
        before.is_some() && iwdg::set_window(iwdg::STALL_PRESCALER, iwdg::STALL_RELOAD);
    let done = erase();
    if let (Some((prescaler, reload)), true) = (before, lengthened) {
        iwdg::set_window(prescaler, reload);
    }
    done
}

/// The IWDG's window registers (RM0090 §21.4): written after the access key, each update
/// done (PVU, RVU clear) before the next, then the counter reloaded with the new value.
#[cfg(not(feature = "qemu"))]
mod iwdg {
    use stm32f4xx_hal::pac::{iwdg::RegisterBlock, IWDG};

    const KEY_ACCESS: u16 = 0x5555;
    const KEY_RELOAD: u16 = 0xAAAA;
    pub const STALL_PRESCALER: u8 = 0b110;
    pub const STALL_RELOAD: u16 = 0xFFF;
    /// Polls of PVU and RVU (an update takes up to five LSI periods, about 0.3 ms; an LSI
    /// not running, with the dog never started, never ends one).
    const UPDATE_POLLS: u32 = 200_000;

    fn registers() -> &'static RegisterBlock {
        // SAFETY: the IWDG's registers, written here only inside a critical section, and by
        // the tick's feed (a write of the reload key, which this sequence also ends with).
        unsafe { &*IWDG::ptr() }
    }

    fn settled(r: &RegisterBlock) -> bool {
        (0..UPDATE_POLLS).any(|_| {
            let sr = r.sr().read();
            sr.pvu().bit_is_clear() && sr.rvu().bit_is_clear()
        })
    }

    /// The window in force (prescaler, reload); `None` while an update never ends.
    pub fn window() -> Option<(u8, u16)> {
        let r = registers();
        settled(r).then(|| (r.pr().read().pr().bits(), r.rlr().read().rl().bits()))
    }

    /// Set the window, then reload the counter with it; whether the update completed (if
    /// not, the counter is reloaded all the same, with the window in force).
    pub fn set_window(prescaler: u8, reload: u16) -> bool {
        cortex_m::interrupt::free(|_| {
            let r = registers();
            // SAFETY (the key, the prescaler): any 16-bit key and any 3-bit prescaler are
            // values the register takes.
            r.kr().write(|w| unsafe { w.key().bits(KEY_ACCESS) });
            let done = settled(r) && {
                r.pr().write(|w| unsafe { w.pr().bits(prescaler) });
                r.rlr().write(|w| w.rl().set(reload));
                settled(r)
            };
            r.kr().write(|w| unsafe { w.key().bits(KEY_RELOAD) });
            done
        })
    }
}

/// Whether the IWDG has been started: before that its clock (the LSI) is off, so a window
/// update would never complete, and would only land, wrong, at the start.
#[cfg(not(feature = "qemu"))]
static STARTED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

#[cfg(not(feature = "qemu"))]
impl Watchdog for Dog {
    fn start(&mut self, timeout_ms: u32) {
        use stm32f4xx_hal::prelude::*;
        self.0.start(timeout_ms.millis());
        STARTED.store(true, core::sync::atomic::Ordering::Relaxed);
    }

    fn feed(&mut self) {
        self.0.feed();
    }
}
