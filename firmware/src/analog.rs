//! The analog inputs on silicon: TIM2's update (TRGO) triggers ADC1's scan of the image's
//! fitted channels at its `scan_hz`; DMA2 stream 0 moves the codes into a double buffer;
//! each full buffer's interrupt adds its scans to the tick's `Block` (the core's `acquire`,
//! which turns it into the controller's inputs). Everything through the HAL: the channels
//! are configured through its typed analog pins, chosen by the image's input numbers.
//!
//! QEMU emulates neither the ADC's sampling nor DMA: this module is built and clippy-checked
//! for silicon (`--no-default-features --features rtt`) and not run in CI; under QEMU the
//! block is filled by a stand-in (`sensor`), and everything after it is the product's code.

use de_resonator::acquire::{Block, FrontEnd, BUFFER_CODES};
use stm32f4xx_hal::adc::config::{
    AdcConfig, Clock, Dma, ExternalTrigger, SampleTime, Scan, Sequence, TriggerMode,
};
use stm32f4xx_hal::adc::Adc;
use stm32f4xx_hal::dma::config::DmaConfig;
use stm32f4xx_hal::dma::{DMAError, PeripheralToMemory, Stream0, Transfer};
use stm32f4xx_hal::gpio::{Analog, PA0, PA1, PB1, PC0, PC1, PC2, PC3, PC4, PC5};
use stm32f4xx_hal::pac::{ADC1, DMA2, TIM2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::timer::{CounterHz, Timer};

/// The sampling time of each conversion, ADC clock cycles (with 12 for the conversion: 68
/// cycles, 3.2 µs at 21 MHz; the core's `MAX_CONVERSIONS_HZ` is below its rate).
const SAMPLE_TIME: SampleTime = SampleTime::Cycles_56;

/// A DMA buffer: a slice of one of the three static arrays, as long as a buffer's scans.
type Buffer = &'static mut [u16];

/// The pins the board leaves to analog inputs (`acquire::BOARD_INPUTS`), set to analog.
pub struct AnalogPins {
    pub pa0: PA0<Analog>,
    pub pa1: PA1<Analog>,
    pub pb1: PB1<Analog>,
    pub pc0: PC0<Analog>,
    pub pc1: PC1<Analog>,
    pub pc2: PC2<Analog>,
    pub pc3: PC3<Analog>,
    pub pc4: PC4<Analog>,
    pub pc5: PC5<Analog>,
}

impl AnalogPins {
    /// ADC input `input` as the `k`-th conversion of the scan; false for an input the board
    /// does not leave to analog (the image's check refuses those first).
    fn configure(&self, adc: &mut Adc<ADC1>, input: u8, k: u8) -> bool {
        let seq = Sequence::from(k);
        match input {
            0 => adc.configure_channel(&self.pa0, seq, SAMPLE_TIME),
            1 => adc.configure_channel(&self.pa1, seq, SAMPLE_TIME),
            9 => adc.configure_channel(&self.pb1, seq, SAMPLE_TIME),
            10 => adc.configure_channel(&self.pc0, seq, SAMPLE_TIME),
            11 => adc.configure_channel(&self.pc1, seq, SAMPLE_TIME),
            12 => adc.configure_channel(&self.pc2, seq, SAMPLE_TIME),
            13 => adc.configure_channel(&self.pc3, seq, SAMPLE_TIME),
            14 => adc.configure_channel(&self.pc4, seq, SAMPLE_TIME),
            15 => adc.configure_channel(&self.pc5, seq, SAMPLE_TIME),
            _ => return false,
        }
        true
    }
}

/// The running acquisition: the DMA transfer, the buffer not in it, and the scan's timer.
pub struct Acquisition {
    transfer: Transfer<Stream0<DMA2>, 0, Adc<ADC1>, PeripheralToMemory, Buffer>,
    spare: Option<Buffer>,
    front_end: FrontEnd,
    _timer: CounterHz<TIM2>,
}

/// The peripherals and memory an acquisition takes.
pub struct Parts {
    pub adc1: ADC1,
    /// DMA2's stream 0 (the board splits DMA2's streams: stream 7 is the telemetry's).
    pub dma: Stream0<DMA2>,
    pub tim2: TIM2,
    pub pins: AnalogPins,
    pub buffers: &'static mut [[u16; BUFFER_CODES]; 3],
}

impl Acquisition {
    /// Start the scans of `front_end`'s fitted channels, `scans_per_tick` a tick (the image's
    /// checked figure); `None` with no channel fitted, or an input the board cannot read.
    pub fn start(
        parts: Parts,
        rcc: &mut Rcc,
        front_end: &FrontEnd,
        scans_per_tick: u32,
    ) -> Option<Self> {
        let channels = front_end.fitted().count();
        let per_buffer = front_end.scans_per_buffer(scans_per_tick) as usize;
        let codes = channels * per_buffer;
        if codes == 0 || codes > BUFFER_CODES {
            return None;
        }
        let config = AdcConfig::default()
            .dma(Dma::Continuous)
            .scan(Scan::Enabled)
            .external_trigger(TriggerMode::RisingEdge, ExternalTrigger::Tim_2_trgo)
            .clock(Clock::Pclk2_div_4);
        let mut adc = Adc::new(parts.adc1, true, config, rcc);
        for (k, (_, spec)) in front_end.fitted().enumerate() {
            if !parts.pins.configure(&mut adc, spec.input, k as u8) {
                return None;
            }
        }
        let [a, b, c] = parts.buffers;
        let (a, b, c) = (&mut a[..codes], &mut b[..codes], &mut c[..codes]);
        let dma = DmaConfig::default()
            .transfer_complete_interrupt(true)
            .memory_increment(true)
            .double_buffer(true);
        let mut transfer = Transfer::init_peripheral_to_memory(parts.dma, adc, a, Some(b), dma);
        transfer.start(|adc| adc.enable());
        let mut timer = Timer::new(parts.tim2, rcc);
        timer.set_master_mode(stm32f4xx_hal::pac::tim2::cr2::MMS::Update);
        let mut timer = timer.counter_hz();
        timer
            .start((libm::roundf(front_end.scan_hz) as u32).Hz())
            .ok()?;
        Some(Self {
            transfer,
            spare: Some(c),
            front_end: *front_end,
            _timer: timer,
        })
    }

    /// A buffer is full (DMA2 stream 0's transfer-complete interrupt): hand the stream the
    /// spare, add the full one's scans to `block`, keep it as the next spare. An interrupt late
    /// by a whole buffer loses that buffer (a tick takes fewer scans: its checked path reads
    /// them); one the chip's DMA stopped on (a transfer error) gives no more: the next ticks'
    /// blocks are empty, a fault by name (`InputError::NoSamples`), down to 0 V, and only a
    /// reset starts the DMA again.
    pub fn on_buffer(&mut self, block: &mut Block) {
        let Some(spare) = self.spare.take() else {
            return;
        };
        match self.transfer.next_transfer(spare) {
            Ok((full, _)) => {
                block.add_scans(&self.front_end, full);
                self.spare = Some(full);
            }
            Err(DMAError::NotReady(buf) | DMAError::SmallBuffer(buf) | DMAError::Overrun(buf)) => {
                self.spare = Some(buf)
            }
        }
    }
}
