//! The methods' solves, a file a method: the explicit multi-stage ones ([`explicit`]: velocity
//! Verlet and RK4; the Euler methods' kick is the step's own pass), implicit Euler with its
//! conjugate gradient and the ground it holds (a folder, [`implicit_euler`]), projective
//! dynamics ([`projective`]), XPBD ([`xpbd`]), VBD ([`vbd`]) and BDF2 ([`bdf2`], projective
//! dynamics' solve on its own target). Beside them, the force evaluation they all start from
//! ([`evaluate`]) and the buffers the multi-stage methods and implicit Euler share
//! ([`scratch`]).
//!
//! A method may import every room below it (the state, contact, the linear algebra, the
//! forces, the threads) and the methods' names ([`crate::solver::method`]); only the step
//! (`solver::step`) imports the methods.

pub(crate) mod bdf2;
pub(crate) mod evaluate;
pub(crate) mod explicit;
pub(crate) mod implicit_euler;
pub(crate) mod projective;
pub(crate) mod scratch;
pub(crate) mod vbd;
pub(crate) mod xpbd;
