//! The numerics every layer above stands on: the float trait ([`real`]), bracketed roots and
//! extrema ([`roots`]), the fixed-step integrators of the equation of motion
//! ([`integration`]), and numbers written for people without the core library's float
//! formatting ([`decimal`]).

pub mod decimal;
pub mod integration;
pub mod real;
pub mod roots;
