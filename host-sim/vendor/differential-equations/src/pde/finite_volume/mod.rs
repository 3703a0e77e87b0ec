//! Finite Volume backend for conservation laws.
//!
//! This module provides a finite-volume spatial discretization with reconstruction, numerical fluxes, and limiters.

mod finite_volume;
mod flux;
mod limiter;
mod reconstruction;

pub use finite_volume::{FiniteVolume, FiniteVolumeSemiDiscrete};
pub use flux::NumericalFlux;
pub use limiter::Limiter;
pub use reconstruction::Reconstruction;
