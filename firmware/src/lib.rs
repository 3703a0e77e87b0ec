//! The firmware for the STM32F405: an RTIC application (`bin/firmware.rs`) that reads its
//! device, table, amplifier and settings from the configuration image in flash sector 11,
//! ticks the core's controller on SysTick, writes the DAC through SPI1, and serves the
//! command port on USART2. The logic is in the `de-resonator` core; nothing here decides a
//! voltage, answers a request or decides when the amplifier is on (the core's `board`). One
//! module a part: `chip` (clocks, pins, peripherals), `analog` (silicon's ADC, its timer and
//! DMA, filling the tick's block of codes), `config` (the image), `storage` (where `save`
//! keeps the settings and the board its fault log), `stream` (the telemetry stream's port),
//! `watchdog` (the IWDG), `link` (the link build's ends of host-sim's link), `runtime` (exit
//! codes, panic and fault handlers, the stack meter). `qemu` holds what stands in for what
//! QEMU does not emulate (a clock, the watchdog, the flash, a DAC bus that can fail, the ADC
//! and DMA, the stream's DMA), in the QEMU builds only. Compiled in every build but doing
//! nothing on silicon: `sensor` (the codes QEMU's tick reads in place of the ADC's;
//! `NoSensor` on silicon), `switches` (QEMU's test switches in the tick) and `link` (the link
//! build's ends). `reference` and `stand_in` serve the on-target checks and counts only.
#![no_std]

use cortex_m as _;
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "log-semihosting")]
use defmt_semihosting as _;

#[cfg(not(feature = "qemu"))]
pub mod analog;
pub mod chip;
pub mod config;
pub mod link;
#[cfg(feature = "qemu")]
pub mod qemu;
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
