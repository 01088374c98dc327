//! The forces and the per-particle kernels that every method evaluates: one spring's force and
//! projection (`spring`), the scalar kernels (`kernels`) and their AVX forms (`wide`),
//! the spring force pass on the pool's threads (`passes`), the fused particle sweep with the
//! ground (`sweep`), the springs' stiffness blocks for the implicit methods (`stiffness`),
//! and the materials beyond the Hooke spring ([`material`]): dashpots, gas bodies, muscles,
//! plastic springs.
//!
//! It reads the packed records (`solver::packed`) and runs on the threads (`solver::threads`);
//! it knows no state, no method and no contact: the rooms above hand it arrays.

pub(crate) mod kernels;
pub mod material;
pub(crate) mod passes;
pub(crate) mod spring;
pub(crate) mod stiffness;
pub(crate) mod sweep;
pub(crate) mod wide;
