//! The engines: the full plant (model.md §§4–8 and its extras: networks, amplifier, leakage,
//! the true §6 checks; [`plant`]), the simulated bench the board's outputs and inputs are wired
//! to ([`bench`]: DAC, enable line, sensors, their noise), the closed loop running the core's
//! board against it ([`closed_loop`], the core's board as [`core_board`]), or the firmware's binary under QEMU in its place
//! ([`firmware`]), the open-loop runs the core's integrators are measured by ([`open_loop`]:
//! the core's fixed-step methods and the references, under the safety monitor), the solvers
//! beneath them ([`solver`]: DOP853, Radau, BDF; [`erk`] and [`lift`]), and the events
//! located between their samples ([`events`]: turns of the stretch, first failures).

pub mod bench;
pub mod closed_loop;
pub mod core_board;
pub mod erk;
pub mod events;
pub mod firmware;
pub mod lift;
pub mod loop_board;
pub mod open_loop;
pub mod plant;
pub mod solver;
