//! The output stage as the IO side holds it (the "shell" around the sans-IO controller):
//! the DAC and the amplifier's enable line, and the one reaction to any fault. The firmware
//! and host-sim's loop both drive through it.
//!
//! The safe state: the enable line low at once (it works when the bus does not: a dead bus
//! keeps the DAC's last code), then the DAC powered down (output to ground through 1 kΩ).

use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiDevice;

use crate::controller::{Controller, Fault, Output, Phase};
use crate::drive::{Dac8551, DacError};

/// What failed on the way out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StageError<S, P> {
    /// The DAC's SPI transfer.
    Bus(S),
    /// The enable line.
    Pin(P),
}

impl<S: core::fmt::Debug, P: core::fmt::Debug> core::fmt::Display for StageError<S, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StageError::Bus(e) => write!(f, "DAC bus error: {e:?}"),
            StageError::Pin(e) => write!(f, "amplifier-enable line error: {e:?}"),
        }
    }
}

impl<S: core::fmt::Debug, P: core::fmt::Debug> core::error::Error for StageError<S, P> {}

/// The DAC and the amplifier's enable line.
pub struct OutputStage<SPI, EN> {
    dac: Dac8551<SPI>,
    enable: EN,
    /// Whether the stage is in its safe state (enable low, DAC down).
    safe: bool,
}

impl<SPI: SpiDevice, EN: OutputPin> OutputStage<SPI, EN> {
    /// A stage in its safe state: call `safe` at once (the pins' power-on state is the
    /// board's), and `enable` only after the boot checks passed.
    pub fn new(dac: Dac8551<SPI>, enable: EN) -> Self {
        Self {
            dac,
            enable,
            safe: true,
        }
    }

    /// Raise the enable line: the amplifier follows the DAC.
    pub fn enable(&mut self) -> Result<(), StageError<SPI::Error, EN::Error>> {
        self.enable.set_high().map_err(StageError::Pin)?;
        self.safe = false;
        Ok(())
    }

    /// The safe state: the enable line low first, then the DAC powered down. Both are
    /// tried whatever the other does; the first error is returned.
    pub fn safe(&mut self) -> Result<(), StageError<SPI::Error, EN::Error>> {
        self.safe = true;
        let pin = self.enable.set_low().map_err(StageError::Pin);
        let bus = self
            .dac
            .power_down()
            .map_err(|DacError::Bus(e)| StageError::Bus(e));
        pin.and(bus)
    }

    /// Send one tick's output: its code, or the safe state once a fault's descent has
    /// reached 0 V (or the bus fails now, which faults the controller: the enable line drops
    /// at once). Nothing is written while the stage is safe (before `enable`, or after a
    /// fault). `out` is left as it was sent: a bus failure makes it code 0 with
    /// `Event::Fault(Fault::Bus)`. (In place, not a copy in and out: the tick's budget.)
    pub fn send(&mut self, controller: &mut Controller, out: &mut Output) {
        if self.safe {
            return;
        }
        if out.volts == 0.0 && controller.phase() == Phase::Faulted {
            let _ = self.safe();
            return;
        }
        if self.dac.write(out.code).is_err() {
            *out = controller.fault(Fault::Bus);
            let _ = self.safe();
        }
    }

    /// Whether the stage is in its safe state.
    pub fn is_safe(&self) -> bool {
        self.safe
    }

    /// The DAC, for a caller that inspects its bus.
    pub fn dac(&self) -> &Dac8551<SPI> {
        &self.dac
    }

    /// The enable line, for a caller that inspects it.
    pub fn enable_line(&self) -> &EN {
        &self.enable
    }

    /// The DAC and the enable line back.
    pub fn release(self) -> (Dac8551<SPI>, EN) {
        (self.dac, self.enable)
    }
}
