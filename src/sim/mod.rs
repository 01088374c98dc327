//! The simulation as a Bevy plugin: the data model (components), the parameters and status
//! (resources), the schedule (public system sets), and the read-only packed [`Solver`].
//!
//! The solver's machinery (kernels, the AVX pass, the stiffness blocks, the thread splits, the
//! integrators' scratch buffers, projective dynamics' factor, XPBD's colouring, the ECS sync) is
//! private to the crate: it holds invariants
//! (array lengths, index order, thread-part boundaries) that only the sync maintains, and it
//! changes from release to release. Users change the simulation through components and
//! resources, and read it through [`Solver`]'s accessors.

pub mod components;
pub mod grid;
pub mod inputs;
pub(crate) mod integrators;
pub(crate) mod kernels;
pub(crate) mod parallel;
pub mod params;
pub mod profile;
pub(crate) mod projective;
pub mod schedule;
pub mod solver;
pub mod stability;
pub(crate) mod stiffness;
pub(crate) mod sync;
pub mod tear;
pub mod watch;
pub(crate) mod wide;
pub(crate) mod xpbd;

pub use components::*;
pub use integrators::CgSettings;
pub use parallel::{PARALLEL_MIN_SPRINGS, SolverThreads};
pub use params::*;
pub use profile::PassTimes;
pub use schedule::{
    ParticleSweep, PhysicsStep, PhysicsSystems, SimPlugin, StepBudget, StepSystems, TickPlan,
    advance, pack,
};
#[allow(deprecated)]
pub use schedule::{PhysicsSet, StepSet};
pub use solver::{Energy, PackedSpring, SolveStats, Solver};
pub use stability::StabilityEstimate;
