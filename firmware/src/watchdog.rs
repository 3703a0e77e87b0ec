//! A watchdog only a healthy control loop can feed. The tick feeds it, and only while the
//! low-priority tasks have checked in within `CHECK_IN_TICKS` (a heartbeat task the tick asks
//! for at their priority: a task that hangs, or runs past the deadline, starves the dog).
//!
//! On the chip it is the IWDG (its own oscillator: it resets a stuck tick too). QEMU does not
//! emulate the IWDG (QEMU-STM32F405.md §6), so QEMU builds count the ticks since the last
//! feed instead and reset through `SCB::sys_reset` with the cause recorded: that stand-in
//! lives in the tick, so under QEMU it catches a hung task, not a stuck tick.
//!
//! A latched fault keeps the dog fed: the output is already at 0 V, and a reset would only
//! lose the fault's reason. After a watchdog reset the firmware comes up refusing to drive,
//! says so, and starts the dog again at `clear`.

/// The dog's timeout, ms.
pub const TIMEOUT_MS: u32 = 1_000;
/// Ticks the low-priority tasks may go without checking in (at 1 kHz: 0.5 s, longer than
/// their longest work: a boot's checks, about 12 ms on the chip).
pub const CHECK_IN_SECONDS: f32 = 0.5;

/// A watchdog: started once, then fed.
pub trait Watchdog {
    fn start(&mut self, timeout_ms: u32, tick_hz: f32);
    fn feed(&mut self);
    /// Once a tick, fed or not (the stand-in counts; the IWDG counts on its own).
    fn tick(&mut self) {}
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
    fn start(&mut self, timeout_ms: u32, _tick_hz: f32) {
        use stm32f4xx_hal::prelude::*;
        self.0.start(timeout_ms.millis());
    }

    fn feed(&mut self) {
        self.0.feed();
    }
}

/// QEMU's stand-in: ticks left until it bites (`None`: not started).
#[cfg(feature = "qemu")]
pub struct Dog {
    left: Option<u32>,
    timeout_ticks: u32,
}

#[cfg(feature = "qemu")]
impl Dog {
    pub fn new(_iwdg: stm32f4xx_hal::pac::IWDG) -> Self {
        Self {
            left: None,
            timeout_ticks: 0,
        }
    }
}

#[cfg(feature = "qemu")]
impl Watchdog for Dog {
    fn start(&mut self, timeout_ms: u32, tick_hz: f32) {
        self.timeout_ticks = (timeout_ms as f32 * tick_hz / 1000.0) as u32;
        self.left = Some(self.timeout_ticks);
    }

    fn feed(&mut self) {
        if self.left.is_some() {
            self.left = Some(self.timeout_ticks);
        }
    }

    fn tick(&mut self) {
        match self.left {
            Some(0) => crate::runtime::reset(crate::runtime::ResetCause::Watchdog),
            Some(n) => self.left = Some(n - 1),
            None => {}
        }
    }
}
