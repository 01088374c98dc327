//! The buffers that the multi-stage methods (velocity Verlet, RK4) and implicit Euler reuse
//! from step to step, and implicit Euler's counters. One struct for both: implicit Euler's
//! Newton iterates use the stage buffers, so a scene never holds two sets.

use crate::solver::contact::slide::Slides;
use crate::solver::contact::support::Support;
use crate::solver::forces::material::GasJacobian;
use crate::solver::forces::stiffness::{Block, Sym2};
use crate::solver::threads::SpringBuffers;
use glam::DVec2;

/// Buffers the multi-stage methods reuse from step to step.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    pub(super) x: Vec<DVec2>,
    pub(super) f: Vec<DVec2>,
    pub(super) sum_u: Vec<DVec2>,
    pub(super) sum_a: Vec<DVec2>,
    pub(super) stage_v: Vec<DVec2>,
    /// Implicit Euler: the pair push's scratch, when contact runs inside the solve.
    pub(super) contact: Vec<DVec2>,
    /// Implicit Euler: the contact forces, carried from step to step.
    pub(super) support: Support,
    /// Implicit Euler: the Newton matrix's answer to the contact forces' last change, and the
    /// solve's Δv kept aside while it is found (the line search, [`Support::line_search`]).
    pub(super) answer: Vec<DVec2>,
    pub(super) kept_dv: Vec<DVec2>,
    pub(super) cg: Cg,
    /// The pair passes' thread split (the force pass's and every stage's).
    pub(crate) pairs: SpringBuffers,
    /// Implicit Euler: the gas bodies' share of the Newton matrix (empty without them).
    pub(super) gas: GasJacobian,
    /// Implicit Euler: the bodies (groups joined by springs) that the friction of the ground and
    /// of the obstacles slows as a whole ([`super::implicit_euler`]), with each particle's
    /// contact at the step's end.
    pub(super) groups: Slides,
    /// Implicit Euler's Newton steps so far, and its time steps.
    pub(super) newton_steps: u64,
    pub(super) newton_solves: u64,
}

impl Scratch {
    /// Mean conjugate-gradient iterations per implicit Euler step so far, if any were taken.
    pub fn cg_iterations_per_step(&self) -> Option<f64> {
        (self.newton_solves > 0).then(|| self.cg.iterations as f64 / self.newton_solves as f64)
    }

    /// Mean Newton steps per implicit Euler step so far, if any were taken.
    pub fn newton_iterations_per_step(&self) -> Option<f64> {
        (self.newton_solves > 0).then(|| self.newton_steps as f64 / self.newton_solves as f64)
    }

    /// New buffers for a repacked state, keeping the counters.
    pub(crate) fn repacked(&self) -> Scratch {
        Scratch {
            cg: Cg {
                iterations: self.cg.iterations,
                unconverged: self.cg.unconverged,
                last_iterations: self.cg.last_iterations,
                ..Cg::default()
            },
            newton_steps: self.newton_steps,
            newton_solves: self.newton_solves,
            ..Scratch::default()
        }
    }

    pub(super) fn fit(&mut self, n: usize) {
        for b in [
            &mut self.x,
            &mut self.f,
            &mut self.sum_u,
            &mut self.sum_a,
            &mut self.stage_v,
        ] {
            b.resize(n, DVec2::ZERO);
        }
    }
}

/// Conjugate-gradient buffers and counters.
#[derive(Debug, Default, Clone)]
pub struct Cg {
    /// The previous step's Δv, the warm start of the next solve.
    pub(super) dv: Vec<DVec2>,
    pub(super) r: Vec<DVec2>,
    pub(super) p: Vec<DVec2>,
    pub(super) ap: Vec<DVec2>,
    pub(super) z: Vec<DVec2>,
    /// Per particle: the inverse of its diagonal block of A (the preconditioner).
    pub(super) diag: Vec<Sym2>,
    /// Per particle: which components of Δv the solve may change ([`super::implicit_euler`]'s
    /// row filter), and the filter of the pins alone.
    pub(super) filter: Vec<DVec2>,
    pub(super) pins: Vec<DVec2>,
    /// The right-hand side, kept while the ground's solves overwrite `z`.
    pub(super) b: Vec<DVec2>,
    /// Per spring: its block of the stiffness matrix at the start of the step.
    pub(super) blocks: Vec<Block>,
    /// The threaded K u's split of the blocks.
    pub(super) buffers: SpringBuffers,
    pub iterations: u64,
    pub unconverged: u64,
    pub last_iterations: u32,
}

impl Cg {
    pub(super) fn fit(&mut self, n: usize, springs: usize) {
        for b in [
            &mut self.dv,
            &mut self.r,
            &mut self.p,
            &mut self.ap,
            &mut self.z,
        ] {
            b.resize(n, DVec2::ZERO);
        }
        self.diag.resize(n, Sym2::default());
        self.blocks.reserve(springs);
    }
}
