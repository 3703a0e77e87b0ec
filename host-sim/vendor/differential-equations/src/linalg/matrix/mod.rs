//! Matrix types, operations, and utilities.

mod add;
mod base;
mod index;
mod linear;
mod macros;
mod mul;
mod sub;

pub use base::{Matrix, MatrixStorage};
