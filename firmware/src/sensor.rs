//! What the tick measures: the stretch (a displacement sensor on the bars) and the amplifier's
//! monitored output, behind one trait so that the tick is the same with or without them.
//! QEMU has no ADC (its DR is a fake ramp): its builds read none, or (`model-sensor`, for
//! testing the trim under QEMU) the stretch of the flashed device's own model, stepped at
//! each tick with the voltage commanded.

use de_resonator::{Device, DeviceParams, Drive, Inputs, Integrator, Method, State};

/// The tick's measurements: read once a tick, before it; told the voltage after it.
pub trait Sensor {
    /// This tick's samples (`Inputs::NONE` where there is no sensor).
    fn sample(&mut self) -> Inputs;
    /// The voltage the tick commanded (a model plant steps with it).
    fn commanded(&mut self, volts: f32) {
        let _ = volts;
    }
}

/// A board without sensors: the controller drives open loop (no trim, no monitor of the
/// measured motion; the plan was checked in the model).
pub struct NoSensor;

impl Sensor for NoSensor {
    fn sample(&mut self) -> Inputs {
        Inputs::NONE
    }
}

/// The flashed device's model as the plant (RK4, one step a tick, substeps if needed), its
/// stretch the sample: a stand-in for a displacement sensor under QEMU. `None` until an image
/// gives a device.
pub struct ModelSensor {
    plant: Option<(Device<f32>, Integrator<f32>)>,
    /// A sensor that fails: NaN from this many samples on (a QEMU test's `sensor-fails`).
    fails_after: Option<u32>,
    samples: u32,
}

impl ModelSensor {
    /// The model of `params` at rest at the pre-stretch, stepped at `tick_hz`.
    pub fn new(params: Option<DeviceParams<f32>>, tick_hz: f32) -> Self {
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
        Self {
            plant,
            fails_after: None,
            samples: 0,
        }
    }

    /// The same sensor failing (NaN samples, for good) after `samples` samples: a runtime
    /// fault whose cause stays present, for the QEMU tests of the latch and of `clear`.
    pub fn failing_after(self, samples: Option<f32>) -> Self {
        Self {
            fails_after: samples.map(|n| n as u32),
            ..self
        }
    }
}

impl Sensor for ModelSensor {
    fn sample(&mut self) -> Inputs {
        self.samples = self.samples.saturating_add(1);
        if self.fails_after.is_some_and(|n| self.samples > n) {
            return Inputs::stretch(f32::NAN);
        }
        match &self.plant {
            Some((_, model)) => Inputs::stretch(model.state().stretch),
            None => Inputs::NONE,
        }
    }

    fn commanded(&mut self, volts: f32) {
        if let Some((device, model)) = &mut self.plant {
            let stepped = model
                .set_drive(Drive::constant(device, volts))
                .and_then(|()| model.step());
            // A model that cannot go on gives no more samples (the trim then fails: a fault).
            if stepped.is_err() {
                self.plant = None;
            }
        }
    }
}
