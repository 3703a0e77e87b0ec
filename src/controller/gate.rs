//! The final check every code passes on its way to the DAC.

use super::fault::Fault;
use crate::drive::{Amplifier, DacCode};

/// The voltage is a number in [0, `max_volts`], and so is what its code gives; else
/// `Fault::Gate` (never expected: the boot checks the plan's whole range first).
pub(super) fn gate(amplifier: &Amplifier, volts: f32, max_volts: f32) -> Result<DacCode, Fault> {
    let refuse = Fault::Gate { volts, max_volts };
    if !(volts >= 0.0 && volts <= max_volts) {
        return Err(refuse);
    }
    let code = amplifier.code(volts).map_err(Fault::Amplifier)?;
    if !(amplifier.volts(code) <= max_volts) {
        return Err(refuse);
    }
    Ok(code)
}
