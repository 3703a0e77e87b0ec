//! What the tick measures: the stretch (a displacement sensor on the bars) and the amplifier's
//! monitored output, behind one trait so that the tick is the same with or without them.
//! QEMU has no ADC (its DR is a fake ramp): the QEMU build reads none.

use de_resonator::Inputs;

/// The tick's measurements, read once a tick.
pub trait Sensor {
    /// This tick's samples (`Inputs::NONE` where there is no sensor).
    fn sample(&mut self) -> Inputs;
}

/// A board without sensors: the controller drives open loop (no trim, no monitor of the
/// measured motion; the plan was checked in the model).
pub struct NoSensor;

impl Sensor for NoSensor {
    fn sample(&mut self) -> Inputs {
        Inputs::NONE
    }
}
