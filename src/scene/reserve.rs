//! Entity ids reserved for a scene's spawn, so that a scene of millions of entities makes Bevy's
//! per-entity storage grow once, to its final size.
//!
//! Bevy keeps a metadata record per entity index (24 bytes) in a `Vec` that grows when an entity
//! past its end is spawned, and a `Vec` grows by doubling: after the 20 M entities of a 2000²
//! cloth it held 33.5 M records, 20 bytes a spring of the cloth's peak memory, spent on nothing.
//! A batch spawn sizes the tables exactly but takes its ids one after the other from the
//! allocator. So the load allocates all the scene's ids first, spawns (and despawns) the one
//! with the highest index, which grows the metadata once to hold them all, and hands the ids
//! back to the allocator just before each batch, which takes them from its free list, in order.
//!
//! The free list costs 8 bytes per id it holds at once, so a batch holds at most half the
//! springs (two batches still size a table exactly: the second doubles the first). A scene
//! loaded over one as big finds its ids on the free list, within the metadata, and grows
//! nothing. (The allocator keeps up to 127 freed ids on a local list that batches do not take
//! from: the room left after the scene covers them.)
//!
//! The room lies *below* the scene's ids, and is handed out lowest first. Bevy stores every
//! resource as a sparse-set component on an entity of its own, and a sparse set keeps an
//! array indexed by entity index, 4 bytes per index up to its highest entity. A resource
//! first inserted after a scene (the load's `CurrentScene`, the id of a system run with
//! `run_system_cached`, a panel's notice) gets the next free id: past the scene's, that array
//! spans the whole scene, 81 MB for each such resource at 16 M springs (three of them made
//! 15 of the cloth's 201 bytes a spring); below the scene's, it spans the few entities made
//! before it.

use bevy::prelude::*;

/// Ids allocated for entities still to be spawned, handed out batch by batch.
pub(super) struct Reserved {
    ids: Vec<Entity>,
    next: usize,
    /// The ids of the [`HEADROOM`].
    room: Vec<Entity>,
}

/// Scenes of fewer entities than this spawn without reserving: their metadata's doubling is
/// a few kilobytes, and the allocator keeps ids freed a few at a time (up to 128) on a local
/// list that batches do not take from.
const RESERVE_MIN: usize = 1 << 16;

/// Room for one more entity per this many of the scene's, within the grown metadata: what a
/// resource, a clicked particle or an edit spawns later would otherwise double it again at
/// once (a resource is an entity too: the load's own `insert_resource` did, +480 MB at 16 M
/// springs). It costs 1.5 bytes a spring.
const HEADROOM: usize = 16;

impl Reserved {
    /// Allocates ids for `count` entities and grows the entity metadata to hold them; `None`
    /// for a scene too small to need it ([`RESERVE_MIN`]).
    pub(super) fn new(world: &mut World, count: usize) -> Option<Reserved> {
        if count < RESERVE_MIN {
            return None;
        }
        let records = world.entities().len();
        let take = |world: &mut World, n: usize| -> Vec<Entity> {
            let n = u32::try_from(n).unwrap_or(u32::MAX);
            world.entity_allocator().alloc_many(n).collect()
        };
        let mut ids = take(world, count);
        // A scene loaded over one as big takes its ids back from the free list, and the
        // metadata already holds them: nothing to grow, and the room is still there.
        let mut room = vec![];
        if ids.iter().any(|e| e.index_u32() >= records) {
            // The fresh ids (after any reused ones) and the room's are one ascending run: the
            // room takes its first ids, and the scene the rest, in order.
            let extra = count / HEADROOM;
            ids.extend(take(world, extra));
            let mut run = ids.len() - 1;
            while run > 0 && ids[run - 1].index_u32().checked_add(1) == Some(ids[run].index_u32()) {
                run -= 1;
            }
            room = ids.drain(run..run + extra).collect();
            let highest = (ids.iter_mut().chain(&mut room)).max_by_key(|e| e.index_u32());
            // Spawned and despawned without being freed: its id, a generation on, is handed
            // out with the others (a single id freed alone would wait on the local list).
            if let Some(highest) = highest
                && world.spawn_empty_at(*highest).is_ok()
                && let Ok(next) = world.try_despawn_no_free(*highest)
            {
                *highest = next;
            }
        }
        Some(Reserved { ids, next: 0, room })
    }

    /// Hands the next `n` ids back to the allocator, for the next batch of `n` to take.
    pub(super) fn release(&mut self, world: &mut World, n: usize) {
        let end = self.next.saturating_add(n).min(self.ids.len());
        world
            .entity_allocator_mut()
            .free_many(&self.ids[self.next..end]);
        self.next = end;
    }

    /// After the last batch: hands back the room (and any ids not released yet), for whatever
    /// is spawned later. Freed last, it fits the free list's buffer as the batches left it
    /// (freed first, under the batches' ids, it grew it by 4 bytes a spring). Freed highest
    /// first, as the free list hands out the last id freed first: the lowest go first.
    pub(super) fn finish(mut self, world: &mut World) {
        self.release(world, usize::MAX);
        self.room.reverse();
        world.entity_allocator_mut().free_many(&self.room);
    }
}
