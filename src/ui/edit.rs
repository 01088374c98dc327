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

/// Removes every particle, spring and pressure body.
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

/// The spacing of a drawn ball's particles, m.
const BALL_SPACING: f64 = 0.02;
/// A drawn ball's particle mass, kg.
const BALL_MASS: f64 = 0.05;
/// How far the gas inflates a drawn ball's springs past their rest length.
const BALL_INFLATION: f64 = 0.1;

/// Adds a ball: a ring of particles round `center` whose springs (of `stiffness`) are at rest
/// at `radius`, filled with a gas that stretches them by [`BALL_INFLATION`]. For N sides of
/// rest length L₀ and stretched side s = (1 + ε) L₀, the balance N k (s − L₀) = 2 nRT/s of
/// `docs/integrators.md` gives nRT = N k s (s − L₀)/2.
pub fn add_ball(commands: &mut Commands, center: DVec2, radius: f64, stiffness: f64) {
    use std::f64::consts::TAU;
    commands.queue(history::before("ball"));
    let n = ((TAU * radius / BALL_SPACING).round() as usize).clamp(8, 64);
    let particles: Vec<Entity> = (0..n)
        .map(|i| {
            let at = center + DVec2::from_angle(TAU * i as f64 / n as f64) * radius;
            let particle = (Particle, Position(at), Mass(BALL_MASS));
            commands.spawn(particle).id()
        })
        .collect();
    let rest = 2.0 * radius * (TAU / (2.0 * n as f64)).sin();
    for i in 0..n {
        let (a, b) = (particles[i], particles[(i + 1) % n]);
        commands.spawn(Spring::new(a, b, rest, stiffness));
    }
    let side = (1.0 + BALL_INFLATION) * rest;
    let nrt = n as f64 * stiffness * side * (side - rest) / 2.0;
    commands.spawn(PressureBody { particles, nrt });
}

/// Adds an obstacle of `shape` centred at `center`, unrotated and at rest.
pub fn add_obstacle(commands: &mut Commands, shape: Shape, center: DVec2) {
    commands.queue(history::before("obstacle"));
    commands.spawn((Obstacle(shape), ObstaclePose { center, angle: 0.0 }));
}

/// The crates' density, kg/m²: a 10 cm crate weighs 1 kg, as the app's particles do.
pub const CRATE_DENSITY: f64 = 100.0;

/// Adds a crate, a rigid box of avian's of half size `half` centred at `center`, at rest.
pub fn add_crate(commands: &mut Commands, half: DVec2, center: DVec2) {
    commands.queue(history::before("crate"));
    let def = crate::scene::BodyDef {
        shape: crate::scene::ObstacleDef::Box {
            center: (center.x, center.y),
            half: (half.x, half.y),
            angle: 0.0,
        },
        mass: 4.0 * half.x * half.y * CRATE_DENSITY,
        velocity: (0.0, 0.0),
        spin: 0.0,
        fixed: false,
    };
    commands.queue(move |world: &mut World| {
        crate::scene::bodies::spawn_body(world, &def);
    });
}

/// Deletes an obstacle.
pub fn delete_obstacle(commands: &mut Commands, obstacle: Entity) {
    commands.queue(history::before("delete obstacle"));
    commands.entity(obstacle).try_despawn();
}
