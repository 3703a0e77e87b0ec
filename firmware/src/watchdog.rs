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
    pub fn new(iwdg: stm32f4xx_hal::pac::IWDG) -> Self {
        Self(stm32f4xx_hal::watchdog::IndependentWatchdog::new(iwdg))
    }
}

#[cfg(not(feature = "qemu"))]
impl Watchdog for Dog {
    fn start(&mut self, timeout_ms: u32) {
        use stm32f4xx_hal::prelude::*;
        self.0.start(timeout_ms.millis());
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
        FED_AT_MICROS.store(crate::board::qemu_clock::micros(), Ordering::Relaxed);
    }

    pub fn starved() -> bool {
        let timeout = TIMEOUT_MICROS.load(Ordering::Relaxed);
        let since =
            crate::board::qemu_clock::micros().wrapping_sub(FED_AT_MICROS.load(Ordering::Relaxed));
        timeout > 0 && since > timeout
    }
}

#[cfg(feature = "qemu")]
impl Dog {
    pub fn new(_iwdg: stm32f4xx_hal::pac::IWDG) -> Self {
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
