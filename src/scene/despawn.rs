//! Clearing a kind of entity from a world: what loading a scene does to the particles and
//! springs, the obstacles and the rigid bodies it replaces.

use bevy::ecs::query::QueryFilter;
use bevy::prelude::*;

/// Despawns every entity that `F` selects (a scene's particles and springs, its obstacles,
/// its bodies).
pub(crate) fn despawn_all<F: QueryFilter>(world: &mut World) {
    let old: Vec<Entity> = world.query_filtered::<Entity, F>().iter(world).collect();
    for e in old {
        world.despawn(e);
    }
}
