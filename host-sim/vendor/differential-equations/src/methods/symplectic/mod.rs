//! Symplectic Integrators for Hamiltonian Systems
//!
//! Symplectic integrators are numerical integration schemes designed specifically
//! for the solution of Hamilton's equations, which arise in classical mechanics
//! and orbital mechanics.
//!
//! The fundamental property of these integrators is that they conserve the symplectic
//! 2-form, which geometrically means they preserve phase space volume exactly.
//! Because of this property, symplectic integrators exhibit near-perfect long-term
//! energy conservation, making them vastly superior to standard explicit Runge-Kutta
//! methods for simulating conservative systems over many cycles.

mod ruth_forest;
mod velocity_verlet;

use std::marker::PhantomData;

use crate::{
    status::Status,
    traits::{Real, State},
};

pub struct SymplecticIntegrator<E, F, T: Real, Y: State<T>, const S: usize> {
    pub h: T,
    pub t: T,
    pub y: Y,
    pub y_prev: Y,

    // Constants from partitioned method
    pub c: [T; S], // Position update coefficients
    pub d: [T; S], // Momentum update coefficients

    // Settings
    pub h_max: T,
    pub h_min: T,
    pub max_steps: usize,

    // Iteration tracking
    pub steps: usize,
    pub status: Status<T, Y>,

    // Method info
    pub order: usize,
    pub stages: usize,

    // Family classification
    family: PhantomData<F>,

    // Equation type
    equation: PhantomData<E>,
}

impl<E, F, T: Real, Y: State<T>, const S: usize> Default for SymplecticIntegrator<E, F, T, Y, S> {
    fn default() -> Self {
        Self {
            h: T::zero(),
            t: T::zero(),
            y: Y::zeros(),
            y_prev: Y::zeros(),
            c: [T::zero(); S],
            d: [T::zero(); S],
            h_max: T::infinity(),
            h_min: T::zero(),
            max_steps: 10_000,
            steps: 0,
            status: Status::Uninitialized,
            order: 0,
            stages: S,
            family: PhantomData,
            equation: PhantomData,
        }
    }
}

impl<E, F, T: Real, Y: State<T>, const S: usize> SymplecticIntegrator<E, F, T, Y, S> {
    /// Set the maximum number of steps allowed
    pub fn max_steps(mut self, max_steps: usize) -> Self {
        self.max_steps = max_steps;
        self
    }
}
