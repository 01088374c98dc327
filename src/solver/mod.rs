//! The solver core: the packed state, the step's passes, the methods, and what they run on.
//!
//! It knows nothing of the engine: plain arrays of glam's `DVec2` and `f64`, rayon threads,
//! faer's Cholesky. The Bevy layer ([`crate::sim`]) owns the entities, packs them into a
//! [`State`] and runs the step's passes ([`step`], where the step's semantics are written
//! down pass by pass) as systems in its public sets, as rapier's Bevy adapter runs rapier.
//!
//! The core is built in floors, each room importing only the rooms below it:
//!
//! * the top: [`step`] (the passes of one step, and the methods' buffers, [`Workspace`]),
//!   [`stability`] (how close a scene is to its method's limit), [`state`] (the packed
//!   arrays, [`State`], and what is read from them: energy, finiteness) and [`method`] (the
//!   integrators' names and iteration counts);
//! * `methods/`: one file a method's solve (the explicit multi-stage ones, implicit Euler
//!   with its conjugate gradient, projective dynamics, XPBD, VBD, BDF2);
//! * [`contact`]: obstacles, the contact pass, particle pairs;
//! * `linear/`: projective dynamics' sparse Cholesky factor, its supernodes, its elimination
//!   tree and its fill-reducing order;
//! * [`forces`]: one spring, the scalar and AVX kernels, the threaded force pass, the particle
//!   sweep, the stiffness blocks, and the materials ([`forces::material`]);
//! * `gpu/` (the `gpu` feature): the explicit step as WGSL compute kernels on wgpu, beside the
//!   floors: it reads the packed state and names no other room's machinery;
//! * `threads/`: the pool, the pair scatter, the team and the crew, huge pages;
//! * at the ground, the packed spring record ([`PackedSpring`]) that every floor reads.
//!
//! The machinery is private to the crate: it holds invariants (array lengths, index order,
//! thread-part boundaries) that only the packing maintains.

pub mod contact;
#[cfg(test)]
pub(crate) mod fixtures;
pub mod forces;
#[cfg(feature = "gpu")]
pub mod gpu;
pub(crate) mod linear;
pub mod method;
pub(crate) mod methods;
pub(crate) mod packed;
pub mod stability;
pub mod state;
pub mod step;
pub(crate) mod threads;

pub use contact::obstacle::{Placed, Polygon, Pose, Shape};
pub use contact::pairs::{PairReport, Pairs};
pub use contact::{ContactSettings, Inertia, Reaction, Reactions, Surroundings};
pub use forces::material::{GasBody, Materials, PackedMuscle, PackedPlastic};
pub use forces::sweep::{Contact, Motion, Sweep};
pub use method::{Integrator, Iterations};
pub use methods::implicit_euler::CgSettings;
pub use methods::projective::FactorOrder;
pub use stability::StabilityEstimate;
pub use state::{Energy, PackedSpring, State};
pub use step::{Contacts, Method, SolveStats, Workspace};
pub use threads::{MAX_THREADS, PARALLEL_MIN_SPRINGS, Threads};

/// Moved to [`forces::material`].
#[deprecated(since = "0.1.0", note = "moved to `hooke::solver::forces::material`")]
pub mod material {
    pub use super::forces::material::*;
}

/// Moved to [`contact::obstacle`].
#[deprecated(since = "0.1.0", note = "moved to `hooke::solver::contact::obstacle`")]
pub mod obstacle {
    pub use super::contact::obstacle::*;
}

/// Moved to [`contact::pairs`].
#[deprecated(since = "0.1.0", note = "moved to `hooke::solver::contact::pairs`")]
pub mod pairs {
    pub use super::contact::pairs::*;
}
