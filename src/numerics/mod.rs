//! The numerics every layer above stands on: the float trait ([`real`]), bracketed roots and
//! extrema ([`roots`]), and numbers written for people without the core library's float
//! formatting ([`decimal`]). Pure numbers: nothing here knows the device.

pub mod decimal;
pub mod gradient;
pub mod interval;
pub mod real;
pub mod roots;
