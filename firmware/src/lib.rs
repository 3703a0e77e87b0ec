//! Board glue shared by the firmware's binaries: the defmt transport, exit codes, the panic
//! and HardFault handlers, the stack meter, the DAC bus, and the device, table and settings
//! flashed with it. The logic is in the `de-resonator` core; nothing here decides a voltage.
#![no_std]

use cortex_m as _;
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(feature = "log-semihosting")]
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

#[cfg(feature = "defmt")]
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    exit(101)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    #[cfg(feature = "defmt")]
    defmt::error!("panic");
    exit(101)
}

#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    #[cfg(feature = "defmt")]
    defmt::error!(
        "HardFault at pc {=u32:#x}, lr {=u32:#x}",
        frame.pc(),
        frame.lr()
    );
    let _ = frame;
    exit(102)
}

/// The stack's high-water mark, by painting: `paint` fills the free stack below the caller
/// with a pattern, `used_below` finds the lowest word that lost it. Runtime glue (raw
/// memory); only valid while no interrupt handler runs (none does in these binaries).
pub mod stack {
    use core::ptr::{addr_of, read_volatile, write_volatile};

    const PAINT: u32 = 0xC0DE_CAFE;
    /// Left unpainted below `paint`'s own stack pointer.
    const SLACK_BYTES: u32 = 16;

    extern "C" {
        /// End of the statics, start of the stack's room (cortex-m-rt's link.x).
        static __sheap: u32;
        /// The top of RAM, where the stack starts.
        static _stack_start: u32;
    }

    /// Where the stack starts (only the symbol's address is taken).
    pub fn top() -> u32 {
        addr_of!(_stack_start) as u32
    }

    /// The lowest address the stack may reach (only the symbol's address is taken).
    fn bottom() -> u32 {
        addr_of!(__sheap) as u32
    }

    /// The stack pointer now.
    pub fn pointer() -> u32 {
        cortex_m::register::msp::read()
    }

    /// Paint the free stack from the end of the statics to just below this call's frame.
    #[inline(never)]
    pub fn paint() {
        let sp = pointer();
        let mut at = bottom();
        while at + SLACK_BYTES < sp {
            // SAFETY: [__sheap, sp − slack) is RAM no one uses: below the live stack (no
            // interrupts run), above the statics.
            unsafe { write_volatile(at as *mut u32, PAINT) };
            at += 4;
        }
    }

    /// Bytes of stack used below the address `mark` since `paint` (called with the stack
    /// pointer at or above `mark`).
    pub fn used_below(mark: u32) -> u32 {
        let mut at = bottom();
        // SAFETY: reads of the painted RAM, between the statics and `mark`.
        while at < mark && unsafe { read_volatile(at as *const u32) } == PAINT {
            at += 4;
        }
        mark - at
    }
}

/// The amplifier-enable line as QEMU has it: GPIO is not emulated (writes are ignored), so
/// this stand-in keeps the level the firmware set. On a board it is the HAL's output pin.
#[derive(Default)]
pub struct EnableLine {
    pub high: bool,
}

impl embedded_hal::digital::ErrorType for EnableLine {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::OutputPin for EnableLine {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.high = true;
        Ok(())
    }
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
