//! An independent clock of virtual time: TIM2 counting microseconds (QEMU's timer model
//! counts at 1 GHz whatever RCC says; started first thing, its count is right:
//! QEMU-STM32F405.md §2). The stand-ins' clock, and the tick-rate test's.

use stm32f4xx_hal::pac::TIM2;

/// Start TIM2 free-running in microseconds.
pub fn start(tim2: &TIM2) {
    tim2.psc().write(|w| w.psc().set(999));
    tim2.arr().write(|w| w.arr().set(u32::MAX));
    tim2.egr().write(|w| w.ug().set_bit());
    tim2.cr1().modify(|_, w| w.cen().set_bit());
}

/// Microseconds of virtual time since `start`.
pub fn micros() -> u32 {
    // SAFETY: a read of a counter register no one writes after `start`.
    unsafe { (*TIM2::ptr()).cnt().read().bits() }
}
