//! What QEMU's netduinoplus2 does not emulate, and what stands in for it in the QEMU builds
//! (`qemu`): none of it is on silicon. The codes its tick reads in place of the ADC's are
//! `sensor`'s, its test switches `switches`' (both nothing on silicon; docs/firmware.md).
//!
//! - `clock`: TIM2 counting microseconds of virtual time, the stand-ins' clock.
//! - `dog`: the watchdog (no IWDG): the feeds' clock readings, checked from TIM3.
//! - `flash`: the settings' and the fault log's flash (no flash controller): `.uninit` RAM
//!   pages that a reset keeps, each erase stalling as a chip's does.
//! - `bus`: a DAC bus a test can break (QEMU's SPI never fails), kept broken through resets.
//! - `analog`: no acquisition (no ADC sampling, no DMA); `sensor` fills the tick's block.
//! - `stream`: the telemetry stream's port straight into USART1's data register (no DMA).

pub mod analog;
pub mod bus;
pub mod clock;
pub mod dog;
pub mod flash;
pub mod stream;
