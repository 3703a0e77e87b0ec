//! The firmware for the STM32F405: an RTIC application (`bin/firmware.rs`) that reads its
//! device, table, amplifier and settings from the configuration image in flash sector 11,
//! ticks the core's controller on SysTick, writes the DAC through SPI1, and serves the
//! command port on USART2. The logic is in the `de-resonator` core; nothing here decides a
//! voltage, answers a request or decides when the amplifier is on (the core's `board`). One
//! module a part: `chip` (clocks, pins, peripherals), `analog` (silicon's ADC, its timer and
//! DMA, filling the tick's block of codes), `config` (the image), `sensor` (QEMU's stand-ins
//! for the analog inputs), `storage` (where `save` keeps the settings), `stream` (the telemetry stream's port),
//! `watchdog` (the
//! IWDG, or its QEMU stand-in), `link` (the link build's ends of host-sim's link), `runtime`
//! (exit codes, panic and fault handlers, the stack meter), `switches` (QEMU's test switches
//! in the tick; none on silicon); `reference` and `stand_in` serve the on-target checks and
//! counts only.
#![no_std]

use cortex_m as _;
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "log-semihosting")]
use defmt_semihosting as _;

#[cfg(not(feature = "qemu"))]
pub mod analog;
/// QEMU emulates no ADC sampling and no DMA: no acquisition ever starts (the type the app's
/// resources and its DMA task name).
#[cfg(feature = "qemu")]
pub mod analog {
    use de_resonator::acquire::Block;

    /// Never made under QEMU.
    pub enum Acquisition {}

    impl Acquisition {
        pub fn on_interrupt(&mut self, _: &mut Block) {
            match *self {}
        }
    }
}
pub mod chip;
pub mod config;
pub mod link;
#[cfg(all(feature = "link", feature = "model-sensor"))]
compile_error!("`link` takes the plant's samples from host-sim: build it without `model-sensor`");
pub mod reference;
pub mod runtime;
pub mod sensor;
pub mod stand_in;
pub mod storage;
pub mod stream;
pub mod switches;
pub mod watchdog;

pub use runtime::{exit, stack};
