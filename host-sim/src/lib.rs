//! host-sim's library: the std side of de-resonator (device files, the reference simulator,
//! the plant, studies, and the commands with their typed reports in `cmd`), used by the
//! `host-sim` binary and its benchmarks.

// Checks are written `!(x > 0)` on purpose: NaN must fail them (as in the core).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cmd;
pub mod device_file;
pub mod hil;
pub mod lut;
pub mod plant;
pub mod plot;
pub mod precision;
pub mod scene;
pub mod settings_file;
pub mod simulate;
pub mod stress;
pub mod sweep;
pub mod text;
pub mod work;
