//! The step on the graphics card: WGSL compute kernels through wgpu, the library Bevy draws
//! with (the `gpu` feature).
//!
//! What runs here today: symplectic and explicit Euler with gravity, external forces,
//! damping, the ground, pins and dashpots (`explicit.wgsl`), the contact pass against
//! obstacles and the ground with the particles' radius, friction and restitution
//! (`contact.wgsl`), contact between particles through a hash grid rebuilt every step
//! (`pairs.wgsl`), tearing at the end of each of the CPU's ticks (`tear.wgsl`), and XPBD in the
//! CPU's colours and order with the same contact inside its substeps (`xpbd.wgsl`), all in
//! [`GpuStep`]; in f32, and in f64 where the adapter has `SHADER_F64`. The state stays on the
//! card between steps and comes back only when asked ([`GpuStep::read_into`], or started with
//! [`GpuStep::begin_read`] and taken later, so that the caller need not wait); what a caller
//! needs of it every tick (its energy by kind, springs torn) comes back reduced on the card as a
//! [`Summary`] (`summary.wgsl`, [`GpuStep::begin_summary`]). What does not
//! run here (the other methods, XPBD to a tolerance, contact by outlines, pressure bodies,
//! muscles, plasticity) stays on the CPU, and the callers say so ([`GpuStep::unsupported`],
//! [`crate::sim::gpu`]).
//!
//! The kernels take a [`Gpu`], a wgpu device and queue: the CLI and the tests open their own,
//! an app hands over its renderer's. Nothing here names an engine type.

mod contact;
mod context;
mod draw;
mod kernel;
mod pairs;
mod readback;
mod settings;
mod step;
mod summary;
mod tear;
mod xpbd;

pub use context::{Gpu, GpuError, Precision};
pub use draw::{
    DOT_CORNERS, DrawSource, DrawStyle, DrawTarget, DrawTargets, Painter, SPRING_CORNERS,
    VERTEX_BYTES,
};
pub use settings::{ExplicitMethod, ExplicitSettings, TearSettings};
pub use step::GpuStep;
pub use summary::Summary;
