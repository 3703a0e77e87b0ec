//! The telemetry stream's port: USART1's TX (PA9) at `BAUD`, a line of its own so the command
//! port stays a line protocol. The records (the core's `wire::stream`) are taken and framed
//! in the idle loop, outside the tick; a frame goes out on silicon by DMA (DMA2 stream 7,
//! channel 4) from one of two buffers while the other is filled; under QEMU (which emulates
//! no DMA) `qemu::stream`'s port writes straight into the data register.

#[cfg(not(feature = "qemu"))]
use de_resonator::wire::stream::FRAME_BYTES;
#[cfg(not(feature = "qemu"))]
use stm32f4xx_hal::pac::USART1;
#[cfg(not(feature = "qemu"))]
use stm32f4xx_hal::serial::Tx;

/// The stream port's baud rate: 1 kHz records (66 kB/s, 660 kbaud with 8N1) with room.
pub const BAUD: u32 = 2_000_000;

#[cfg(not(feature = "qemu"))]
type Frame = &'static mut [u8; FRAME_BYTES];

/// The port, ready for frames: a DMA transfer under way or done, and the spare buffer.
#[cfg(not(feature = "qemu"))]
pub struct StreamPort {
    transfer: stm32f4xx_hal::dma::Transfer<
        stm32f4xx_hal::dma::Stream7<stm32f4xx_hal::pac::DMA2>,
        4,
        Tx<USART1>,
        stm32f4xx_hal::dma::MemoryToPeripheral,
        Frame,
    >,
    spare: Option<Frame>,
}

#[cfg(not(feature = "qemu"))]
impl StreamPort {
    /// The port on `stream`, `tx` set up with its DMA request (`serial::config::DmaConfig::Tx`).
    /// The first transfer sends the first buffer's zeros: empty frames, which a receiver
    /// skips.
    pub fn new(
        stream: stm32f4xx_hal::dma::Stream7<stm32f4xx_hal::pac::DMA2>,
        tx: Tx<USART1>,
        buffers: &'static mut [[u8; FRAME_BYTES]; 2],
    ) -> Self {
        use stm32f4xx_hal::dma::{config::DmaConfig, Transfer};
        let [first, spare] = buffers;
        let mut transfer = Transfer::init_memory_to_peripheral(
            stream,
            tx,
            first,
            None,
            DmaConfig::default().memory_increment(true),
        );
        transfer.start(|_| {});
        Self {
            transfer,
            spare: Some(spare),
        }
    }

    /// Send a frame if the last one is out; whether it went (a frame not sent is a record the
    /// receiver counts as lost).
    pub fn send(&mut self, frame: &[u8]) -> bool {
        use stm32f4xx_hal::dma::traits::DmaFlagExt as _;
        use stm32f4xx_hal::dma::DMAError;
        use stm32f4xx_hal::ReadFlags as _;
        if !self.transfer.flags().is_transfer_complete() {
            return false;
        }
        let Some(spare) = self.spare.take() else {
            return false;
        };
        // Every frame is FRAME_BYTES long (COBS of a fixed record); zeros after a shorter one
        // are empty frames.
        spare.fill(0);
        for (slot, &byte) in spare.iter_mut().zip(frame) {
            *slot = byte;
        }
        match self.transfer.next_transfer(spare) {
            Ok((sent, _)) => {
                self.spare = Some(sent);
                true
            }
            Err(DMAError::NotReady(b) | DMAError::SmallBuffer(b) | DMAError::Overrun(b)) => {
                self.spare = Some(b);
                false
            }
        }
    }
}
