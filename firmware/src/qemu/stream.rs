//! The telemetry stream's port under QEMU, which emulates no DMA: each frame straight into
//! USART1's data register, which QEMU's USART takes at once.

use stm32f4xx_hal::pac::USART1;
use stm32f4xx_hal::serial::Tx;

/// The port, ready for frames.
pub struct StreamPort {
    tx: Tx<USART1>,
}

impl StreamPort {
    pub fn new(tx: Tx<USART1>) -> Self {
        Self { tx }
    }

    /// Send a frame; whether it went (always: QEMU's USART is never busy).
    pub fn send(&mut self, frame: &[u8]) -> bool {
        use embedded_hal_nb::serial::Write as _;
        for &byte in frame {
            let _ = nb::block!(self.tx.write(byte));
        }
        true
    }
}
