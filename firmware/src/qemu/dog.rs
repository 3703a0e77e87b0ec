//! The watchdog's stand-in: QEMU does not emulate the IWDG (QEMU-STM32F405.md §6), so the
//! dog keeps the time of the last feed on TIM2's microsecond clock (`clock`) and checks it
//! from TIM3's interrupt, above the tick's priority (`bite_if_starved`): a stuck tick or a
//! hung task ends in `SCB::sys_reset` with the cause recorded. QEMU's TIM3 period is not
//! exact (set up at boot it is about 100 ms); the check compares clock readings, so it only
//! decides how late the bite may come.

use core::sync::atomic::{AtomicU32, Ordering};

use super::clock;
use crate::watchdog::{Watchdog, STALL_WINDOW_MS};

/// The timeout, µs (0: not started).
static TIMEOUT_MICROS: AtomicU32 = AtomicU32::new(0);
/// TIM2's reading at the last feed, µs.
static FED_AT_MICROS: AtomicU32 = AtomicU32::new(0);

fn fed() {
    FED_AT_MICROS.store(clock::micros(), Ordering::Relaxed);
}

fn starved() -> bool {
    let timeout = TIMEOUT_MICROS.load(Ordering::Relaxed);
    let since = clock::micros().wrapping_sub(FED_AT_MICROS.load(Ordering::Relaxed));
    timeout > 0 && since > timeout
}

/// The stand-in: the feeds' clock readings, checked by `bite_if_starved`.
pub struct Dog;

impl Dog {
    pub fn new(_iwdg: stm32f4xx_hal::pac::IWDG, _dbgmcu: &stm32f4xx_hal::pac::DBGMCU) -> Self {
        Self
    }

    /// TIM3's update interrupt about every 100 ms (QEMU counts timers at 1 GHz: a prescaler
    /// of 10,000 and a reload of 10,000; TIM3 is 16-bit), the stand-in's own clock. Set up
    /// first thing at boot, where QEMU's timer period is right (QEMU-STM32F405.md §2).
    pub fn start_clock(tim3: &stm32f4xx_hal::pac::TIM3) {
        tim3.psc().write(|w| w.psc().set(9_999));
        tim3.arr().write(|w| w.arr().set(10_000));
        tim3.egr().write(|w| w.ug().set_bit());
        tim3.sr().write(|w| w.uif().clear_bit());
        tim3.dier().write(|w| w.uie().set_bit());
        tim3.cr1().modify(|_, w| w.cen().set_bit());
    }
}

impl Watchdog for Dog {
    fn start(&mut self, timeout_ms: u32) {
        fed();
        TIMEOUT_MICROS.store(timeout_ms.saturating_mul(1000), Ordering::Relaxed);
    }

    fn feed(&mut self) {
        fed();
    }
}

/// The stand-in's `through_stall`: its timeout lengthened to `STALL_WINDOW_MS` (then fed)
/// while `erase` runs, then fed and restored.
pub fn through_stall<R>(erase: impl FnOnce() -> R) -> R {
    let before = TIMEOUT_MICROS.load(Ordering::Relaxed);
    if before > 0 {
        TIMEOUT_MICROS.store(STALL_WINDOW_MS * 1000, Ordering::Relaxed);
        fed();
    }
    let done = erase();
    if before > 0 {
        fed();
        TIMEOUT_MICROS.store(before, Ordering::Relaxed);
    }
    done
}

/// From TIM3's interrupt: reset (cause: the watchdog) if the dog went unfed past its timeout.
pub fn bite_if_starved() {
    // SAFETY: clearing TIM3's update flag, a register only this interrupt writes after boot.
    unsafe {
        (*stm32f4xx_hal::pac::TIM3::ptr())
            .sr()
            .write(|w| w.uif().clear_bit())
    };
    if starved() {
        crate::runtime::reset(crate::runtime::ResetCause::Watchdog);
    }
}
