//! The watchdog's hardware; when to start and feed it is the core's `board::watchdog` (the
//! tick feeds it only while the low-priority tasks check in).
//!
//! On the chip it is the IWDG (its own oscillator: it resets a stuck tick too). QEMU does not
//! emulate the IWDG (QEMU-STM32F405.md §6), so QEMU builds keep the time of the last feed on
//! TIM2's microsecond clock and check it from TIM3's interrupt, above the tick's priority
//! (`bite_if_starved`): a stuck tick or a hung task ends in `SCB::sys_reset` with the cause
//! recorded. QEMU's TIM3 period is not exact (set up at boot it is about 100 ms); the check
//! compares clock readings, so it only decides how late the bite may come. After a watchdog
//! reset the firmware comes up refusing to drive, says so, and starts the dog again at `clear`.

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

/// QEMU's stand-in: the feeds' clock readings, checked by `bite_if_starved`.
#[cfg(feature = "qemu")]
pub struct Dog;

#[cfg(feature = "qemu")]
mod stand_in {
    use core::sync::atomic::{AtomicU32, Ordering};

    /// The timeout, µs (0: not started).
    pub static TIMEOUT_MICROS: AtomicU32 = AtomicU32::new(0);
    /// TIM2's reading at the last feed, µs.
    pub static FED_AT_MICROS: AtomicU32 = AtomicU32::new(0);

    pub fn feed() {
        FED_AT_MICROS.store(crate::chip::qemu_clock::micros(), Ordering::Relaxed);
    }

    pub fn starved() -> bool {
        let timeout = TIMEOUT_MICROS.load(Ordering::Relaxed);
        let since =
            crate::chip::qemu_clock::micros().wrapping_sub(FED_AT_MICROS.load(Ordering::Relaxed));
        timeout > 0 && since > timeout
    }
}

/// QEMU's stand-in for `through_stall`: the stand-in's timeout lengthened to
/// `STALL_WINDOW_MS` (then fed) while `erase` runs, then fed and restored.
#[cfg(feature = "qemu")]
pub fn through_stall<R>(erase: impl FnOnce() -> R) -> R {
    use core::sync::atomic::Ordering;
    let before = stand_in::TIMEOUT_MICROS.load(Ordering::Relaxed);
    if before > 0 {
        stand_in::TIMEOUT_MICROS.store(STALL_WINDOW_MS * 1000, Ordering::Relaxed);
        stand_in::feed();
    }
    let done = erase();
    if before > 0 {
        stand_in::feed();
        stand_in::TIMEOUT_MICROS.store(before, Ordering::Relaxed);
    }
    done
}

#[cfg(feature = "qemu")]
impl Dog {
    pub fn new(_iwdg: stm32f4xx_hal::pac::IWDG, _dbgmcu: &stm32f4xx_hal::pac::DBGMCU) -> Self {
        Self
    }

    /// TIM3's update interrupt about every 100 ms (QEMU counts timers at 1 GHz: a prescaler
    /// of 10,000 and a reload of 10,000; TIM3 is 16-bit), the stand-in's own clock. Set up first thing at boot,
    /// where QEMU's timer period is right (QEMU-STM32F405.md §2).
    pub fn start_clock(tim3: &stm32f4xx_hal::pac::TIM3) {
        tim3.psc().write(|w| w.psc().set(9_999));
        tim3.arr().write(|w| w.arr().set(10_000));
        tim3.egr().write(|w| w.ug().set_bit());
        tim3.sr().write(|w| w.uif().clear_bit());
        tim3.dier().write(|w| w.uie().set_bit());
        tim3.cr1().modify(|_, w| w.cen().set_bit());
    }
}

/// From TIM3's interrupt: reset (cause: the watchdog) if the dog went unfed past its timeout.
#[cfg(feature = "qemu")]
pub fn bite_if_starved() {
    // SAFETY: clearing TIM3's update flag, a register only this interrupt writes after boot.
    unsafe {
        (*stm32f4xx_hal::pac::TIM3::ptr())
            .sr()
            .write(|w| w.uif().clear_bit())
    };
    if stand_in::starved() {
        crate::runtime::reset(crate::runtime::ResetCause::Watchdog);
    }
}

#[cfg(feature = "qemu")]
impl Watchdog for Dog {
    fn start(&mut self, timeout_ms: u32) {
        stand_in::feed();
        stand_in::TIMEOUT_MICROS.store(
            timeout_ms.saturating_mul(1000),
            core::sync::atomic::Ordering::Relaxed,
        );
    }

    fn feed(&mut self) {
        stand_in::feed();
    }
}
