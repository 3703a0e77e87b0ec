//! What the controller measures of the plant, each estimator pure and tested on its own: the
//! natural frequency from a ring's timing and μ from it ([`ring`], the trim's), the resonance
//! from a lock-in on the stretch at the drive's frequency ([`lockin`], tracking's), the
//! stretch from the membrane's capacitance under a square probe ([`capacitance`], the
//! probe's). The controller's halves that run them in the tick are `controller::trim`,
//! `controller::tracking` and `controller::sensing`.

pub mod capacitance;
pub mod lockin;
pub mod ring;
