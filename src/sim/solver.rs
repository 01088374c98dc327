//! The solver as a Bevy resource: the core's packed [`State`] and method buffers, with the
//! entity each dense index stands for.
//!
//! The ECS components stay the source of truth; the crate's sync rebuilds or patches this copy
//! when entities change, and the step's systems run the core's passes on it.

use super::components::Spring;
use crate::solver::{SolveStats, State, Workspace};
use bevy::ecs::entity::{Entities, EntityIndex};
use bevy::prelude::*;
use std::ops::{Deref, DerefMut};

pub use crate::solver::{Energy, PackedSpring};

/// The packed copy of the simulation the step loop runs on (see the module docs). Read it
/// (its [`State`]'s accessors are reached through it: `solver.x()`, `solver.energy(g)`);
/// change the simulation through the components and resources.
///
/// ```
/// # use bevy::math::DVec2;
/// # use hooke::sim::Solver;
/// let loaded = hooke::scene::presets::resolve("rope").unwrap();
/// let app = hooke::running_app(&loaded).unwrap();
/// let solver = app.world().resource::<Solver>();
/// let lowest = solver.x().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
/// let energy = solver.energy(DVec2::new(0.0, -9.8)).total();
/// assert_eq!(solver.particle_count(), 16);
/// # let _ = (lowest, energy);
/// ```
#[derive(Resource, Debug, Default)]
pub struct Solver {
    /// The packed arrays.
    pub(crate) state: State,
    /// The methods' buffers and counters.
    pub(crate) work: Workspace,
    /// Particle entity of each dense index, in creation order.
    pub(crate) entities: Vec<Entity>,
    /// The index of each packed spring's entity, as of the last repack. Four bytes a spring
    /// rather than an [`Entity`]'s eight (the generation): at millions of springs every byte
    /// per spring shows in memory. [`Solver::spring_entity`] resolves and checks it.
    pub(crate) spring_entity_indices: Vec<u32>,
    /// The card's sum of its state's energy, while the steps run there and the packed state
    /// lags the card's (the card's state read on demand: [`crate::sim::gpu`]); `None` when the
    /// packed state is the latest.
    pub(crate) energy_on_card: Option<crate::solver::Energy>,
}

impl Deref for Solver {
    type Target = State;
    fn deref(&self) -> &State {
        &self.state
    }
}

impl DerefMut for Solver {
    fn deref_mut(&mut self) -> &mut State {
        &mut self.state
    }
}

impl Solver {
    /// The state's energy now: the card's own sum while the steps run there and the packed
    /// state lags the card's (its state read on demand), else the packed state's, summed on
    /// `threads` ([`State::energy_on`]).
    pub fn energy_now(
        &self,
        gravity: bevy::math::DVec2,
        threads: &crate::solver::Threads,
    ) -> crate::solver::Energy {
        self.energy_on_card
            .unwrap_or_else(|| self.state.energy_on(gravity, threads))
    }

    /// Particle entity of each dense index, in creation order.
    pub fn entities(&self) -> &[Entity] {
        &self.entities
    }

    /// The entity of packed spring `i`, if it is still the spring packed there: the solver
    /// keeps only its entity's index, so the entity now at that index is looked up in
    /// `entities` and its [`Spring`] (through `spring`) must join the packed ends. A spring
    /// despawned since the last repack, whose index a new entity took, gives `None`.
    pub fn spring_entity(
        &self,
        i: usize,
        entities: &Entities,
        spring: impl Fn(Entity) -> Option<Spring>,
    ) -> Option<Entity> {
        let index = EntityIndex::from_raw_u32(*self.spring_entity_indices.get(i)?)?;
        let e = entities.resolve_from_index(index);
        let (s, packed) = (spring(e)?, self.state.springs[i]);
        let (a, b) = (
            self.entities[packed.a as usize],
            self.entities[packed.b as usize],
        );
        (s.a == a && s.b == b).then_some(e)
    }

    /// [`Solver::spring_entity`] in a world (for headless use and tests).
    pub fn spring_entity_in(&self, world: &World, i: usize) -> Option<Entity> {
        self.spring_entity(i, world.entities(), |e| world.get::<Spring>(e).copied())
    }

    /// The packed state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// Mean conjugate-gradient iterations per implicit Euler step so far, if any were taken.
    pub fn cg_iterations_per_step(&self) -> Option<f64> {
        self.work.scratch.cg_iterations_per_step()
    }

    /// What the iterative methods did so far: iterations per step, factorisations and their
    /// time, colours.
    pub fn solve_stats(&self) -> SolveStats {
        self.work.solve_stats()
    }

    /// The packed index of spring entity `e` between dense particles `a` and `b`: a binary
    /// search of the springs, which are sorted by their ends.
    pub(crate) fn find_spring(&self, a: u32, b: u32, e: Entity) -> Option<usize> {
        let springs = &self.state.springs;
        let start = springs.partition_point(|s| (s.a, s.b) < (a, b));
        (start..springs.len())
            .take_while(|&i| (springs[i].a, springs[i].b) == (a, b))
            .find(|&i| self.spring_entity_indices[i] == e.index_u32())
    }
}
