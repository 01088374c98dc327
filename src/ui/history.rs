//! Undo and redo of every edit: adding, grabbing, pinning, deleting, cutting, tearing,
//! clearing, building, moving and deleting obstacles, and the panel's parameter changes.
//!
//! Each entry is the whole simulation state just before the edit (parameters, clock, every
//! particle and spring), so undoing restores exactly what was there, structure and motion
//! alike. Entries whose springs did not change share one copy of them: a run of parameter
//! changes or grabs on a 64×64 cloth costs 200 kB an entry, not 700 kB. A burst of the same
//! kind of edit (a slider drag, a tearing cloth) within [`COALESCE`] is one entry
//! ([`record_burst`]); discrete edits (clicks, keys) are one entry each ([`record`]).

use crate::scene::bodies::{body_defs, replace_bodies};
use crate::scene::{
    BodyDef, Expanded, ObstacleDef, ParticleDef, PressureDef, SpringDef, explicit_state,
    obstacle_defs, replace_contents, replace_obstacles,
};
use crate::sim::{SimClock, SimParams, SimStatus, watch::EnergyWatch};
use bevy::prelude::*;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Entries kept; the oldest go first.
pub const DEPTH: usize = 200;
/// Edits of the same kind closer together than this are one entry.
pub const COALESCE: Duration = Duration::from_millis(800);

/// A whole simulation state.
#[derive(Debug, Clone)]
pub struct State {
    pub params: SimParams,
    pub clock: SimClock,
    pub particles: Vec<ParticleDef>,
    pub springs: Arc<Vec<SpringDef>>,
    /// The obstacles at their poses.
    pub obstacles: Vec<ObstacleDef>,
    /// The gas-filled loops.
    pub pressure: Vec<PressureDef>,
    /// The rigid bodies at their poses, moving as they moved.
    pub bodies: Vec<BodyDef>,
}

#[derive(Debug, Clone)]
pub struct Entry {
    /// What the edit was ("add", "cut", "stiffness", ...).
    pub label: &'static str,
    pub state: State,
    /// Which version of the scene `state` is (see [`History::unsaved`]).
    version: u64,
}

#[derive(Resource, Debug, Default)]
pub struct History {
    pub undo: VecDeque<Entry>,
    pub redo: Vec<Entry>,
    /// The label and time of the last recorded edit, for coalescing.
    last: Option<(&'static str, Instant)>,
    /// The version on screen: each edit makes a new one, and undo and redo bring back the
    /// version they restore, so undoing back to what was saved leaves nothing unsaved.
    version: u64,
    /// The newest version made.
    newest: u64,
    /// The version last saved or loaded from a file.
    saved: u64,
}

impl History {
    /// Is what is on screen other than what was last saved or loaded: has the user made
    /// something that closing the app would lose? (Running the simulation is no edit.)
    pub fn unsaved(&self) -> bool {
        self.version != self.saved
    }

    /// What is on screen is now in a file (saved, or just loaded).
    pub fn mark_saved(&mut self) {
        self.saved = self.version;
        self.last = None;
    }

    /// The springs of the newest entry, to share when they have not changed.
    fn shared_springs(&self, springs: Vec<SpringDef>) -> Arc<Vec<SpringDef>> {
        let newest = self.undo.back().or(self.redo.last());
        match newest {
            Some(e) if *e.state.springs == springs => e.state.springs.clone(),
            _ => Arc::new(springs),
        }
    }
}

/// The world's state now, with `params` in place of the current parameters when given.
fn capture(world: &mut World, params: Option<SimParams>) -> State {
    let params = params.unwrap_or_else(|| world.resource::<SimParams>().clone());
    let Expanded {
        particles,
        springs,
        pressure,
    } = explicit_state(world, None);
    let springs = world.resource::<History>().shared_springs(springs);
    State {
        params,
        clock: *world.resource::<SimClock>(),
        particles,
        springs,
        obstacles: obstacle_defs(world),
        pressure,
        bodies: body_defs(world),
    }
}

/// Records the state before an edit labelled `label` (call it before the edit takes effect).
pub fn record(world: &mut World, label: &'static str) {
    push(world, label, None, false);
}

/// Records the state before an edit that comes in bursts (a slider drag, a tearing cloth):
/// edits of one label closer together than [`COALESCE`] are one entry, the state before the
/// first. `params` are the parameters before the edit, for an edit that has already changed
/// them.
pub fn record_burst(world: &mut World, label: &'static str, params: Option<SimParams>) {
    push(world, label, params, true);
}

fn push(world: &mut World, label: &'static str, params: Option<SimParams>, burst: bool) {
    let now = Instant::now();
    // (A save ends a burst: `mark_saved` clears `last`.)
    let coalesce = burst
        && world
            .resource::<History>()
            .last
            .is_some_and(|(l, t)| l == label && now.duration_since(t) < COALESCE);
    if coalesce {
        world.resource_mut::<History>().last = Some((label, now));
        return;
    }
    let state = capture(world, params);
    let mut history = world.resource_mut::<History>();
    let version = history.version;
    history.undo.push_back(Entry {
        label,
        state,
        version,
    });
    history.newest += 1;
    history.version = history.newest;
    while history.undo.len() > DEPTH {
        history.undo.pop_front();
    }
    history.redo.clear();
    history.last = Some((label, now));
}

/// A command that records the state before an edit (queue it before the edit's commands).
pub fn before(label: &'static str) -> impl FnOnce(&mut World) {
    move |world: &mut World| record(world, label)
}

/// Puts a recorded state into the world. The run state (paused or not) stays as it is, and a
/// blow-up is cleared; the simulation pauses if it had stopped on one.
fn restore(world: &mut World, state: &State) {
    let status = *world.resource::<SimStatus>();
    let paused = world.resource::<SimParams>().paused || status != SimStatus::Running;
    let params = SimParams {
        paused,
        ..state.params.clone()
    };
    let expanded = Expanded {
        particles: state.particles.clone(),
        springs: state.springs.to_vec(),
        pressure: state.pressure.clone(),
    };
    replace_contents(world, params, &expanded);
    if obstacle_defs(world) != state.obstacles {
        replace_obstacles(world, &state.obstacles);
    }
    if body_defs(world) != state.bodies {
        let gravity = state.params.gravity;
        replace_bodies(world, &state.bodies, gravity);
    }
    *world.resource_mut::<SimClock>() = state.clock;
    *world.resource_mut::<SimStatus>() = SimStatus::Running;
    if let Some(mut watch) = world.get_resource_mut::<EnergyWatch>() {
        *watch = EnergyWatch::default();
    }
}

/// Takes back the newest edit. Returns its label, or `None` when there is nothing to undo.
pub fn undo(world: &mut World) -> Option<&'static str> {
    travel(world, |h| h.undo.pop_back(), |h, e| h.redo.push(e))
}

/// Does again the newest undone edit. Returns its label, or `None` when there is none.
pub fn redo(world: &mut World) -> Option<&'static str> {
    travel(world, |h| h.redo.pop(), |h, e| h.undo.push_back(e))
}

/// Restores the entry `take` gives, and hands the state it replaced, under the same label, to
/// `put` (the other stack).
fn travel(
    world: &mut World,
    take: fn(&mut History) -> Option<Entry>,
    put: fn(&mut History, Entry),
) -> Option<&'static str> {
    let entry = take(&mut world.resource_mut::<History>())?;
    let now = capture(world, None);
    restore(world, &entry.state);
    let mut history = world.resource_mut::<History>();
    let version = history.version;
    put(
        &mut history,
        Entry {
            label: entry.label,
            state: now,
            version,
        },
    );
    history.version = entry.version;
    history.last = None;
    Some(entry.label)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Particle, Solver, Spring};
    use bevy::math::DVec2;

    fn state(world: &mut World) -> (Vec<DVec2>, Vec<DVec2>, Vec<f64>, usize, SimClock) {
        crate::sim::pack(world).unwrap();
        let s = world.resource::<Solver>();
        let out = (
            s.x.clone(),
            s.v.clone(),
            s.inv_mass.clone(),
            s.spring_count(),
        );
        (out.0, out.1, out.2, out.3, *world.resource::<SimClock>())
    }

    /// Deleting a particle of a moving rope and running on, then undoing, gives back the rope
    /// as it was at the delete, to the bit; redo gives back the state undo left.
    #[test]
    fn undo_restores_exactly_what_was_there_and_redo_the_edit() {
        let loaded = crate::scene::presets::resolve("rope").unwrap();
        let mut app = crate::running_app(&loaded).unwrap();
        app.init_resource::<History>();
        let world = app.world_mut();
        crate::sim::advance(world, 500);
        let before = state(world);
        record(world, "delete");
        let victim = world.resource::<Solver>().entities[5];
        let attached: Vec<Entity> = world
            .query::<(Entity, &Spring)>()
            .iter(world)
            .filter(|(_, s)| s.a == victim || s.b == victim)
            .map(|(e, _)| e)
            .collect();
        for e in attached.into_iter().chain([victim]) {
            world.despawn(e);
        }
        crate::sim::advance(world, 300);
        let after = state(world);
        assert_eq!(after.0.len(), before.0.len() - 1);

        assert_eq!(undo(world), Some("delete"));
        assert_eq!(state(world), before);
        assert_eq!(world.resource::<History>().redo.len(), 1);
        assert_eq!(redo(world), Some("delete"));
        assert_eq!(state(world), after);
        assert_eq!(undo(world), Some("delete"));
        assert_eq!(undo(world), None, "one edit, one undo");
        let particles = world.query::<&Particle>().iter(world).count();
        assert_eq!(particles, before.0.len());
    }

    /// Nothing is unsaved until an edit; saving marks what is on screen saved; undoing past the
    /// save, or an edit after it (a burst's next step included), makes it unsaved again, and
    /// redoing back to it saved.
    #[test]
    fn unsaved_follows_the_edits_since_the_save() {
        let mut app = crate::headless_app();
        app.init_resource::<History>();
        let world = app.world_mut();
        let unsaved = |w: &World| w.resource::<History>().unsaved();
        assert!(!unsaved(world));
        record(world, "add");
        assert!(unsaved(world));
        world.resource_mut::<History>().mark_saved();
        assert!(!unsaved(world));
        undo(world);
        assert!(unsaved(world), "undone past the save");
        redo(world);
        assert!(!unsaved(world), "redone back to it");
        record_burst(world, "stiffness", None);
        world.resource_mut::<History>().mark_saved();
        record_burst(world, "stiffness", None);
        assert!(unsaved(world), "a burst goes on after a save");
        undo(world);
        assert!(!unsaved(world), "back at the saved state");
        undo(world);
        undo(world);
        assert!(unsaved(world));
    }

    /// A slider drag is one entry, a different edit another, each click one; a new edit drops
    /// the redos; the oldest entries go past [`DEPTH`].
    #[test]
    fn bursts_of_one_kind_of_edit_are_one_entry() {
        let mut app = crate::headless_app();
        app.init_resource::<History>();
        let world = app.world_mut();
        for _ in 0..5 {
            record_burst(world, "stiffness", None);
        }
        record_burst(world, "damping", None);
        assert_eq!(world.resource::<History>().undo.len(), 2);
        // A parameter edit records the parameters from before it; undo puts them back.
        let before = world.resource::<SimParams>().clone();
        world.resource_mut::<SimParams>().stiffness_override = Some(4e5);
        record_burst(world, "stiffness", Some(before.clone()));
        assert_eq!(undo(world), Some("stiffness"));
        assert_eq!(*world.resource::<SimParams>(), before);
        assert_eq!(redo(world), Some("stiffness"));
        assert_eq!(world.resource::<SimParams>().stiffness_override, Some(4e5));
        record(world, "add");
        record(world, "add");
        assert_eq!(
            world.resource::<History>().undo.len(),
            5,
            "clicks are one entry each"
        );
        undo(world);
        undo(world);
        assert_eq!(world.resource::<History>().redo.len(), 2);
        record(world, "add");
        assert!(world.resource::<History>().redo.is_empty());
        for _ in 0..2 * DEPTH {
            record(world, "add");
        }
        assert_eq!(world.resource::<History>().undo.len(), DEPTH);
    }
}
