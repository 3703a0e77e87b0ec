//! Board glue shared by the firmware's binaries: the defmt transport, exit codes, the panic
//! and HardFault handlers, the DAC bus, and the device, table and settings flashed with it.
//! The logic is in the `de-resonator` core; nothing here decides a voltage.
#![no_std]

use cortex_m as _;
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "qemu")]
use defmt_semihosting as _;

use de_resonator::{Amplifier, DeviceParams, Settings, REFERENCE_DEVICE};
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

/// The tuning table for the reference device, from `host-sim lut` (tables/reference.bin).
pub static TABLE: &[u8] = include_bytes!("../../tables/reference.bin");

/// The device this firmware drives: the reference device of MODEL.md §9, in f32.
pub fn device() -> DeviceParams<f32> {
    REFERENCE_DEVICE.cast()
}

/// DAC8551 with a 2.5 V reference into an amplifier of gain 4000: 0 to 10 kV.
pub const DAC_REFERENCE_VOLTS: f32 = 2.5;
pub const AMPLIFIER_GAIN: f32 = 4000.0;

pub fn amplifier() -> Result<Amplifier, de_resonator::CodeError> {
    Amplifier::new(DAC_REFERENCE_VOLTS, AMPLIFIER_GAIN)
}

/// The reference run: 44 Hz, then 100 V of AC at 40 Hz.
pub fn settings() -> Settings {
    Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    }
}

/// End the run with a status (QEMU's exit status under semihosting).
pub fn exit(code: i32) -> ! {
    #[cfg(feature = "qemu")]
    semihosting::process::exit(code);
    #[cfg(not(feature = "qemu"))]
    {
        let _ = code;
        loop {
            cortex_m::asm::bkpt();
        }
    }
}

#[defmt::panic_handler]
fn defmt_panic() -> ! {
    exit(101)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    exit(101)
}

#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    defmt::error!(
        "HardFault at pc {=u32:#x}, lr {=u32:#x}",
        frame.pc(),
        frame.lr()
    );
    exit(102)
}

/// The DAC's SPI bus as QEMU has it: no DAC on the board, so frames are counted and the
/// last one kept. A bus that fails after `fail_after` frames stands for a broken wire.
pub struct RecordingBus {
    pub frames: u32,
    pub last: [u8; 3],
    pub fail_after: Option<u32>,
}

impl RecordingBus {
    pub const fn new(fail_after: Option<u32>) -> Self {
        Self {
            frames: 0,
            last: [0; 3],
            fail_after,
        }
    }
}

impl ErrorType for RecordingBus {
    type Error = embedded_hal::spi::ErrorKind;
}

impl SpiDevice for RecordingBus {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        if self.fail_after.is_some_and(|n| self.frames >= n) {
            return Err(embedded_hal::spi::ErrorKind::Other);
        }
        for op in operations {
            if let Operation::Write(bytes) = op {
                for (slot, b) in self.last.iter_mut().zip(bytes.iter()) {
                    *slot = *b;
                }
                self.frames += 1;
            }
        }
        Ok(())
    }
}
