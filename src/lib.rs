//! de-resonator: model, safe region and bias tuning of a dielectric elastomer resonator.
//!
//! `no_std`, no allocation, no panics on any input. Generic over the float type: `f32` on
//! the target, `f64` on the host. Data flows one way: [`device`] parameters → [`statics`]
//! model → [`safety`] and [`tuning`] decisions; [`integration`] steps the dynamics. Equations cite `MODEL.md` sections.
#![no_std]
#![forbid(unsafe_code)]
// Checks are written `!(x > 0)` on purpose: NaN must fail them, and that form says so.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod device;
pub mod integration;
pub mod material;
pub mod real;
pub mod roots;
pub mod safety;
pub mod statics;
pub mod tuning;

pub use device::{Device, DeviceParams, Field, ParamError, Problem, REFERENCE_DEVICE};
pub use integration::{Drive, Integrator, Method, State, StepError};
pub use real::Real;
pub use safety::{Crossing, FailureMode, Limit, Margins, Monitor};
pub use statics::Equilibrium;
pub use tuning::{TunableRange, TuneError, Tuner, DEFAULT_MARGIN};
