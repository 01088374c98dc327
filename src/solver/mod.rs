//! The solver core: the packed state, the step's kernels and threads, and the integrators.
//!
//! It knows nothing of the engine: plain arrays of glam's `DVec2` and `f64`, rayon threads,
//! faer's Cholesky. The Bevy layer ([`crate::sim`]) owns the entities, packs them into a
//! [`State`] and runs the step's passes ([`step`], where the step's semantics are written
//! down pass by pass) as systems in its public sets, as rapier's Bevy adapter runs rapier.
//!
//! * [`state`]: the packed arrays ([`State`], [`PackedSpring`]) and what is read from them
//!   (energy, finiteness).
//! * [`method`]: the integrators and their iteration counts.
//! * [`material`]: dashpots, gas bodies, muscles and plastic springs, and where each enters
//!   the methods.
//! * [`obstacle`]: the geometry of contact: obstacle shapes, their distance and a swept test
//!   against tunnelling, and one particle's response (friction, restitution).
//! * [`contact`]: the contact pass that the step runs after the position update.
//! * [`step`]: the passes of one step, and the methods' buffers ([`Workspace`]).
//! * [`stability`]: how close a scene is to its integrator's limit.
//! * The machinery, private to the crate: the scalar and AVX kernels, the thread splits and
//!   teams, the stiffness blocks, the integrators' updates, projective dynamics' factor and
//!   XPBD's colouring. They hold invariants (array lengths, index order, thread-part
//!   boundaries) that only the packing maintains.

pub(crate) mod bdf2;
pub(crate) mod cholesky;
pub mod contact;
pub(crate) mod crew;
pub(crate) mod etree;
pub(crate) mod integrators;
pub(crate) mod kernels;
pub mod material;
pub mod method;
pub mod obstacle;
pub(crate) mod ordering;
pub(crate) mod pages;
pub mod pairs;
pub(crate) mod parallel;
pub(crate) mod projective;
pub(crate) mod spring;
pub mod stability;
pub mod state;
pub mod step;
pub(crate) mod stiffness;
pub(crate) mod supernode;
pub(crate) mod sweep;
pub(crate) mod team;
pub(crate) mod vbd;
pub(crate) mod wide;
pub(crate) mod xpbd;

pub use contact::{ContactSettings, Surroundings};
pub use integrators::CgSettings;
pub use material::{GasBody, Materials, PackedMuscle, PackedPlastic};
pub use method::{Integrator, Iterations};
pub use obstacle::{Placed, Pose, Shape};
pub use pairs::{PairReport, Pairs};
pub use parallel::{MAX_THREADS, PARALLEL_MIN_SPRINGS, Threads};
pub use projective::FactorOrder;
pub use stability::StabilityEstimate;
pub use state::{Energy, PackedSpring, State};
pub use step::{Contacts, Method, SolveStats, Workspace};
pub use sweep::{Contact, Motion, Sweep};

/// Each vector's two coordinates as bits, for the tests that ask two ways of computing the same
/// thing for the same bits.
#[cfg(test)]
pub(crate) fn bits(v: &[glam::DVec2]) -> Vec<(u64, u64)> {
    v.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect()
}
