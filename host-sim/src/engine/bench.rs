//! The bench the closed loop runs on: the board's outputs and inputs as simulated hardware.
//! A DAC8551 on a simulated `SpiDevice` (the real `Dac8551` driver writes its frames), the
//! amplifier's enable line, the displacement sensor and the current monitor, and their noise
//! (reproducible from a seed).

use std::cell::Cell;
use std::convert::Infallible;

use embedded_hal::digital::{self, OutputPin};
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// The DAC8551 as its datasheet has it: 24-bit frames (PD1 PD0, then the code MSB first),
/// VOUT = VREF·code/65536, 0 V when powered down. Its bus fails after `fail_after` frames.
/// Shared (`&SimulatedDac` is the `SpiDevice`), so the loop reads its output and fails its
/// bus while the output stage holds it.
#[derive(Default)]
pub struct SimulatedDac {
    pub reference_volts: f64,
    pub output_volts: Cell<f64>,
    /// The last frame's code, and whether it powered the DAC on.
    pub last: Cell<(u16, bool)>,
    pub frames: Cell<u64>,
    pub fail_after: Cell<Option<u64>>,
}

impl ErrorType for &SimulatedDac {
    type Error = ErrorKind;
}

impl SpiDevice for &SimulatedDac {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        if self
            .fail_after
            .get()
            .is_some_and(|n| self.frames.get() >= n)
        {
            return Err(ErrorKind::Other);
        }
        for op in operations {
            let Operation::Write(bytes) = op else {
                return Err(ErrorKind::Other);
            };
            let (code, on) = de_resonator::wire::link::dac_frame(bytes).ok_or(ErrorKind::Other)?;
            self.frames.set(self.frames.get() + 1);
            self.show(code, on);
        }
        Ok(())
    }
}

impl SimulatedDac {
    /// The output after a frame of `code`, powered `on` or down.
    pub fn show(&self, code: u16, on: bool) {
        self.last.set((code, on));
        self.output_volts.set(if on {
            self.reference_volts * f64::from(code) / 65536.0
        } else {
            0.0
        });
    }
}

/// The amplifier's enable line: high lets the amplifier follow the DAC.
#[derive(Default)]
pub struct EnableLine {
    pub high: Cell<bool>,
}

impl digital::ErrorType for &EnableLine {
    type Error = Infallible;
}

impl OutputPin for &EnableLine {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.high.set(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.high.set(true);
        Ok(())
    }
}

/// The displacement sensor: what it reads of λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    /// Standard deviation of its Gaussian noise, in stretch.
    pub noise: f64,
    /// Its quantum, in stretch (0: none).
    pub resolution: f64,
    /// A sample every this many controller ticks.
    pub every_ticks: u32,
    /// From this time on it repeats its last reading (a stuck sensor), s.
    pub stuck_after_seconds: Option<f64>,
    /// Whether the controller also reads the amplifier's monitor output.
    pub amplifier_monitor: bool,
}

/// The amplifier's current monitor as the controller reads it: the mean over a tick of the
/// output current (model.md §8), with noise and a quantum.
#[derive(Clone, Copy, Debug)]
pub struct CurrentMonitor {
    /// RMS noise of a tick's mean, A.
    pub noise_amps: f64,
    /// The quantum of a tick's mean, A (0: none).
    pub resolution_amps: f64,
}

impl CurrentMonitor {
    /// The reading of a true mean current `amps`.
    pub(crate) fn read(&self, amps: f64, noise: &mut Noise) -> f64 {
        let x = amps + self.noise_amps * noise.gaussian();
        if self.resolution_amps > 0.0 {
            (x / self.resolution_amps).round() * self.resolution_amps
        } else {
            x
        }
    }
}

/// Reproducible noise from a seed: SplitMix64, normal deviates by the ziggurat
/// (rand_distr's `StandardNormal`).
pub(crate) struct Noise(pub(crate) u64);

impl Noise {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A standard normal deviate.
    pub(crate) fn gaussian(&mut self) -> f64 {
        rand_distr::Distribution::sample(&rand_distr::StandardNormal, self)
    }
}

impl rand_core::TryRng for Noise {
    type Error = core::convert::Infallible;

    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        Ok((self.next_u64() >> 32) as u32)
    }

    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        Ok(self.next_u64())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        for chunk in dst.chunks_mut(8) {
            let bytes = self.next_u64().to_le_bytes();
            chunk.copy_from_slice(&bytes[..chunk.len()]);
        }
        Ok(())
    }
}

/// The board's outputs as the plant sees them: the DAC on its bus, the amplifier's enable line
/// (the output stage borrows both).
#[derive(Default)]
pub struct Wires {
    pub bus: SimulatedDac,
    pub enable: EnableLine,
}
