//! The chip: clocks, the tick's timer, and the pins and peripherals the app drives. Wiring
//! (README, Firmware: wiring):
//!
//! | signal | pin | peripheral |
//! |---|---|---|
//! | DAC8551 SCLK, DIN | PA5, PA7 (PA6 MISO unused) | SPI1, mode 1, 1 MHz |
//! | DAC8551 SYNC (chip select) | PA4 | GPIO, in `ExclusiveDevice` |
//! | amplifier enable (high: on) | PB0 | GPIO |
//! | command port TX, RX | PA2, PA3 | USART2, 115200 8N1 |
//! | telemetry stream TX | PA9 | USART1, 2 Mbaud 8N1, DMA2 stream 7 |
//! | the link build's bell from host-sim (QEMU only) | PB11 | USART3 RX |
//! | analog inputs (the image's front end) | PA0, PA1, PB1, PC0..PC5 (IN0, IN1, IN9, IN10..IN15) | ADC1, triggered by TIM2, DMA2 stream 0 |
//!
//! Silicon runs from an 8 MHz crystal (HSE) and the PLL at 168 MHz; the `qemu` build leaves
//! the clocks at reset (QEMU does not emulate RCC, and its SysTick runs at 168 MHz anyway).

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use embedded_hal_bus::spi::ExclusiveDevice;
use stm32f4xx_hal::gpio::{Output, Pin, PushPull};
use stm32f4xx_hal::pac::{self, SPI1, USART2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::{Config, Rcc};
use stm32f4xx_hal::serial::{self, Rx, Serial, Tx};
use stm32f4xx_hal::spi::Spi;

/// The DAC on SPI1 with its chip select.
pub type DacSpi =
    ExclusiveDevice<Spi<SPI1>, Pin<'A', 4, Output<PushPull>>, embedded_hal_bus::spi::NoDelay>;
/// The amplifier-enable line.
pub type EnablePin = Pin<'B', 0, Output<PushPull>>;
/// The output stage's DAC bus and enable line: as wired (silicon); under QEMU breakable by a
/// test (`Breakable`), and in the link build tapped, so the link reports what was last written.
#[cfg(not(feature = "qemu"))]
pub type StageSpi = DacSpi;
#[cfg(all(feature = "qemu", not(feature = "link")))]
pub type StageSpi = crate::qemu::bus::Breakable<DacSpi>;
#[cfg(not(feature = "link"))]
pub type StagePin = EnablePin;
#[cfg(feature = "link")]
pub type StageSpi = de_resonator::wire::link::Tap<crate::qemu::bus::Breakable<DacSpi>>;
#[cfg(feature = "link")]
pub type StagePin = de_resonator::wire::link::Tap<EnablePin>;

/// The DAC bus and the enable line as the output stage takes them.
pub fn stage_wires(dac: DacSpi, enable: EnablePin) -> (StageSpi, StagePin) {
    #[cfg(feature = "link")]
    {
        use crate::qemu::bus::Breakable;
        use de_resonator::wire::link::Tap;
        (Tap::new(Breakable(dac)), Tap::new(enable))
    }
    #[cfg(all(feature = "qemu", not(feature = "link")))]
    {
        (crate::qemu::bus::Breakable(dac), enable)
    }
    #[cfg(not(feature = "qemu"))]
    {
        (dac, enable)
    }
}

/// Polls of the output's state before a `reset` goes ahead anyway (a few ticks' worth: the
/// tick turns the output off at its next run).
pub const RESET_WAIT_POLLS: u32 = 2_000_000;

/// The command port's baud rate.
pub const BAUD: u32 = 115_200;
/// The SPI clock to the DAC (the DAC8551 takes up to 30 MHz).
const SPI_HZ: u32 = 1_000_000;
/// The crystal on the board, and the core clock from the PLL.
const HSE_HZ: u32 = 8_000_000;
const SYSCLK_HZ: u32 = 168_000_000;
/// Polls of a ready flag before the clock setup gives up (the HSE starts in about 2 ms, the
/// PLL locks in about 0.1 ms; 16 MHz HSI: a poll is a few cycles).
#[cfg(not(feature = "qemu"))]
const CLOCK_POLLS: u32 = 200_000;

/// Why the clock setup fell back to the 16 MHz internal oscillator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ClockError {
    /// The crystal did not start (HSERDY never set).
    Hse,
    /// The PLL did not lock (PLLRDY never set).
    Pll,
}

/// The peripherals the app owns, set up.
pub struct Chip {
    pub dac: DacSpi,
    pub enable: EnablePin,
    pub tx: Tx<USART2>,
    pub rx: Rx<USART2>,
    /// The telemetry stream's port (`None`: no divider gives its baud rate from the clock in
    /// use, the 16 MHz fallback: `stream` then answers that the board has none).
    pub stream_tx: Option<Tx<pac::USART1>>,
    /// Its DMA stream (silicon).
    #[cfg(not(feature = "qemu"))]
    pub stream_dma: stm32f4xx_hal::dma::Stream7<pac::DMA2>,
    /// The link build's bell from host-sim (`link`).
    #[cfg(feature = "link")]
    pub link: Rx<pac::USART3>,
    /// The core clock SysTick counts, Hz.
    pub core_hz: u32,
    /// The flash controller (the settings' storage on silicon).
    pub flash: pac::FLASH,
    /// The independent watchdog (not emulated by QEMU), and the debug unit that stops it
    /// while a debugger halts the core.
    pub iwdg: pac::IWDG,
    pub dbgmcu: pac::DBGMCU,
    /// Set when the crystal or the PLL failed and the board runs on HSI (slower, still safe:
    /// every rate is computed from the clock in use).
    pub clock_error: Option<ClockError>,
    /// The clocks, for the peripherals set up once the image is read (the ADC, its DMA).
    pub rcc: Rcc,
    /// The analog inputs' peripherals and pins (silicon; QEMU emulates no ADC sampling).
    #[cfg(not(feature = "qemu"))]
    pub analog: AnalogParts,
}

/// What the acquisition (`analog`) takes, apart from its buffers.
#[cfg(not(feature = "qemu"))]
pub struct AnalogParts {
    pub adc1: pac::ADC1,
    pub dma: stm32f4xx_hal::dma::Stream0<pac::DMA2>,
    pub tim2: pac::TIM2,
    pub pins: crate::analog::AnalogPins,
}

/// Poll `ready` up to `CLOCK_POLLS` times.
#[cfg(not(feature = "qemu"))]
fn wait(ready: impl Fn() -> bool) -> bool {
    (0..CLOCK_POLLS).any(|_| ready())
}

/// Whether the crystal starts and the PLL locks, each wait bounded. stm32f4xx-hal 0.23's
/// `freeze` waits on HSERDY and PLLRDY without a timeout (rcc/f4/mod.rs, lines 437 and 461),
/// so a board with a dead crystal would hang there at 0 V with no word said: we prove both
/// first, with timeouts, and call `freeze` only once they have worked.
#[cfg(not(feature = "qemu"))]
fn probe_clocks(rcc: &pac::RCC) -> Result<(), ClockError> {
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    if !wait(|| rcc.cr().read().hserdy().bit_is_set()) {
        rcc.cr().modify(|_, w| w.hseon().clear_bit());
        return Err(ClockError::Hse);
    }
    // PLL from HSE: 8 MHz / 8 × 336 / 2 = 168 MHz (Q = 7: 48 MHz).
    rcc.pllcfgr().write(|w| unsafe {
        w.pllsrc().hse();
        w.pllm().bits(8);
        w.plln().bits(336);
        w.pllp().div2();
        w.pllq().bits(7)
    });
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    let locked = wait(|| rcc.cr().read().pllrdy().bit_is_set());
    rcc.cr().modify(|_, w| w.pllon().clear_bit());
    let _ = wait(|| rcc.cr().read().pllrdy().bit_is_clear());
    if locked {
        Ok(())
    } else {
        Err(ClockError::Pll)
    }
}

/// The clocks: HSE + PLL at 168 MHz on silicon (HSI if either fails), reset clocks in QEMU.
fn clocks(rcc: Rcc) -> (Rcc, u32, Option<ClockError>) {
    #[cfg(feature = "qemu")]
    {
        // QEMU's SysTick counts at 168 MHz whatever RCC says (QEMU-STM32F405.md §1).
        (rcc, SYSCLK_HZ, None)
    }
    #[cfg(not(feature = "qemu"))]
    {
        match probe_clocks(&rcc) {
            Ok(()) => (
                rcc.freeze(Config::hse(HSE_HZ.Hz()).sysclk(SYSCLK_HZ.Hz())),
                SYSCLK_HZ,
                None,
            ),
            Err(e) => (rcc.freeze(Config::hsi()), 16_000_000, Some(e)),
        }
    }
}

impl Chip {
    /// Set up the board. The pins that hold the output safe come first, before the clock
    /// probe (which may wait milliseconds on a dead crystal): the amplifier's enable driven
    /// low, the DAC's SYNC high; the command port's RX pulled up (an unconnected port reads
    /// idle, not noise). Until then only the board's own pull-down holds the enable.
    pub fn new(dp: pac::Peripherals) -> Self {
        let mut rcc = dp.RCC.constrain();
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let enable = gpiob
            .pb0
            .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::Low);
        let cs = gpioa
            .pa4
            .into_push_pull_output_in_state(stm32f4xx_hal::gpio::PinState::High);
        let rx_pin = gpioa.pa3.internal_pull_up(true);
        let (mut rcc, core_hz, clock_error) = clocks(rcc);
        let _ = (HSE_HZ, Config::hsi);
        #[cfg(not(feature = "qemu"))]
        let streams = stm32f4xx_hal::dma::StreamsTuple::new(dp.DMA2, &mut rcc);
        #[cfg(not(feature = "qemu"))]
        let analog = {
            let gpioc = dp.GPIOC.split(&mut rcc);
            AnalogParts {
                adc1: dp.ADC1,
                dma: streams.0,
                tim2: dp.TIM2,
                pins: crate::analog::AnalogPins {
                    pa0: gpioa.pa0.into_analog(),
                    pa1: gpioa.pa1.into_analog(),
                    pb1: gpiob.pb1.into_analog(),
                    pc0: gpioc.pc0.into_analog(),
                    pc1: gpioc.pc1.into_analog(),
                    pc2: gpioc.pc2.into_analog(),
                    pc3: gpioc.pc3.into_analog(),
                    pc4: gpioc.pc4.into_analog(),
                    pc5: gpioc.pc5.into_analog(),
                },
            }
        };
        let spi = dp.SPI1.spi(
            (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
            embedded_hal::spi::MODE_1,
            SPI_HZ.Hz(),
            &mut rcc,
        );
        let dac = match ExclusiveDevice::new_no_delay(spi, cs) {
            Ok(dac) => dac,
            Err(never) => match never {},
        };
        let serial: Serial<USART2> = match dp.USART2.serial(
            (gpioa.pa2, rx_pin),
            serial::Config::default().baudrate(BAUD.bps()),
            &mut rcc,
        ) {
            Ok(serial) => serial,
            // 115200 baud from any of the clocks above is a valid divider.
            Err(_) => crate::runtime::exit(103),
        };
        let (tx, mut rx) = serial.split();
        rx.listen();
        let config = serial::Config::default().baudrate(crate::stream::BAUD.bps());
        #[cfg(not(feature = "qemu"))]
        let config = config.dma(serial::config::DmaConfig::Tx);
        let stream_tx = dp.USART1.tx(gpioa.pa9, config, &mut rcc).ok();
        #[cfg(feature = "link")]
        let link = {
            let serial: Serial<pac::USART3> = match dp.USART3.serial(
                (gpiob.pb10, gpiob.pb11),
                serial::Config::default().baudrate(BAUD.bps()),
                &mut rcc,
            ) {
                Ok(serial) => serial,
                Err(_) => crate::runtime::exit(103),
            };
            let (_, mut rx) = serial.split();
            rx.listen();
            rx
        };
        Self {
            dac,
            enable,
            tx,
            rx,
            stream_tx,
            #[cfg(not(feature = "qemu"))]
            stream_dma: streams.7,
            #[cfg(feature = "link")]
            link,
            core_hz,
            flash: dp.FLASH,
            iwdg: dp.IWDG,
            dbgmcu: dp.DBGMCU,
            clock_error,
            rcc,
            #[cfg(not(feature = "qemu"))]
            analog,
        }
    }
}

/// SysTick interrupts at `tick_hz` (rounded to whole core cycles), or `None` if the period
/// does not fit the 24-bit reload (below core_hz / 2²⁴, about 10 Hz at 168 MHz).
pub fn start_tick(syst: &mut SYST, core_hz: u32, tick_hz: f32) -> Option<u32> {
    let cycles = libm::roundf(core_hz as f32 / tick_hz);
    if !(2.0..=16_777_216.0).contains(&cycles) {
        return None;
    }
    let reload = cycles as u32 - 1;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(reload);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    Some(reload)
}

/// Core cycles since the SysTick period began (it counts down from its reload).
pub fn cycles_into_tick() -> u32 {
    SYST::get_reload().saturating_sub(SYST::get_current())
}

/// Whether QEMU was started with the semihosting argument `word` (`busy-idle`,
/// `sensor-fails`, `tick-hangs`, `dac-bus-fails`): test switches of QEMU runs, never on
/// silicon.
pub fn asked(word: &str) -> bool {
    #[cfg(feature = "qemu")]
    {
        semihosting::experimental::env::args::<64>()
            .is_ok_and(|args| (&args).into_iter().any(|a| a == Ok(word)))
    }
    #[cfg(not(feature = "qemu"))]
    {
        let _ = word;
        false
    }
}
