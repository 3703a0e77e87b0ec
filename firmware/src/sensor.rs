//! QEMU's stand-ins for the analog inputs. On silicon the DMA fills the tick's block of ADC
//! codes (`analog`); QEMU emulates neither the ADC's sampling nor DMA, so its builds fill the
//! block here, and everything after it (the image's front end, its checks, the controller)
//! is the product's code. `NoSensor` fills nothing (an image with a front end then faults:
//! no samples); `ModelSensor` (`model-sensor`, for testing the trim under QEMU) gives the
//! codes of the flashed device's own model, stepped at each tick with the voltage commanded.

use de_resonator::acquire::{Block, Channel, FrontEnd};
use de_resonator::{Device, DeviceParams, Drive, Integrator, Method, State};

/// The tick's stand-in measurements: codes added to the block before the tick reads it; told
/// the voltage after it.
pub trait Sensor {
    /// Add this tick's scans to `block`.
    fn fill(&mut self, block: &mut Block) {
        let _ = block;
    }
    /// The voltage the tick commanded (a model plant steps with it).
    fn commanded(&mut self, volts: f32) {
        let _ = volts;
    }
}

/// No stand-in: silicon's DMA fills the block, or (QEMU) nothing does.
pub struct NoSensor;

impl Sensor for NoSensor {}

/// The flashed device's model as the plant (RK4, one step a tick, substeps if needed), read
/// through the image's front end: its stretch, the amplifier's voltage, and the current
/// (the membrane's charge over the tick, model.md §8) as codes, `scans` a tick. `None`
/// until an image gives a device.
pub struct ModelSensor {
    plant: Option<(Device<f32>, Integrator<f32>)>,
    front_end: FrontEnd,
    scans: u32,
    tick_hz: f32,
    volts: f32,
    /// The stretch at the start of the last step (the current's charge difference).
    before: f32,
    /// A sensor that fails: its line open (pulled to code 0) from this many ticks on (a QEMU
    /// test's `sensor-fails`).
    fails_after: Option<u32>,
    ticks: u32,
}

impl ModelSensor {
    /// The model of `params` at rest at the pre-stretch, stepped at `tick_hz`, read through
    /// `front_end` with `scans` scans a tick.
    pub fn new(
        params: Option<DeviceParams<f32>>,
        front_end: FrontEnd,
        scans: u32,
        tick_hz: f32,
    ) -> Self {
        let plant = params.and_then(|p| {
            let device = Device::new(p).ok()?;
            let rest = State {
                stretch: device.prestretch_1(),
                velocity: 0.0,
            };
            let drive = Drive::constant(&device, 0.0);
            let range = device.model_range();
            let model =
                Integrator::new(device, drive, Method::Rk4, 1.0 / tick_hz, range, rest, true)
                    .ok()?;
            Some((device, model))
        });
        let before = plant.as_ref().map_or(0.0, |(d, _)| d.prestretch_1());
        Self {
            plant,
            front_end,
            scans,
            tick_hz,
            volts: 0.0,
            before,
            fails_after: None,
            ticks: 0,
        }
    }

    /// The same sensor failing (its output line open, for good) after `ticks` ticks: a
    /// runtime fault whose cause stays present, for the QEMU tests of the latch and `clear`.
    pub fn failing_after(self, ticks: Option<f32>) -> Self {
        Self {
            fails_after: ticks.map(|n| n as u32),
            ..self
        }
    }
}

impl Sensor for ModelSensor {
    fn fill(&mut self, block: &mut Block) {
        self.ticks = self.ticks.saturating_add(1);
        let failed = self.fails_after.is_some_and(|n| self.ticks > n);
        let Some((device, model)) = &self.plant else {
            return;
        };
        let stretch = model.state().stretch;
        let farads = |l: f32| device.params().capacitance_farads(l);
        let amps = self.volts * (farads(stretch) - farads(self.before)) * self.tick_hz;
        for _ in 0..self.scans {
            for (channel, spec) in self.front_end.fitted() {
                let reading = match channel {
                    Channel::Current => amps,
                    Channel::Amplifier => self.volts,
                    Channel::Stretch => stretch,
                };
                let code = if failed && channel == Channel::Stretch {
                    0
                } else {
                    spec.adc_code(reading)
                };
                block.add(channel, code);
            }
        }
    }

    fn commanded(&mut self, volts: f32) {
        self.volts = volts;
        if let Some((device, model)) = &mut self.plant {
            self.before = model.state().stretch;
            let stepped = model
                .set_drive(Drive::constant(device, volts))
                .and_then(|()| model.step());
            // A model that cannot go on gives no more samples (the tick then faults on them).
            if stepped.is_err() {
                self.plant = None;
            }
        }
    }
}
