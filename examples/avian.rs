//! hooke's particles and avian2d's rigid bodies in one world, headless, each pushing the other:
//!
//! - a trampoline: a net hung by its two ends, two crates dropped on it;
//! - a rope pinned at one end, a crate tied to its other end ([`Attachment`]), let go level with
//!   the pin: it swings down into a stack of three boxes and knocks it;
//! - a seesaw: a plank lying on a fixed wedge, a soft ball dropped on one end, which tips it.
//!
//! Every quarter second it prints the crates' heights on the net, the swinging crate's place,
//! the stack's top box and the plank's angle.
//!
//! `cargo run --release --example avian`
//!
//! In your own app: add avian's `PhysicsPlugins` and hooke's `HookeAvianPlugin` beside
//! `SimPlugin`, spawn avian's bodies as avian's documentation says, and hooke's particles
//! collide with their colliders, the dynamic ones feeling the particles. A scene file can hold
//! bodies too (`bodies: [..]`, the `crates` scene), though not yet attachments.

use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::sim::avian::{Attachment, HookeAvianPlugin};
use hooke::sim::{
    ContactSettings, Dashpot, Integrator, Mass as ParticleMass, Particle, Pinned,
    Position as ParticlePosition, SimParams, Spring,
};

/// The step: XPBD at 1/240 s, the two engines' one clock.
const DT: f64 = 1.0 / 240.0;

fn main() {
    let mut app = hooke::headless_app();
    app.add_plugins((
        bevy::transform::TransformPlugin,
        PhysicsPlugins::default(),
        HookeAvianPlugin,
    ));
    // avian readies some of its resources in `finish`, which `App::run` calls.
    app.finish();
    app.cleanup();
    app.insert_resource(Gravity(Vec2::new(0.0, -9.8)));
    {
        let mut p = app.world_mut().resource_mut::<SimParams>();
        p.integrator = Integrator::Xpbd;
        p.dt = DT;
        p.damping = 1.0;
        p.ground = Some(0.0);
        p.paused = false;
        p.contact = Some(ContactSettings {
            radius: 0.005,
            friction: 0.5,
            ..ContactSettings::default()
        });
    }
    let world = app.world_mut();
    // The floor, for the bodies: a fixed box with its top at y = 0.1.
    body(
        world,
        RigidBody::Static,
        Collider::rectangle(3.0, 0.1),
        1.0,
        (1.4, 0.05),
    );
    let crates = trampoline(world);
    let (swinging, stack) = rope_and_stack(world);
    let plank = seesaw(world);

    println!(
        "  t (s)  crates on the net (y, m)  swinging crate (x, y)  stack's top (x, y)  plank (°)"
    );
    for k in 1..=16 {
        hooke::sim::advance(app.world_mut(), (0.25 / DT).round() as u64);
        let w = app.world();
        let at = |e: Entity| w.get::<Position>(e).map_or(Vec2::NAN, |p| p.0);
        let angle = w
            .get::<Rotation>(plank)
            .map_or(f32::NAN, |r| r.as_degrees());
        let (s, top) = (at(swinging), at(stack));
        println!(
            "{:7.2}  {:>6.3} {:>6.3}             {:>6.3} {:>6.3}          {:>6.3} {:>6.3}     {:>6.1}",
            k as f64 * 0.25,
            at(crates[0]).y,
            at(crates[1]).y,
            s.x,
            s.y,
            top.x,
            top.y,
            angle,
        );
    }
}

/// A rigid body of `mass` kg at `at`.
fn body(
    world: &mut World,
    kind: RigidBody,
    collider: Collider,
    mass: f32,
    at: (f32, f32),
) -> Entity {
    world
        .spawn((kind, collider, Mass(mass), Position(Vec2::new(at.0, at.1))))
        .id()
}

/// A particle of `mass` kg at `at`.
fn particle(world: &mut World, at: DVec2, mass: f64) -> Entity {
    world
        .spawn((Particle, ParticlePosition(at), ParticleMass(mass)))
        .id()
}

/// A net of 41 × 2 particles of 10 g between x = 0.1 and 0.9 at y = 0.5, its two top corners
/// pinned, and two crates dropped on it. Returns the crates.
fn trampoline(world: &mut World) -> [Entity; 2] {
    let (columns, dx) = (41, 0.02);
    let mut net = vec![];
    for r in 0..2 {
        for c in 0..columns {
            let at = DVec2::new(0.1 + c as f64 * dx, 0.5 - r as f64 * dx);
            let p = particle(world, at, 0.01);
            if r == 0 && (c == 0 || c == columns - 1) {
                world.entity_mut(p).insert(Pinned);
            }
            net.push(p);
        }
    }
    let id = |r: usize, c: usize| net[r * columns + c];
    for c in 0..columns {
        for r in 0..2 {
            if c + 1 < columns {
                world.spawn(Spring::new(id(r, c), id(r, c + 1), dx, 2e4));
            }
        }
        world.spawn(Spring::new(id(0, c), id(1, c), dx, 2e4));
        if c + 1 < columns {
            let d = dx * std::f64::consts::SQRT_2;
            world.spawn(Spring::new(id(0, c), id(1, c + 1), d, 2e4));
            world.spawn(Spring::new(id(1, c), id(0, c + 1), d, 2e4));
        }
    }
    let crate_body = |world: &mut World, x: f32, y: f32| {
        body(
            world,
            RigidBody::Dynamic,
            Collider::rectangle(0.12, 0.08),
            0.5,
            (x, y),
        )
    };
    [crate_body(world, 0.35, 0.75), crate_body(world, 0.6, 0.9)]
}

/// A rope of 20 particles of 5 g pinned at (1.5, 0.8), laid out level to the left, a 0.5 kg
/// crate tied to its free end; three boxes stacked on the floor under the pin's right. Returns
/// the crate and the stack's top box.
fn rope_and_stack(world: &mut World) -> (Entity, Entity) {
    let (n, dx) = (20, 0.025);
    let pin = DVec2::new(1.5, 0.8);
    let beads: Vec<Entity> = (0..n)
        .map(|i| particle(world, pin - DVec2::X * (i as f64 * dx), 0.005))
        .collect();
    world.entity_mut(beads[0]).insert(Pinned);
    for pair in beads.windows(2) {
        world.spawn((Spring::new(pair[0], pair[1], dx, 5e3), Dashpot(0.5)));
    }
    let end = pin - DVec2::X * ((n - 1) as f64 * dx);
    let swinging = body(
        world,
        RigidBody::Dynamic,
        Collider::rectangle(0.1, 0.1),
        0.5,
        (end.x as f32, end.y as f32 - 0.05),
    );
    world.entity_mut(beads[n - 1]).insert(Attachment {
        body: swinging,
        anchor: Vec2::new(0.0, 0.05),
    });
    let mut top = swinging;
    for k in 0..3 {
        top = body(
            world,
            RigidBody::Dynamic,
            Collider::rectangle(0.1, 0.1),
            0.2,
            (1.62, 0.15 + 0.1 * k as f32),
        );
    }
    (swinging, top)
}

/// A plank of 0.6 m lying on a fixed wedge at x = 2.3, and a soft ball (a hub and a rim of 16
/// particles, 0.2 kg, springs with dashpots) dropped on its left end. Returns the plank.
fn seesaw(world: &mut World) -> Entity {
    let wedge = Collider::triangle(
        Vec2::new(-0.06, 0.0),
        Vec2::new(0.06, 0.0),
        Vec2::new(0.0, 0.1),
    );
    body(world, RigidBody::Static, wedge, 1.0, (2.3, 0.1));
    let plank = body(
        world,
        RigidBody::Dynamic,
        Collider::rectangle(0.6, 0.02),
        0.3,
        (2.3, 0.21),
    );
    let (centre, radius, n) = (DVec2::new(2.1, 0.6), 0.06, 16);
    let m = 0.2 / (n + 1) as f64;
    let hub = particle(world, centre, m);
    let rim: Vec<Entity> = (0..n)
        .map(|k| {
            let at =
                centre + DVec2::from_angle(k as f64 * std::f64::consts::TAU / n as f64) * radius;
            particle(world, at, m)
        })
        .collect();
    let side = 2.0 * radius * (std::f64::consts::PI / n as f64).sin();
    for k in 0..n {
        let (a, b) = (rim[k], rim[(k + 1) % n]);
        world.spawn((Spring::new(a, b, side, 3e3), Dashpot(2.0)));
        world.spawn((Spring::new(hub, a, radius, 3e3), Dashpot(2.0)));
    }
    plank
}
