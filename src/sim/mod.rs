//! The simulation as a Bevy plugin, around the solver core ([`crate::solver`]): the data model
//! (components), the parameters and status (resources), the schedule (public system sets, in
//! [`schedule`]: the one place that says when each pass runs), the sync between the entities
//! and the packed state, and the read-only [`Solver`] resource.
//!
//! The sync is private to the crate: it keeps the invariants (array lengths, index order) the
//! core's passes rely on. Users change the simulation through components and resources, and
//! read it through [`Solver`]'s accessors.

mod advance;
#[cfg(feature = "avian")]
pub mod avian;
mod budget;
pub mod components;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod grid;
pub mod inputs;
pub mod obstacles;
pub mod params;
pub mod profile;
pub mod pull;
pub mod schedule;
mod sets;
pub mod solver;
pub mod stability;
pub(crate) mod sync;
pub mod tear;
pub mod watch;

pub use crate::solver::PARALLEL_MIN_SPRINGS;
pub use crate::solver::SolveStats;
pub use components::*;
pub use obstacles::{Obstacle, ObstaclePose, ObstacleVelocity, Obstacles};
pub use params::*;
pub use profile::PassTimes;
pub use pull::Attraction;
pub use schedule::{
    ParticleSweep, PhysicsStep, PhysicsSystems, SimPlugin, StepBudget, StepSystems, advance, check,
    pack, steps_per_tick,
};
#[allow(deprecated)]
pub use schedule::{PhysicsSet, StepSet};
pub use solver::{Energy, PackedSpring, Solver};
pub use stability::{Stability, StabilityEstimate};
