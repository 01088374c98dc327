//! Contact: the geometry of obstacles, their distance and a swept test against tunnelling,
//! and one particle's response with friction and restitution ([`obstacle`]); the contact pass
//! that the step runs after the position update ([`collide`]), or only its velocities after a
//! solve that kept contact itself ([`settle`]); contact between particles, with their neighbour
//! lists ([`pairs`]); contact inside the large-step methods' solves (`inside`), the contact
//! forces their global solves learn and the step each body takes along them (`support`), and
//! where VBD's descent starts a body landing on a surface (`landing`) and how it slides a body
//! along one as a whole (`slide`); and the impulses the
//! obstacles take back ([`reaction`]), or the bodies a solve moves among its unknowns
//! (`solved`).
//!
//! It reads the state (`solver::state`), the sweep's motion (`solver::forces`) and the threads;
//! the methods above call it (XPBD pushes pairs apart inside its substeps) and the step runs
//! its pass.

pub(crate) mod groups;
pub(crate) mod inside;
pub(crate) mod landing;
pub mod obstacle;
pub mod outline;
pub mod pairs;
mod pass;
pub mod reaction;
pub(crate) mod slide;
pub(crate) mod solved;
pub(crate) mod support;

pub(crate) use pass::moves_first;
pub(crate) use pass::reaches;
pub use pass::{ContactSettings, Surroundings, collide, moves_with_drift, settle};
pub use reaction::{Inertia, Reaction, Reactions};
