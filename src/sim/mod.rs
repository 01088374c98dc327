//! The simulation: data model, parameters, packed solver, kernels and schedule.

pub mod components;
pub mod grid;
pub mod inputs;
pub mod integrators;
pub mod kernels;
pub mod parallel;
pub mod params;
pub mod profile;
pub mod schedule;
pub mod solver;
pub mod stability;
pub mod stiffness;
pub mod sync;
pub mod tear;
pub mod watch;
pub mod wide;

pub use components::*;
pub use integrators::CgSettings;
pub use parallel::SolverThreads;
pub use params::*;
pub use profile::PassTimes;
#[allow(deprecated)]
pub use schedule::{PhysicsSet, StepSet};
pub use schedule::{
    PhysicsStep, PhysicsSystems, SimPlugin, StepBudget, StepSystems, TickPlan, advance, pack,
};
pub use solver::{Energy, PackedSpring, Solver};
pub use stability::StabilityEstimate;
