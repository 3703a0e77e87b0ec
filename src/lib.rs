//! de-resonator: model, safe region and bias tuning of a dielectric elastomer resonator.
//!
//! `no_std`, no allocation, no panics on any input. Generic over the float type: `f32` on
//! the target, `f64` on the host. Data flows one way: [`numerics`] → the [`model`] (device
//! parameters → statics → safe region) → [`tuning`] decisions and their [`table`] → the
//! [`estimate`]s of the plant → the [`controller`] (its output in [`drive`]'s DAC codes) →
//! the [`board`] (boot, command port, output stage, watchdog). [`image`] and [`store`] are
//! the formats the board boots from and saves to. Equations cite the sections of
//! `docs/model.md` as `model.md §n`.
#![no_std]
#![forbid(unsafe_code)]
// "No panic on any input" checked by the compiler: no unwrap, expect, panic or indexing in
// the library. Crate attributes rather than `[lints]` in Cargo.toml, which would bind the
// tests too (they unwrap to fail loudly).
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// Checks are written `!(x > 0)` on purpose: NaN must fail them, and that form says so.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod acquire;
pub mod board;
pub mod bytes;
pub mod controller;
pub mod drive;
pub mod estimate;
pub mod fault_log;
#[cfg(feature = "storage")]
pub mod flash;
pub mod image;
pub mod model;
pub mod numerics;
#[cfg(feature = "storage")]
pub mod store;
pub mod table;
pub mod tuning;
pub mod wire;

pub use board::stage::{OutputStage, StageError};
pub use controller::{
    Boot, Controller, Event, EventKind, Fault, FaultStage, Inputs, Output, Phase, Plan, Refusal,
    ReplanJob, Replanned, Setting, Settings, BUS_FAULT_SAID, EVENT_VALUES, FAULT_KEYS, FAULT_SAID,
};
#[cfg(feature = "trim")]
pub use controller::{Ceiling, NextRing, TrimDone, TrimJob, TrimResult};
pub use drive::{Amplifier, CodeError, Dac8551, DacCode, DacError, PowerMode};
pub use estimate::ring::TrimError;
pub use image::{AmplifierSpec, Image, ImageError, PowerUp};
pub use model::device::{Device, DeviceParams, Field, ParamError, Problem, REFERENCE_DEVICE};
pub use model::motion::{Drive, Integrator, Method, State, StepError};
pub use model::safety::{Crossing, FailureMode, Limit, Margins, Monitor};
pub use model::statics::Equilibrium;
pub use model::swing::{AcDrive, Ramp, Resonance, Swing, SwingError};
pub use numerics::decimal::Decimal;
pub use numerics::real::Real;
pub use table::{Table, TableError};
pub use tuning::{TunableRange, TuneError, Tuner, DEFAULT_MARGIN};
