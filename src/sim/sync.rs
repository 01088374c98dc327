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
use super::solver::Solver;
use crate::solver::threads::pages;
use crate::solver::{PackedSpring, State};
use bevy::ecs::system::SystemParam;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Signals that the set of particles or springs changed since the last sync. (An added spring
/// is found by the scan of changed springs in [`Edits`], which sees it as changed too: one scan
/// of the springs' change ticks a tick, not two.)
#[derive(SystemParam)]
pub struct StructureChanges<'w, 's> {
    added_particles: Query<'w, 's, (), Added<Particle>>,
    added_pins: Query<'w, 's, (), Added<Pinned>>,
    removed_particles: RemovedComponents<'w, 's, Particle>,
    removed_springs: RemovedComponents<'w, 's, Spring>,
    removed_pins: RemovedComponents<'w, 's, Pinned>,
    materials: MaterialChanges<'w, 's>,
}

/// Materials added, changed or removed: they repack (they are rare edits, and their packed
/// lists follow the springs' order).
#[derive(SystemParam)]
pub struct MaterialChanges<'w, 's> {
    changed: Query<'w, 's, (), crate::sim::components::MaterialChanged>,
    removed_dashpots: RemovedComponents<'w, 's, Dashpot>,
    removed_muscles: RemovedComponents<'w, 's, Muscle>,
    removed_plastic: RemovedComponents<'w, 's, Plastic>,
    removed_bodies: RemovedComponents<'w, 's, PressureBody>,
}

impl MaterialChanges<'_, '_> {
    fn any(&mut self) -> bool {
        let removed = self.removed_dashpots.read().count()
            + self.removed_muscles.read().count()
            + self.removed_plastic.read().count()
            + self.removed_bodies.read().count();
        removed > 0 || !self.changed.is_empty()
    }
}

impl StructureChanges<'_, '_> {
    fn any(&mut self) -> bool {
        // Drain every reader so that old removals are not seen again.
        let removed = self.removed_particles.read().count()
            + self.removed_springs.read().count()
            + self.removed_pins.read().count();
        let materials = self.materials.any();
        removed > 0 || materials || !self.added_particles.is_empty() || !self.added_pins.is_empty()
    }
}

/// The materials' components, read when the solver repacks.
#[derive(SystemParam)]
pub struct MaterialData<'w, 's> {
    dashpots: Query<'w, 's, (Entity, &'static Dashpot), With<Spring>>,
    muscles: Query<'w, 's, (Entity, &'static Muscle), With<Spring>>,
    plastic: Query<'w, 's, (Entity, &'static Plastic), With<Spring>>,
    bodies: Query<'w, 's, &'static PressureBody>,
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
type Springs<'w, 's> = Query<'w, 's, (Entity, &'static Spring), Without<Particle>>;

/// A particle's value edits: what the sync patches in place.
type ParticleEdited = Or<(
    Changed<Position>,
    Changed<Velocity>,
    Changed<Mass>,
    Changed<ExternalForce>,
    Added<Kinematic>,
)>;

/// A spring added or changed.
type SpringEdited = (Changed<Spring>, Without<Particle>);

/// What changed since the last sync, found by filtered scans (they read change ticks, not
/// components, for the entities that did not change): a tick of a big scene with nothing
/// edited costs about one pass over the ticks.
#[derive(SystemParam)]
pub struct Edits<'w, 's> {
    particles: Query<'w, 's, Entity, (With<Particle>, ParticleEdited)>,
    released: RemovedComponents<'w, 's, Kinematic>,
    held: Query<'w, 's, (), (With<Particle>, With<Kinematic>)>,
    /// Springs added or changed (an added component counts as changed).
    springs: Query<'w, 's, (Entity, Ref<'static, Spring>), SpringEdited>,
}

/// Whether the world holds edits that [`sync_into_solver`] would bring into the solver (read
/// without taking them: its own readers still see them). The card's step asks before it, while
/// the solver lags the card's state (`sim::gpu`): an edit must land on the latest state.
/// Between its runs a change counts once it happened after the last; a change it saw before
/// and the sync since took only costs one more read of the card.
#[cfg(feature = "gpu")]
pub fn edits_pending(mut structure: StructureChanges, edits: Edits) -> bool {
    structure.any()
        || !edits.particles.is_empty()
        || !edits.released.is_empty()
        || !edits.springs.is_empty()
}

/// Brings ECS edits into the solver. Runs at the start of every fixed tick.
pub fn sync_into_solver(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    mut structure: StructureChanges,
    mut particles: Particles,
    springs: Springs,
    mut edits: Edits,
    materials: MaterialData,
) {
    let repack = |solver: &mut Solver, particles: &mut Particles, edits: &mut Edits| {
        edits.released.clear();
        rebuild(solver, particles, &springs);
        pack_materials(solver, particles, &materials);
        solver.apply_stiffness_override(params.stiffness_override);
        let n = solver.springs.len();
        solver
            .materials
            .apply_default_dashpot(params.spring_damping, n);
    };
    if structure.any() {
        repack(&mut solver, &mut particles, &mut edits);
        return;
    }
    // The springs' edits first, in the one scan of their change ticks: an added spring (or one
    // whose ends changed) repacks everything, the rest are patched in place.
    let mut springs_changed = false;
    for (e, spring) in &edits.springs {
        springs_changed = true;
        let end = |e: Entity| particles.get(e).ok().map(|p| p.8.0);
        let packed = (end(spring.a).zip(end(spring.b)))
            .and_then(|(a, b)| solver.find_spring(a, b, e))
            .filter(|_| !spring.is_added());
        let Some(si) = packed else {
            // New, or not packed under these ends (they changed, or one was missing at the
            // last rebuild).
            repack(&mut solver, &mut particles, &mut edits);
            return;
        };
        solver.springs[si].rest = spring.rest;
        if let Some(m) = solver.materials.muscle_mut(si) {
            m.rest = spring.rest;
        }
        solver.set_own_stiffness(si, spring.stiffness);
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
        if (pos.is_changed() || vel.is_changed()) && !(pinned || held) {
            solver.edited();
        }
        // Grabbing and releasing (Kinematic) changes the inverse mass without a repack.
        let w = inverse_mass(mass.0, pinned || held);
        if mass.is_changed() || solver.inv_mass[i].to_bits() != w.to_bits() {
            solver.mass[i] = mass.0;
            solver.inv_mass[i] = w;
            solver.touch();
        }
        if external.is_changed() {
            solver.set_external(i, external.0);
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
        solver.refresh_external();
    }
    if springs_changed || solver.applied_override != params.stiffness_override {
        solver.apply_stiffness_override(params.stiffness_override);
    }
    if solver.materials.default_dashpot.to_bits() != params.spring_damping.to_bits() {
        let n = solver.springs.len();
        if solver
            .materials
            .apply_default_dashpot(params.spring_damping, n)
        {
            solver.touch();
        }
    }
}

/// Packs the materials of the springs and loops just packed: each spring's by its entity
/// index (sorted lists, searched: no map of every spring), the pressure bodies' loops by their
/// particles' dense indices.
fn pack_materials(solver: &mut Solver, particles: &Particles, data: &MaterialData) {
    use crate::solver::{GasBody, Materials, PackedMuscle, PackedPlastic};
    let mut m = Materials::default();
    let spring_slots = |list: Vec<(u32, usize)>| -> Vec<(u32, usize)> {
        let mut list = list;
        list.sort_unstable();
        let mut out = vec![];
        for (i, e) in solver.spring_entity_indices.iter().enumerate() {
            if let Ok(k) = list.binary_search_by_key(e, |(e, _)| *e) {
                out.push((i as u32, list[k].1));
            }
        }
        out
    };
    if !data.dashpots.is_empty() {
        let own: Vec<Dashpot> = data.dashpots.iter().map(|(_, d)| *d).collect();
        let list = (data.dashpots.iter().enumerate())
            .map(|(k, (e, _))| (e.index_u32(), k))
            .collect();
        m.own_dashpot = vec![f64::NAN; solver.springs.len()];
        for (i, k) in spring_slots(list) {
            m.own_dashpot[i as usize] = own[k].0;
        }
    }
    if !data.muscles.is_empty() {
        let all: Vec<Muscle> = data.muscles.iter().map(|(_, d)| *d).collect();
        let list = (data.muscles.iter().enumerate())
            .map(|(k, (e, _))| (e.index_u32(), k))
            .collect();
        for (i, k) in spring_slots(list) {
            let (muscle, rest) = (all[k], solver.springs[i as usize].rest);
            m.muscles.push(PackedMuscle {
                spring: i,
                rest,
                amplitude: muscle.amplitude,
                frequency: muscle.frequency,
                phase: muscle.phase,
            });
        }
    }
    if !data.plastic.is_empty() {
        let all: Vec<Plastic> = data.plastic.iter().map(|(_, d)| *d).collect();
        let list = (data.plastic.iter().enumerate())
            .map(|(k, (e, _))| (e.index_u32(), k))
            .collect();
        for (i, k) in spring_slots(list) {
            m.plastic.push(PackedPlastic {
                spring: i,
                yield_strain: all[k].yield_strain,
                rate: all[k].rate,
            });
        }
    }
    for body in &data.bodies {
        let loop_: Vec<u32> = (body.particles.iter())
            .filter_map(|e| particles.get(*e).ok().map(|p| p.8.0))
            .filter(|&i| (i as usize) < solver.x.len())
            .collect();
        if loop_.len() >= 3 {
            m.gas.push(GasBody::new(loop_, body.nrt, &solver.x));
        }
    }
    solver.state.materials = m;
}

/// Repacks every particle and spring. Springs whose endpoints are not both particles are left
/// out.
///
/// Built for millions of springs: no hash maps (particles are ranked by creation order through
/// their query positions, a spring's ends are read from an array by entity index), and the
/// springs are sorted in place ([`sort_springs`]), so that the temporaries are a few bytes per
/// spring beside the packed arrays themselves.
fn rebuild(solver: &mut Solver, particles: &mut Particles, springs: &Springs) {
    // Rank the particles by creation order: rank[j] is the dense index of the j-th in query
    // order (which stays the same until the archetypes change, not within this system).
    let mut order: Vec<(CreationOrder, u32)> = (particles.iter().enumerate())
        .map(|(j, p)| (*p.1, j as u32))
        .collect();
    order.sort_unstable();
    let n = order.len();
    let mut rank = vec![0u32; n];
    for (i, &(_, j)) in order.iter().enumerate() {
        rank[j as usize] = i as u32;
    }
    drop(order);
    // The step's arrays on huge pages where the system has them (`pages`).
    let (mut x, mut v, mut mass, mut inv_mass) = (
        pages::filled(DVec2::ZERO, n),
        pages::filled(DVec2::ZERO, n),
        pages::filled(1.0, n),
        pages::filled(1.0, n),
    );
    let mut entities = vec![Entity::PLACEHOLDER; n];
    let (mut kinematic, mut external_active) = (0, false);
    for (j, (e, _, pos, vel, m, ext, pinned, held, mut solver_index)) in
        particles.iter_mut().enumerate()
    {
        let i = rank[j] as usize;
        solver_index.0 = i as u32;
        entities[i] = e;
        x[i] = pos.0;
        v[i] = if pinned { DVec2::ZERO } else { vel.0 };
        mass[i] = m.0;
        inv_mass[i] = inverse_mass(m.0, pinned || held);
        external_active |= ext.0 != DVec2::ZERO;
        kinematic += held as usize;
    }
    drop(rank);
    // The external forces are stored only while one is set (a second pass, then).
    let mut external = vec![];
    if external_active {
        external = pages::filled(DVec2::ZERO, n);
        for (_, _, _, _, _, ext, _, _, index) in particles.iter() {
            external[index.0 as usize] = ext.0;
        }
    }

    // A spring's ends by entity index: a plain array, not a query lookup per end (which
    // fetches every term of the particle query, and dominated the repack of a big cloth).
    // `entities` confirms the generation, so a stale end reads as missing.
    let top = entities.iter().map(|e| e.index_u32() as usize + 1).max();
    let mut by_index = vec![u32::MAX; top.unwrap_or(0)];
    for (i, e) in entities.iter().enumerate() {
        by_index[e.index_u32() as usize] = i as u32;
    }
    let end = |e: Entity| {
        let i = *by_index.get(e.index_u32() as usize)?;
        (i != u32::MAX && entities[i as usize] == e).then_some(i)
    };
    // Sized once: the query knows its length.
    let m = springs.iter().size_hint().1.unwrap_or(0);
    let (mut packed, mut spring_entity_indices) = (pages::with_capacity(m), Vec::with_capacity(m));
    for (e, s) in springs {
        if let (Some(a), Some(b)) = (end(s.a), end(s.b)) {
            packed.push(PackedSpring {
                a,
                b,
                rest: s.rest,
                k: s.stiffness,
            });
            spring_entity_indices.push(e.index_u32());
        }
    }
    // Grouped by first end, then second (ties by entity index): the spring pass then sums each
    // particle's run of springs in a register, and repeated second ends lie a few springs
    // apart, so no update waits on the previous one's store (see `solver::spring::Run`).
    sort_springs(&mut packed, &mut spring_entity_indices);

    let state = State {
        f: pages::filled(DVec2::ZERO, n),
        external_active,
        external,
        kinematic,
        drift: vec![],
        edits: 0,
        x,
        v,
        mass,
        inv_mass,
        own_stiffness: vec![],
        springs: packed,
        applied_override: None,
        non_finite: false,
        materials: Default::default(),
        // The new revision makes the large-step methods redo their precomputation.
        revision: solver.state.revision.wrapping_add(1),
    };
    *solver = Solver {
        work: solver.work.repacked(),
        state,
        entities,
        spring_entity_indices,
        energy_on_card: None,
    };
}

/// Sorts the packed springs and their entities together by (a, b, entity).
///
/// Springs usually arrive nearly sorted (a generator emits them cell by cell, each a few places
/// from its sorted position), so an insertion sort of the two arrays in place does it in one
/// pass with no extra memory. When it has moved more than a few places per spring the input is
/// not nearly sorted, and a permutation sort finishes the job.
fn sort_springs(springs: &mut [PackedSpring], entities: &mut [u32]) {
    let key = |s: &PackedSpring, e: u32| (s.a, s.b, e);
    let budget = 8 * springs.len();
    let mut moves = 0;
    for i in 1..springs.len() {
        let mut j = i;
        while j > 0 && key(&springs[j - 1], entities[j - 1]) > key(&springs[j], entities[j]) {
            springs.swap(j - 1, j);
            entities.swap(j - 1, j);
            j -= 1;
            moves += 1;
        }
        if moves > budget {
            let mut perm: Vec<u32> = (0..springs.len() as u32).collect();
            perm.sort_unstable_by_key(|&i| key(&springs[i as usize], entities[i as usize]));
            let mut seen = vec![];
            permute(springs, &perm, &mut seen);
            permute(entities, &perm, &mut seen);
            return;
        }
    }
}

/// Reorders `items` in place so that `items[k]` becomes the old `items[perm[k]]`, following the
/// permutation's cycles (`seen`, a bit per item, is scratch): no second copy of the array.
fn permute<T: Copy>(items: &mut [T], perm: &[u32], seen: &mut Vec<u64>) {
    seen.clear();
    seen.resize(items.len().div_ceil(64), 0);
    for start in 0..items.len() {
        if seen[start / 64] >> (start % 64) & 1 == 1 {
            continue;
        }
        let first = items[start];
        let mut k = start;
        loop {
            seen[k / 64] |= 1 << (k % 64);
            let next = perm[k] as usize;
            if next == start {
                items[k] = first;
                break;
            }
            items[k] = items[next];
            k = next;
        }
    }
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
    mut particles: Query<
        (
            &SolverIndex,
            &mut Position,
            &mut Velocity,
            Option<&mut Force>,
        ),
        With<Particle>,
    >,
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
        solver.edited();
        return;
    }
    for (index, mut pos, mut vel, mut force) in &mut particles {
        let i = index.0 as usize;
        if i < solver.x.len() {
            pos.bypass_change_detection().0 = solver.x[i];
            vel.bypass_change_detection().0 = solver.v[i];
            if let Some(force) = &mut force {
                force.bypass_change_detection().0 = solver.f[i];
            }
        }
    }
}

/// Writes the plastic springs' rest lengths back to their [`Spring`]s, without flagging them
/// as changed, so that a save, an undo or a repack keeps the bend.
pub fn write_back_rest_lengths(
    solver: Res<Solver>,
    entities: &bevy::ecs::entity::Entities,
    mut springs: Query<&mut Spring>,
) {
    let moved: Vec<(Entity, f64)> = (solver.materials().plastic().iter())
        .filter_map(|p| {
            let i = p.spring as usize;
            let e = solver.spring_entity(i, entities, |e| springs.get(e).ok().copied())?;
            Some((e, solver.springs[i].rest))
        })
        .collect();
    for (e, rest) in moved {
        if let Ok(mut spring) = springs.get_mut(e)
            && spring.rest.to_bits() != rest.to_bits()
        {
            spring.bypass_change_detection().rest = rest;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both paths of the sort (nearly sorted, and scrambled past the insertion budget) give
    /// the order of a plain sort, with each entity still beside its spring.
    #[test]
    fn springs_sort_by_ends_with_their_entities() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % n) as u32
        };
        for scrambled in [false, true] {
            let n = 5000;
            let mut springs: Vec<PackedSpring> = (0..n)
                .map(|i| {
                    let a = if scrambled {
                        next(700)
                    } else {
                        i / 4 + next(2)
                    };
                    PackedSpring {
                        a,
                        b: a + 1 + next(3),
                        rest: i as f64,
                        k: 1.0,
                    }
                })
                .collect();
            let mut entities: Vec<u32> = (0..n).map(|i| 3 * i + 1).collect();
            let mut expected: Vec<(PackedSpring, u32)> = springs
                .iter()
                .copied()
                .zip(entities.iter().copied())
                .collect();
            expected.sort_by_key(|(s, e)| (s.a, s.b, *e));
            sort_springs(&mut springs, &mut entities);
            let got: Vec<(PackedSpring, u32)> = springs.into_iter().zip(entities).collect();
            assert_eq!(got, expected, "scrambled: {scrambled}");
        }
    }
}
