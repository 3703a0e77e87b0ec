//! host-sim's library: the std side of de-resonator, used by the `host-sim` binary and its
//! benchmarks. The [`engine`]s (the plant simulator, the closed loop with the core's board,
//! the reference solvers) apart from the [`study`]s built on them and the commands with their
//! typed reports ([`cmd`]); the files a user writes ([`scene`], [`device_file`],
//! [`settings_file`]), what is written for people ([`plot`], [`text`], [`progress`]), and the board's telemetry stream received ([`telemetry`]).

// Checks are written `!(x > 0)` on purpose: NaN must fail them (as in the core).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cmd;
pub mod command_port;
pub mod dash;
pub mod device_file;
pub mod engine;
pub mod lut;
pub mod plot;
pub mod progress;
pub mod scene;
pub mod settings_file;
pub mod study;
pub mod telemetry;
pub mod text;
