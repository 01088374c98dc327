//! The stability estimate of the app's scene and parameters (the core's
//! [`crate::solver::stability`], read from the [`Solver`] and [`SimParams`] resources).

use super::params::SimParams;
use super::solver::Solver;
use bevy::prelude::*;

pub use crate::solver::stability::{
    StabilityEstimate, amplitude_kept, limit, omega_bound, omega_estimate, stable_dt,
};

/// The stability picture of the world's scene and settings.
///
/// ```
/// # use hooke::sim::{SimParams, Solver, stability};
/// let app = hooke::headless_app();
/// let world = app.world();
/// let estimate = stability::estimate(world.resource::<Solver>(), world.resource::<SimParams>());
/// assert!(estimate.h_omega >= 0.0);
/// ```
pub fn estimate(solver: &Solver, params: &SimParams) -> StabilityEstimate {
    crate::solver::stability::estimate(
        solver.state(),
        params.integrator,
        params.dt,
        params.damping,
        params.iterations,
    )
}

/// The last estimate, as a resource for whoever shows it (the app's panel keeps it current).
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Deref, DerefMut)]
pub struct Stability(pub StabilityEstimate);
