//! The ECS data model: particles and springs are entities.
//!
//! These components are the source of truth that users (the UI, scene loading, tests) read and
//! edit. The hot loop runs on a packed copy ([`crate::sim::Solver`]); edits made here reach it at
//! the start of the next fixed tick, and its results are written back here at the end of a tick.

use bevy::math::DVec2;
use bevy::prelude::*;

/// Marks a particle. `serial` is its creation order: the solver orders particles by it, so that
/// scene order (CSV rows, summation order) survives archetype moves such as pinning.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[require(Position, Velocity, Mass, Force, ExternalForce, SolverIndex)]
pub struct Particle {
    pub serial: u64,
}

/// Position in metres (the scene lives in the unit square by convention).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Position(pub DVec2);

/// Velocity in metres per second.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Velocity(pub DVec2);

/// Mass in kilograms; always positive and finite (scene validation guarantees it).
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Mass(pub f64);

impl Default for Mass {
    fn default() -> Self {
        Mass(1.0)
    }
}

/// The total force on the particle at the start of the last step (gravity plus springs).
/// Written back by the solver for inspection; editing it has no effect.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Force(pub DVec2);

/// A force from outside the spring network, in newtons: wind, the app's mouse attraction, a
/// user's own field. The solver adds it to gravity wherever it evaluates forces, so every
/// integrator sees it at every stage (velocity Verlet's second evaluation, RK4's four, implicit
/// Euler's right-hand side). It is held constant over a fixed tick: write it from a system in
/// `Update` or `FixedUpdate` before [`crate::sim::PhysicsSet::Prepare`]. A scene where every
/// external force is zero pays nothing for it.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ExternalForce(pub DVec2);

/// A particle moved by the user, not by forces: the integrators treat it as having infinite
/// mass (like [`Pinned`]) but it keeps the velocity written to its [`Velocity`], and moves with
/// it during the tick. The app's grab inserts it while the button is held. Adding or removing
/// it patches the solver in place (no repack).
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Kinematic;

/// A pinned particle never moves and keeps zero velocity.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Pinned;

/// A Hooke spring between two particle entities:
/// `f_a = -k (|x_a - x_b| - rest) (x_a - x_b) / |x_a - x_b|`, and `f_b = -f_a`.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
#[require(SolverIndex)]
pub struct Spring {
    pub a: Entity,
    pub b: Entity,
    /// Rest length in metres.
    pub rest: f64,
    /// Stiffness k in N/m. [`crate::sim::SimParams::stiffness_override`] replaces it while set.
    pub stiffness: f64,
    /// Creation order, for a deterministic spring order in the solver.
    pub serial: u64,
}

/// Dense index of a particle or spring in the solver's arrays (`u32::MAX` until the next sync
/// packs it). Maintained by the solver sync; read-only for everyone else.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolverIndex(pub u32);

impl Default for SolverIndex {
    fn default() -> Self {
        SolverIndex(u32::MAX)
    }
}

/// Hands out creation serials for particles and springs.
#[derive(Resource, Debug, Default)]
pub struct Serials {
    next: u64,
}

impl Serials {
    pub fn next_serial(&mut self) -> u64 {
        self.next += 1;
        self.next
    }
}
