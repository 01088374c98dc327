//! The edits a user makes to the network, as commands: each records the state before it in the
//! undo history ([`super::history`]), then changes the entities; the solver follows at the next
//! tick's sync. Nothing here touches the solver's arrays directly.

use super::history;
use crate::scene::ClickRules;
use crate::sim::*;
use crate::solver::Shape;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Adds a particle at `at`, joined to `neighbours` (entity, distance) by springs at their
/// current length. Returns the new particle.
pub fn add_particle(
    commands: &mut Commands,
    at: DVec2,
    pinned: bool,
    rules: &ClickRules,
    stiffness: f64,
    neighbours: &[(Entity, f64)],
) -> Entity {
    commands.queue(history::before("add"));
    let mut particle = commands.spawn((Particle, Position(at), Mass(rules.mass)));
    if pinned {
        particle.insert(Pinned);
    }
    let new = particle.id();
    for &(other, rest) in neighbours {
        commands.spawn(Spring::new(new, other, rest, stiffness));
    }
    new
}

/// Pins a free particle, or frees a pinned one.
pub fn toggle_pin(commands: &mut Commands, particle: Entity, pinned: bool) {
    commands.queue(history::before("pin"));
    if pinned {
        commands.entity(particle).remove::<Pinned>();
    } else {
        commands.entity(particle).insert(Pinned);
    }
}

/// Deletes a particle and every spring attached to it.
pub fn delete_particle<'a>(
    commands: &mut Commands,
    particle: Entity,
    springs: impl IntoIterator<Item = (Entity, &'a Spring)>,
) {
    commands.queue(history::before("delete"));
    for (e, s) in springs {
        if s.a == particle || s.b == particle {
            commands.entity(e).despawn();
        }
    }
    commands.entity(particle).despawn();
}

/// Removes every particle and spring.
pub fn clear(commands: &mut Commands, entities: impl IntoIterator<Item = Entity>) {
    commands.queue(history::before("clear"));
    for e in entities {
        commands.entity(e).despawn();
    }
}

/// Cuts springs (the first cut of a stroke records the state before it).
pub fn cut(commands: &mut Commands, springs: &[Entity], first_of_stroke: bool) {
    if first_of_stroke {
        commands.queue(history::before("cut"));
    }
    for &e in springs {
        commands.entity(e).try_despawn();
    }
}

/// Adds an obstacle of `shape` centred at `center`, unrotated and at rest.
pub fn add_obstacle(commands: &mut Commands, shape: Shape, center: DVec2) {
    commands.queue(history::before("obstacle"));
    commands.spawn((Obstacle(shape), ObstaclePose { center, angle: 0.0 }));
}

/// Deletes an obstacle.
pub fn delete_obstacle(commands: &mut Commands, obstacle: Entity) {
    commands.queue(history::before("delete obstacle"));
    commands.entity(obstacle).try_despawn();
}
