//! Shared by the core's integration tests: the oracle (an independent restatement of the
//! model, `oracle`) apart from the fixtures built on the core (`fixtures`).
#![allow(dead_code, unused_imports)]

pub mod fixtures;
pub mod oracle;

pub use fixtures::*;
pub use oracle::*;
