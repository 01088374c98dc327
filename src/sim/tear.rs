//! Tearing: springs stretched past their limit break.
//!
//! Once per fixed tick, after the writeback, [`find_torn_springs`] lists every spring longer
//! than (1 + strain) × rest ([`SimParams::tear`]) in [`Tearing::pending`]; then
//! [`remove_torn_springs`] despawns them, and the next tick's sync repacks the solver. A system
//! ordered between the two sees the springs about to break with the world still whole (the
//! app's undo history records the state before a tear there). Springs of zero rest length have
//! no strain and never tear. With tearing off neither system runs.

use super::components::Spring;
use super::params::{PassCounts, SimParams, Tearing};
use super::solver::Solver;
use bevy::ecs::entity::Entities;
use bevy::prelude::*;

/// Run condition: tearing is on.
pub fn tearing_enabled(params: Res<SimParams>) -> bool {
    params.tear.is_some()
}

/// Run condition: springs are waiting to be removed.
pub fn tears_pending(tearing: Res<Tearing>) -> bool {
    !tearing.pending.is_empty()
}

/// Lists the springs stretched past the limit.
pub fn find_torn_springs(
    solver: Res<Solver>,
    entities: &Entities,
    springs: Query<&Spring>,
    params: Res<SimParams>,
    mut tearing: ResMut<Tearing>,
    mut n: ResMut<PassCounts>,
) {
    let Some(strain) = params.tear else { return };
    let limit = 1.0 + strain;
    let s = &*solver;
    let torn = s.springs.iter().enumerate().filter(|(_, sp)| {
        let l = (s.x[sp.a as usize] - s.x[sp.b as usize]).length();
        sp.rest > 0.0 && l > limit * sp.rest
    });
    let entity = |i| s.spring_entity(i, entities, |e| springs.get(e).ok().copied());
    tearing.pending.extend(torn.filter_map(|(i, _)| entity(i)));
    n.tear += 1;
}

/// Despawns the springs [`find_torn_springs`] found, and counts them.
pub fn remove_torn_springs(commands: Commands, tearing: ResMut<Tearing>) {
    remove_pending(commands, tearing);
}

/// Despawns the springs the card tore in the last tick (`sim::gpu`, its state read on demand),
/// at the start of this one, before the solver syncs: as the CPU's removal at the end of the
/// last, so that the repack leaves them out. (A system of its own, so that the app's undo can
/// record the state before either removal.)
pub fn remove_springs_torn_on_card(commands: Commands, tearing: ResMut<Tearing>) {
    remove_pending(commands, tearing);
}

fn remove_pending(mut commands: Commands, mut tearing: ResMut<Tearing>) {
    let pending = std::mem::take(&mut tearing.pending);
    tearing.torn += pending.len() as u64;
    for e in pending {
        commands.entity(e).try_despawn();
    }
}
