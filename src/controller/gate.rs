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

#[cfg(test)]
mod tests {
    use super::*;

    /// Below 0 V, above the cap, or not a number: the gate's own refusal, whatever the
    /// amplifier could give; in between, the amplifier's code.
    #[test]
    fn refuses_outside_zero_to_the_cap() {
        let amplifier = Amplifier::new(2.5, 4000.0).unwrap_or_else(|_| unreachable!());
        for volts in [-1.0, -0.0001, 100.5, f32::NAN, f32::INFINITY] {
            let refused = gate(&amplifier, volts, 100.0);
            assert!(
                matches!(refused, Err(Fault::Gate { max_volts, .. }) if max_volts == 100.0),
                "{volts}: {refused:?}"
            );
        }
        assert_eq!(gate(&amplifier, 0.0, 100.0), Ok(DacCode(0)));
        assert_eq!(
            gate(&amplifier, 100.0, 100.0),
            amplifier.code(100.0).map_err(Fault::Amplifier)
        );
    }
}
