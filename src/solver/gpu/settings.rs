//! What the card's step is asked to do: the method, the step's forces, contact and tearing,
//! in the core's words (the ECS's `SimParams` translated by [`crate::sim::gpu`]). Every pass
//! writes its own share of them to the card.

use crate::solver::contact::ContactSettings;
use glam::DVec2;

/// Which method the card runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExplicitMethod {
    /// Move with the velocity after the kick (and damping and ground).
    SymplecticEuler,
    /// Move with the velocity from before the kick.
    ExplicitEuler,
    /// XPBD with these substeps a step and Gauss-Seidel sweeps a substep (`xpbd.wgsl`).
    Xpbd {
        /// Substeps a step.
        substeps: u32,
        /// Sweeps a substep.
        sweeps: u32,
    },
}

/// The step's settings: what `SimParams` says, in the core's words.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitSettings {
    /// The method.
    pub method: ExplicitMethod,
    /// Time step, s.
    pub dt: f64,
    /// Gravity, m/s².
    pub gravity: DVec2,
    /// Damping rate μ, 1/s (v *= exp(−μ dt) a step).
    pub damping: f64,
    /// The ground's height, when there is one.
    pub ground: Option<f64>,
    /// The contact settings: with them the ground is the contact pass's (at the particles'
    /// radius, with friction and restitution), not the step's clamp.
    pub contact: Option<ContactSettings>,
    /// Tearing, when on.
    pub tear: Option<TearSettings>,
}

/// When springs tear: as the CPU's tick does ([`crate::sim::tear`]), a spring stretched past
/// (1 + strain) × rest breaks at the end of every `every` steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TearSettings {
    /// The strain past which a spring breaks.
    pub strain: f64,
    /// Steps between the checks: the CPU's steps a tick.
    pub every: u32,
}
