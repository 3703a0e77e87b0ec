//! The ways the resonator fails (model.md §6): a leaf every other piece of the model names.

use core::fmt;

/// A way the resonator fails (model.md §6), in the order the checks are listed there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FailureMode {
    /// §6.1: ω² ≤ 0, the device loses stability.
    DeviceInstability,
    /// §6.2: electromechanical instability of A (Hessian not positive definite).
    Emi,
    /// §6.3: membrane B slack in direction 1.
    LossOfTension1,
    /// §6.4: membrane A slack in direction 2.
    LossOfTension2a,
    /// §6.4: membrane B slack in direction 2.
    LossOfTension2b,
    /// §6.5: the field in A reaches the breakdown field.
    Breakdown,
    /// §6.6: I1 reaches Jlim in A or B.
    StretchLimit,
}

impl FailureMode {
    /// All modes, in the order of model.md §6 (and of [`Margins::values`]).
    pub const ALL: [FailureMode; 7] = [
        FailureMode::DeviceInstability,
        FailureMode::Emi,
        FailureMode::LossOfTension1,
        FailureMode::LossOfTension2a,
        FailureMode::LossOfTension2b,
        FailureMode::Breakdown,
        FailureMode::StretchLimit,
    ];

    /// The stable machine name (`emi`, `loss_of_tension_1`, ...), as in JSON output.
    pub fn name(self) -> &'static str {
        match self {
            FailureMode::DeviceInstability => "device_instability",
            FailureMode::Emi => "emi",
            FailureMode::LossOfTension1 => "loss_of_tension_1",
            FailureMode::LossOfTension2a => "loss_of_tension_2a",
            FailureMode::LossOfTension2b => "loss_of_tension_2b",
            FailureMode::Breakdown => "breakdown",
            FailureMode::StretchLimit => "stretch_limit",
        }
    }

    /// What the mode means, for people.
    pub fn description(self) -> &'static str {
        match self {
            FailureMode::DeviceInstability => {
                "device instability (natural frequency falls to zero)"
            }
            FailureMode::Emi => "electromechanical instability of the active membrane",
            FailureMode::LossOfTension1 => {
                "loss of tension in direction 1 (passive membrane slack)"
            }
            FailureMode::LossOfTension2a => "loss of tension in direction 2 (active membrane)",
            FailureMode::LossOfTension2b => "loss of tension in direction 2 (passive membrane)",
            FailureMode::Breakdown => "electrical breakdown of the active membrane",
            FailureMode::StretchLimit => "stretch limit (I1 reaches Jlim)",
        }
    }
}

impl fmt::Display for FailureMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
