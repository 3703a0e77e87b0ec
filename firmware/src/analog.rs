//! The analog inputs on silicon: TIM2's update (TRGO) triggers ADC1's scan of the image's
//! fitted channels at its `scan_hz`; DMA2 stream 0 moves the codes into a double buffer;
//! each full buffer's interrupt adds its scans to the tick's `Block` (the core's `acquire`,
//! which turns it into the controller's inputs). Everything through the HAL: the channels
//! are configured through its typed analog pins, chosen by the image's input numbers.
//!
//! An ADC overrun or a DMA transfer error stops the acquisition: the interrupt that sees it
//! re-arms the ADC and its stream and says the stall to the block; the core's reader counts
//! it, or faults on a second within a second (`acquire::Stall`).
//!
//! QEMU emulates neither the ADC's sampling nor DMA: this module is built and clippy-checked
//! for silicon (`--no-default-features --features rtt`) and not run in CI; under QEMU the
//! block is filled by a stand-in (`sensor`), and everything after it is the product's code
//! (the link build takes host-sim's injected stalls to the same block and reader).

use de_resonator::acquire::{Block, FrontEnd, Stall, BUFFER_CODES};
use stm32f4xx_hal::adc::config::{
    AdcConfig, Clock, Dma, ExternalTrigger, SampleTime, Scan, Sequence, TriggerMode,
};
use stm32f4xx_hal::adc::Adc;
use stm32f4xx_hal::dma::config::{DmaConfig, Priority};
use stm32f4xx_hal::dma::traits::StreamISR as _;
use stm32f4xx_hal::dma::{DMAError, PeripheralToMemory, Stream0, Transfer};
use stm32f4xx_hal::gpio::{Analog, PA0, PA1, PB1, PC0, PC1, PC2, PC3, PC4, PC5};
use stm32f4xx_hal::pac::{ADC1, DMA2, TIM2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::timer::{CounterHz, Timer};

/// The sampling time of each conversion, ADC clock cycles (with 12 for the conversion: 68
/// cycles, 3.2 µs at 21 MHz; the core's `MAX_CONVERSIONS_HZ` is below its rate).
const SAMPLE_TIME: SampleTime = SampleTime::Cycles_56;

/// The ADC's clock is APB2's over 4 (`Clock::Pclk2_div_4`): 21 MHz from the PLL, 4 MHz on the
/// HSI fallback.
pub const ADC_CLOCK_DIVIDER: u32 = 4;

/// The ADC's clock in use, Hz (the image's conversions are checked against it at boot).
pub fn adc_clock_hz(rcc: &Rcc) -> f32 {
    (rcc.clocks.pclk2().raw() / ADC_CLOCK_DIVIDER) as f32
}

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

/// The ADC's stream as the acquisition runs it.
type AdcTransfer = Transfer<Stream0<DMA2>, 0, Adc<ADC1>, PeripheralToMemory, Buffer>;

/// The running acquisition: the DMA transfer (`None` only inside a re-arm), the buffer not in
/// it, the stream's configuration (for a re-arm), and the scan's timer.
pub struct Acquisition {
    transfer: Option<AdcTransfer>,
    spare: Option<Buffer>,
    front_end: FrontEnd,
    dma: DmaConfig,
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

/// ADC1's status and control registers, for what the HAL's `Adc` does not reach: the overrun
/// flag (OVR) and its interrupt (OVRIE).
fn adc1() -> &'static stm32f4xx_hal::pac::adc1::RegisterBlock {
    // SAFETY: ADC1's registers; the overrun bits are touched only here, by the acquisition's
    // interrupts (one priority), and the HAL's `Adc` writes CR2 only inside a re-arm.
    unsafe { &*ADC1::ptr() }
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
        // An overrun stops the ADC's DMA requests: its interrupt (ADC) re-arms them.
        adc1().cr1().modify(|_, w| w.ovrie().set_bit());
        let [a, b, c] = parts.buffers;
        let (a, b, c) = (&mut a[..codes], &mut b[..codes], &mut c[..codes]);
        // The highest priority of DMA2's streams (the telemetry's stream 7 must not starve
        // it); a transfer error interrupts too, so the stream is re-armed.
        let dma = DmaConfig::default()
            .priority(Priority::VeryHigh)
            .transfer_complete_interrupt(true)
            .transfer_error_interrupt(true)
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
            transfer: Some(transfer),
            spare: Some(c),
            front_end: *front_end,
            dma,
            _timer: timer,
        })
    }

    /// The DMA's interrupt (a buffer full, or a transfer error) or the ADC's (an overrun).
    /// A stall first: the stream and the ADC re-armed, the stall said to `block` (the core's
    /// reader recovers from one and faults on a repeat). Else a full buffer: the spare to the
    /// stream, the full one's scans to `block`, kept as the next spare. An interrupt too late
    /// for the buffer switch (the HAL's overrun: the stream stopped) is a stall too.
    pub fn on_interrupt(&mut self, block: &mut Block) {
        if let Some(why) = self.stall() {
            self.rearm();
            block.stalled(why);
            return;
        }
        let (Some(transfer), Some(spare)) = (self.transfer.as_mut(), self.spare.take()) else {
            return;
        };
        if !transfer.is_transfer_complete() {
            self.spare = Some(spare);
            return;
        }
        match transfer.next_transfer(spare) {
            Ok((full, _)) => {
                block.add_scans(&self.front_end, full);
                self.spare = Some(full);
            }
            Err(DMAError::NotReady(buf) | DMAError::SmallBuffer(buf)) => self.spare = Some(buf),
            // The HAL's own overrun: too late for the buffer switch, the stream stopped.
            Err(DMAError::Overrun(buf)) => {
                self.spare = Some(buf);
                self.rearm();
                block.stalled(Stall::TransferError);
            }
        }
    }

    /// What stopped the acquisition, if anything: the stream's transfer error, or the ADC's
    /// overrun.
    fn stall(&self) -> Option<Stall> {
        if self
            .transfer
            .as_ref()
            .is_some_and(|t| t.is_transfer_error())
        {
            Some(Stall::TransferError)
        } else if adc1().sr().read().ovr().bit_is_set() {
            Some(Stall::Overrun)
        } else {
            None
        }
    }

    /// Re-arm after a stall (RM0090 §13.8.1, using the DMA: overrun recovery): the ADC off (ADON cleared: its scan
    /// starts again at the first channel, so the codes stay in their channels' places) and its
    /// DMA requests off; the stream stopped, its flags cleared; the ADC's flags cleared (OVR
    /// among them, written 0; the ADC is off, so none comes back at once); the stream set up
    /// again on its two buffers and enabled, then the ADC's DMA requests on, then the ADC on
    /// (its 3 µs start-up before TIM2's next trigger, 100 µs apart at 10 kHz).
    fn rearm(&mut self) {
        let Some(mut transfer) = self.transfer.take() else {
            return;
        };
        transfer.pause(|adc| {
            adc.disable();
            adc.set_dma(Dma::Disabled);
        });
        let (stream, adc, a, b) = transfer.release();
        // rc_w0 flags: a write of 0 clears each, and the ADC is off.
        adc1()
            .sr()
            .write(|w| w.ovr().clear_bit().eoc().clear_bit().strt().clear_bit());
        let mut transfer = Transfer::init_peripheral_to_memory(stream, adc, a, b, self.dma);
        transfer.start(|adc| {
            adc.set_dma(Dma::Continuous);
            adc.enable();
        });
        // t_STAB, 3 µs at most (datasheet), at 168 MHz.
        cortex_m::asm::delay(504);
        self.transfer = Some(transfer);
    }
}
