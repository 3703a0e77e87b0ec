//! The final check every code passes on its way to the DAC.

use super::fault::Fault;
use crate::drive::{Amplifier, DacCode};

/// The voltage is a number ≥ 0 the amplifier gives, and its code's voltage is at most
/// `max_volts`; else `Fault::Gate` (never expected: the boot checks the plan's whole range
/// first). The bound is on the code sent, so a ramp down from a voltage sent (the bound)
/// passes whatever its step, however small against the DAC's.
pub(super) fn gate(amplifier: &Amplifier, volts: f32, max_volts: f32) -> Result<DacCode, Fault> {
    let refuse = Fault::Gate { volts, max_volts };
    if !(volts >= 0.0) {
        return Err(refuse);
    }
    let code = amplifier.code(volts).map_err(|_| refuse)?;
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
        // Beyond the amplifier's range: the gate's refusal too.
        assert!(matches!(
            gate(&amplifier, 10_001.0, 20_000.0),
            Err(Fault::Gate { .. })
        ));
    }

    /// The bound is on the code's voltage: a request a hair above a code's voltage rounds
    /// down to that code and passes a bound at it (a slow ramp down from the voltage sent).
    #[test]
    fn the_bound_is_on_the_code_sent() {
        let amplifier = Amplifier::new(2.5, 4000.0).unwrap_or_else(|_| unreachable!());
        let sent = amplifier.volts(DacCode(30_000));
        let step = amplifier.volts(DacCode(1));
        assert_eq!(
            gate(&amplifier, sent + 0.5 * step, sent),
            Ok(DacCode(30_000))
        );
        assert!(gate(&amplifier, sent + 1.01 * step, sent).is_err());
    }
}
