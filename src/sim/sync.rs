//! Keeps the packed [`Solver`] in step with the ECS components.
//!
//! * Structural changes (a particle or spring added or removed, a particle pinned or unpinned)
//!   rebuild the packed arrays: particles in creation order, springs by their ends' indices,
//!   so results do not depend on archetype layout.
//! * Value edits (a dragged position, a changed mass, spring or external force, a particle
//!   made [`Kinematic`] or released) are patched in place.
//! * After the steps, positions, velocities and forces are written back without flagging them
//!   as changed, so the next sync sees only what users changed.

use super::components::*;
use super::params::SimParams;
use super::solver::{PackedSpring, Solver};
use bevy::ecs::entity::EntityHashMap;
use bevy::ecs::system::SystemParam;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Signals that the set of particles or springs changed since the last sync.
#[derive(SystemParam)]
pub struct StructureChanges<'w, 's> {
    added_particles: Query<'w, 's, (), Added<Particle>>,
    added_springs: Query<'w, 's, (), Added<Spring>>,
    added_pins: Query<'w, 's, (), Added<Pinned>>,
    removed_particles: RemovedComponents<'w, 's, Particle>,
    removed_springs: RemovedComponents<'w, 's, Spring>,
    removed_pins: RemovedComponents<'w, 's, Pinned>,
}

impl StructureChanges<'_, '_> {
    fn any(&mut self) -> bool {
        // Drain every reader so that old removals are not seen again.
        let removed = self.removed_particles.read().count()
            + self.removed_springs.read().count()
            + self.removed_pins.read().count();
        removed > 0
            || !self.added_particles.is_empty()
            || !self.added_springs.is_empty()
            || !self.added_pins.is_empty()
    }
}

type ParticleData<'a> = (
    Entity,
    &'a CreationOrder,
    Ref<'a, Position>,
    Ref<'a, Velocity>,
    Ref<'a, Mass>,
    Ref<'a, ExternalForce>,
    Has<Pinned>,
    Has<Kinematic>,
    &'a mut SolverIndex,
);
type Particles<'w, 's> = Query<'w, 's, ParticleData<'static>, (With<Particle>, Without<Spring>)>;
type Springs<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        Ref<'static, Spring>,
        &'static CreationOrder,
        &'static mut SolverIndex,
    ),
    Without<Particle>,
>;

/// A particle's value edits: what the sync patches in place.
type ParticleEdited = Or<(
    Changed<Position>,
    Changed<Velocity>,
    Changed<Mass>,
    Changed<ExternalForce>,
    Added<Kinematic>,
)>;

/// What changed since the last sync, found by filtered scans (they read change ticks, not
/// components, for the entities that did not change): a tick of a big scene with nothing
/// edited costs about one pass over the ticks.
#[derive(SystemParam)]
pub struct Edits<'w, 's> {
    particles: Query<'w, 's, Entity, (With<Particle>, ParticleEdited)>,
    released: RemovedComponents<'w, 's, Kinematic>,
    held: Query<'w, 's, (), (With<Particle>, With<Kinematic>)>,
    springs: Query<'w, 's, Entity, (Changed<Spring>, Without<Particle>)>,
}

/// Brings ECS edits into the solver. Runs at the start of every fixed tick.
pub fn sync_into_solver(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    mut structure: StructureChanges,
    mut particles: Particles,
    mut springs: Springs,
    mut edits: Edits,
) {
    if structure.any() {
        edits.released.clear();
        rebuild(&mut solver, &mut particles, &mut springs);
        solver.apply_stiffness_override(params.stiffness_override);
        return;
    }
    let mut external_changed = false;
    let released: Vec<Entity> = edits.released.read().collect();
    for e in edits.particles.iter().chain(released) {
        let Ok((_, _, pos, vel, mass, external, pinned, held, index)) = particles.get(e) else {
            continue; // released and despawned since
        };
        let i = index.0 as usize;
        if i >= solver.x.len() {
            continue;
        }
        if pos.is_changed() {
            solver.x[i] = pos.0;
        }
        if vel.is_changed() {
            solver.v[i] = if pinned { DVec2::ZERO } else { vel.0 };
        }
        // Grabbing and releasing (Kinematic) changes the inverse mass without a repack.
        let w = inverse_mass(mass.0, pinned || held);
        if mass.is_changed() || solver.inv_mass[i].to_bits() != w.to_bits() {
            solver.mass[i] = mass.0;
            solver.inv_mass[i] = w;
            solver.touch();
        }
        if external.is_changed() {
            solver.external[i] = external.0;
            external_changed = true;
        }
    }
    let kinematic = edits.held.iter().count();
    // Written only when different: a paused scene's solver stays unchanged, so nothing
    // downstream (drawing, picking grids) redoes its work.
    if solver.kinematic != kinematic {
        solver.kinematic = kinematic;
    }
    if external_changed {
        let active = solver.external.iter().any(|f| *f != DVec2::ZERO);
        if solver.external_active != active {
            solver.external_active = active;
        }
    }
    let mut springs_changed = false;
    let mut endpoints_changed = false;
    for e in &edits.springs {
        let Ok((_, spring, _, index)) = springs.get(e) else {
            continue;
        };
        springs_changed = true;
        if index.0 == u32::MAX {
            // Not packed (an endpoint was missing at the last rebuild): repack.
            endpoints_changed = true;
            continue;
        }
        let endpoint = |e: Entity| particles.get(e).ok().map(|p| p.8.0);
        let si = index.0 as usize;
        let packed = &mut solver.springs[si];
        if endpoint(spring.a) != Some(packed.a) || endpoint(spring.b) != Some(packed.b) {
            endpoints_changed = true;
        }
        packed.rest = spring.rest;
        solver.own_stiffness[si] = spring.stiffness;
    }
    if endpoints_changed {
        rebuild(&mut solver, &mut particles, &mut springs);
    }
    if springs_changed || solver.applied_override != params.stiffness_override {
        solver.apply_stiffness_override(params.stiffness_override);
    }
}

/// Repacks every particle and spring. Springs whose endpoints are not both
/// particles are left out.
fn rebuild(solver: &mut Solver, particles: &mut Particles, springs: &mut Springs) {
    let mut order: Vec<(CreationOrder, Entity)> = particles.iter().map(|p| (*p.1, p.0)).collect();
    order.sort_unstable();
    let n = order.len();
    let mut index: EntityHashMap<u32> = EntityHashMap::default();
    index.reserve(n);
    let mut entities = Vec::with_capacity(n);
    for (i, &(_, e)) in order.iter().enumerate() {
        index.insert(e, i as u32);
        entities.push(e);
    }
    let (mut x, mut v, mut mass, mut inv_mass) = (
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
        vec![1.0; n],
        vec![1.0; n],
    );
    let mut external = vec![DVec2::ZERO; n];
    let mut kinematic = 0;
    for (e, _, pos, vel, m, ext, pinned, held, mut solver_index) in particles.iter_mut() {
        let i = index[&e] as usize;
        solver_index.0 = i as u32;
        x[i] = pos.0;
        v[i] = if pinned { DVec2::ZERO } else { vel.0 };
        mass[i] = m.0;
        inv_mass[i] = inverse_mass(m.0, pinned || held);
        external[i] = ext.0;
        kinematic += held as usize;
    }

    let mut packed: Vec<(CreationOrder, Entity, PackedSpring)> = springs
        .iter()
        .filter_map(|(e, s, order, _)| {
            let (a, b) = (*index.get(&s.a)?, *index.get(&s.b)?);
            let spring = PackedSpring {
                a,
                b,
                rest: s.rest,
                k: s.stiffness,
            };
            Some((*order, e, spring))
        })
        .collect();
    // Grouped by first end, then second (ties by creation): the spring pass then sums each
    // particle's run of springs in a register, and repeated second ends lie a few springs
    // apart, so no update waits on the previous one's store (see `kernels::scatter_pairs`).
    packed.sort_unstable_by_key(|p| (p.2.a, p.2.b, p.0));
    let mut spring_index: EntityHashMap<u32> = EntityHashMap::default();
    spring_index.extend(packed.iter().enumerate().map(|(i, p)| (p.1, i as u32)));
    for (e, _, _, mut solver_index) in springs.iter_mut() {
        solver_index.0 = spring_index.get(&e).copied().unwrap_or(u32::MAX);
    }

    *solver = Solver {
        entities,
        f: vec![DVec2::ZERO; n],
        external_active: external.iter().any(|f| *f != DVec2::ZERO),
        external,
        kinematic,
        drift: v.clone(),
        x,
        v,
        mass,
        inv_mass,
        spring_entities: packed.iter().map(|p| p.1).collect(),
        own_stiffness: packed.iter().map(|p| p.2.k).collect(),
        springs: packed.into_iter().map(|p| p.2).collect(),
        applied_override: None,
        non_finite: false,
        scratch: Default::default(),
        spring_buffers: Default::default(),
        // The new revision makes the large-step methods redo their precomputation; their
        // counters carry on.
        revision: solver.revision.wrapping_add(1),
        projective: std::mem::take(&mut solver.projective),
        xpbd: std::mem::take(&mut solver.xpbd),
    };
}

/// 1/m, or 0 for a particle that forces do not move (pinned, or held by the user).
fn inverse_mass(m: f64, held: bool) -> f64 {
    if held { 0.0 } else { 1.0 / m }
}

/// Writes the solver's results back into the components, without flagging them as changed.
/// After a non-finite step it does the opposite: the components still hold the end of the
/// previous tick, so the solver rolls back to that finite state, and no NaN reaches anything a
/// user sees (the status says what happened and when).
pub fn sync_from_solver(
    mut solver: ResMut<Solver>,
    mut particles: Query<(&SolverIndex, &mut Position, &mut Velocity, &mut Force), With<Particle>>,
) {
    if solver.non_finite {
        for (index, pos, vel, _) in &particles {
            let i = index.0 as usize;
            if i < solver.x.len() {
                solver.x[i] = pos.0;
                solver.v[i] = if solver.inv_mass[i] == 0.0 {
                    DVec2::ZERO
                } else {
                    vel.0
                };
            }
        }
        solver.non_finite = false;
        return;
    }
    for (index, mut pos, mut vel, mut force) in &mut particles {
        let i = index.0 as usize;
        if i < solver.x.len() {
            pos.bypass_change_detection().0 = solver.x[i];
            vel.bypass_change_detection().0 = solver.v[i];
            force.bypass_change_detection().0 = solver.f[i];
        }
    }
}
