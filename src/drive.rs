//! The drive chain: volts at the membrane ↔ DAC codes through the high-voltage amplifier,
//! and a driver for the DAC, generic over embedded-hal 1.0 `SpiDevice`.
//!
//! The DAC is the Texas Instruments DAC8551 (16-bit, single channel, straight binary,
//! datasheet SLAS429, "Serial Interface"): one 24-bit frame per update, MSB first, SPI mode 1
//! (data sampled on the falling edge of SCLK, SYNC low for the frame):
//!
//! | bits 23..18 | bits 17..16 | bits 15..0 |
//! |---|---|---|
//! | don't care (0) | PD1 PD0: 00 normal, 01 output to GND via 1 kΩ | data, code |
//!
//! The output is Vref·code/65536 and the amplifier multiplies it by its gain, so the full
//! scale at the membrane is Vref·gain.

use core::fmt;

use crate::numerics::decimal::Decimal;

use embedded_hal::spi::SpiDevice;

/// A 16-bit DAC code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DacCode(pub u16);

/// The amplifier and DAC reference as one transfer: membrane volts per code step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Amplifier {
    /// Membrane volts at code 65536 (Vref times the amplifier's gain), V.
    full_scale_volts: f32,
    /// The highest voltage it gives: the top code's, or the amplifier's rail if lower, V.
    max_volts: f32,
}

/// Why a voltage has no code.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CodeError {
    /// The full scale is NaN, infinite or not positive.
    BadFullScale { volts: f32 },
    /// The voltage is NaN, negative, or beyond the amplifier's range.
    OutOfRange { volts: f32, max_volts: f32 },
    /// The rail is NaN or not positive.
    BadRail { volts: f32 },
}

impl fmt::Display for CodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            CodeError::BadFullScale { volts } => {
                write!(
                    f,
                    "amplifier full scale {} V is not a positive number",
                    Decimal(volts)
                )
            }
            CodeError::BadRail { volts } => {
                write!(
                    f,
                    "amplifier rail {} V is not a positive number",
                    Decimal(volts)
                )
            }
            CodeError::OutOfRange { volts, max_volts } => {
                write!(
                    f,
                    "{} V is outside the amplifier's range [0, {}] V",
                    Decimal(volts),
                    Decimal(max_volts)
                )
            }
        }
    }
}

impl Amplifier {
    /// A transfer of `reference_volts` (DAC Vref) times `gain` (amplifier V/V).
    pub fn new(reference_volts: f32, gain: f32) -> Result<Self, CodeError> {
        let full_scale_volts = reference_volts * gain;
        if !(full_scale_volts.is_finite() && full_scale_volts > 0.0) {
            return Err(CodeError::BadFullScale {
                volts: full_scale_volts,
            });
        }
        let top = Self {
            full_scale_volts,
            max_volts: f32::INFINITY,
        };
        Ok(Self {
            max_volts: top.volts(DacCode(u16::MAX)),
            ..top
        })
    }

    /// The same transfer on an amplifier whose output stops at `rail_volts`: no code above
    /// the rail (a positive number; the top code's voltage if it is lower).
    pub fn with_rail(self, rail_volts: f32) -> Result<Self, CodeError> {
        if !(rail_volts > 0.0) {
            return Err(CodeError::BadRail { volts: rail_volts });
        }
        Ok(Self {
            max_volts: self.max_volts.min(rail_volts),
            ..self
        })
    }

    /// The highest voltage it gives, V.
    pub fn max_volts(&self) -> f32 {
        self.max_volts
    }

    /// Volts at the membrane for a code.
    pub fn volts(&self, code: DacCode) -> f32 {
        f32::from(code.0) * (self.full_scale_volts / 65536.0)
    }

    /// The largest code whose voltage does not exceed `volts` (rounding down, never up).
    pub fn code(&self, volts: f32) -> Result<DacCode, CodeError> {
        let max_volts = self.max_volts();
        if !(volts >= 0.0 && volts <= max_volts) {
            return Err(CodeError::OutOfRange { volts, max_volts });
        }
        let steps = volts * (65536.0 / self.full_scale_volts);
        // Truncation rounds down; the float product may land a hair above an exact step (by
        // one code at most), so step back while the code's voltage exceeds the request.
        let mut code = (steps as u32).min(u32::from(u16::MAX)) as u16;
        for _ in 0..2 {
            if code > 0 && self.volts(DacCode(code)) > volts {
                code -= 1;
            }
        }
        Ok(DacCode(code))
    }
}

/// DAC8551 power modes (PD1 PD0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerMode {
    Normal = 0b00,
    /// Output to ground through 1 kΩ: the amplifier sees 0 V.
    GroundedOneKilohm = 0b01,
}

/// The 24-bit frame for a power mode and a code, MSB first.
pub fn frame(mode: PowerMode, code: DacCode) -> [u8; 3] {
    let [high, low] = code.0.to_be_bytes();
    [mode as u8, high, low]
}

/// A DAC bus error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DacError<E> {
    /// The SPI transfer failed.
    Bus(E),
}

impl<E: fmt::Debug> fmt::Display for DacError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DacError::Bus(e) => write!(f, "DAC bus error: {e:?}"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for DacError<E> {}

impl core::error::Error for CodeError {}

/// TI DAC8551 on an SPI bus.
pub struct Dac8551<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> Dac8551<SPI> {
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Set the output to `code`.
    pub fn write(&mut self, code: DacCode) -> Result<(), DacError<SPI::Error>> {
        self.spi
            .write(&frame(PowerMode::Normal, code))
            .map_err(DacError::Bus)
    }

    /// Ground the output through 1 kΩ (code 0): the safe state.
    pub fn power_down(&mut self) -> Result<(), DacError<SPI::Error>> {
        self.spi
            .write(&frame(PowerMode::GroundedOneKilohm, DacCode(0)))
            .map_err(DacError::Bus)
    }

    /// The bus, for a caller that inspects it (a simulated DAC).
    pub fn bus(&self) -> &SPI {
        &self.spi
    }

    /// The bus back, for a caller that shares it.
    pub fn release(self) -> SPI {
        self.spi
    }
}
