//! The engines: the full plant (model.md §§4–8 and its extras: networks, amplifier, leakage,
//! the true §6 checks; [`plant`]), the closed loop running the core's board and controller
//! against it through a simulated DAC and enable line ([`hil`]), or the firmware's binary under
//! QEMU in its place ([`firmware`]), and the open-loop reference
//! solvers the core's integrators are measured against ([`simulate`]: DOP853, Radau, BDF), and the
//! events located between their samples ([`events`]: turns of the stretch, first failures).

pub mod erk;
pub mod events;
pub mod firmware;
pub mod hil;
pub mod lift;
pub mod plant;
pub mod simulate;
