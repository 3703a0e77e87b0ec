//! Stand-ins for the on-target checks and counts (`check`, `count`), which run without the
//! board's peripherals: a DAC bus that records its frames, an enable line that keeps its
//! level. The product (`firmware`) drives the real SPI1 and GPIO.

use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

/// An amplifier-enable line that keeps the level set.
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

/// A DAC bus that counts its frames and keeps the last one; one that fails after
/// `fail_after` frames stands for a broken wire.
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
