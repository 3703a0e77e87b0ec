//! The firmware for the STM32F405: an RTIC application (`bin/firmware.rs`) that reads its
//! device, table, amplifier and settings from the configuration image in flash sector 11,
//! ticks the core's controller on SysTick, writes the DAC through SPI1, and serves the
//! command port on USART2. The logic is in the `de-resonator` core; nothing here decides a
//! voltage, answers a request or decides when the amplifier is on (the core's `board`). One
//! module a part: `board` (clocks, pins, peripherals), `config` (the image), `sensor` (what
//! the tick measures), `storage` (where `save` keeps the settings), `watchdog` (the IWDG, or its QEMU stand-in), `runtime` (exit codes,
//! panic and fault handlers, the stack meter); `reference` and `stand_in` serve the
//! on-target checks and counts only.
#![no_std]

use cortex_m as _;
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "log-semihosting")]
use defmt_semihosting as _;

pub mod board;
pub mod config;
pub mod reference;
pub mod runtime;
pub mod sensor;
pub mod stand_in;
pub mod storage;
pub mod watchdog;

pub use runtime::{exit, stack};
