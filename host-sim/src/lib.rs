//! host-sim's library: the std side of de-resonator (device files, the reference simulator,
//! studies and their reports), used by the `host-sim` binary and its benchmarks.

pub mod device_file;
pub mod lut;
pub mod plot;
pub mod precision;
pub mod report;
pub mod simulate;
pub mod stress;
pub mod sweep;
pub mod work;
