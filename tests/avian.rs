//! hooke in an avian2d world (feature `avian`): momentum exchanged in a head-on impact, the
//! spin of an off-centre hit, a crate hanging on a rope, a box resting on a trampoline, avian's
//! circle against hooke's own, a heavy box on a light cloth, and the two clocks in lockstep.

#![cfg(feature = "avian")]

mod common;
use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use hooke::sim::avian::{Attachment, Coupling, HookeAvianPlugin};
use hooke::sim::{
    ContactSettings, Dashpot, Integrator, Mass as ParticleMass, Obstacle, ObstaclePose, Particle,
    Pinned, Position as ParticlePosition, SimClock, SimParams, Solver, Spring,
    Velocity as ParticleVelocity,
};
use std::time::Duration;

/// A headless app with avian and the coupling, stepping `dt` a frame, running.
fn coupled(integrator: Integrator, dt: f64, gravity: Vec2) -> App {
    let mut app = hooke::headless_app();
    app.add_plugins((
        bevy::transform::TransformPlugin,
        PhysicsPlugins::default(),
        HookeAvianPlugin,
    ));
    frame(&mut app, integrator, dt);
    app.insert_resource(Gravity(gravity));
    // avian readies some of its resources in its plugins' `finish`, which `App::run` calls and
    // a hand-stepped app must call itself.
    app.finish();
    app.cleanup();
    app
}

/// hooke's settings for these tests: no air damping, no ground, contact of radius 5 mm
/// without friction or bounce, one step of `dt` a frame.
fn frame(app: &mut App, integrator: Integrator, dt: f64) {
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        dt,
    )));
    let mut p = app.world_mut().resource_mut::<SimParams>();
    p.integrator = integrator;
    p.dt = dt;
    p.damping = 0.0;
    p.ground = None;
    p.paused = false;
    p.contact = Some(ContactSettings {
        radius: 0.005,
        ..ContactSettings::default()
    });
}

fn run(app: &mut App, frames: usize) {
    for _ in 0..frames {
        app.update();
    }
}

/// A dynamic box of `size` (m) and `mass` (kg) at `at`, turned by `turn` rad.
fn dynamic_box(world: &mut World, size: Vec2, mass: f32, at: Vec2, turn: f32) -> Entity {
    world
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(size.x, size.y),
            Mass(mass),
            Position(at),
            Rotation::radians(turn),
        ))
        .id()
}

/// A soft ball of `mass` kg: a centre and a ring of 16 particles, rim and spokes with
/// dashpots, moving at `v`.
fn soft_ball(world: &mut World, centre: DVec2, radius: f64, mass: f64, v: DVec2) -> Vec<Entity> {
    let n = 16;
    let m = mass / (n + 1) as f64;
    let mut spawn = |at: DVec2| {
        world
            .spawn((
                Particle,
                ParticlePosition(at),
                ParticleVelocity(v),
                ParticleMass(m),
            ))
            .id()
    };
    let hub = spawn(centre);
    let rim: Vec<Entity> = (0..n)
        .map(|k| {
            spawn(centre + DVec2::from_angle(k as f64 * std::f64::consts::TAU / n as f64) * radius)
        })
        .collect();
    let side = 2.0 * radius * (std::f64::consts::PI / n as f64).sin();
    for k in 0..n {
        let (a, b) = (rim[k], rim[(k + 1) % n]);
        world.spawn((Spring::new(a, b, side, 2e3), Dashpot(80.0)));
        world.spawn((Spring::new(hub, a, radius, 2e3), Dashpot(80.0)));
    }
    let mut all = vec![hub];
    all.extend(rim);
    all
}

/// A 1 kg particle at (0.1, 0) moving at 1 m/s toward [`one_kg_box`].
fn one_kg_particle(world: &mut World) -> Entity {
    world
        .spawn((
            Particle,
            ParticlePosition(DVec2::new(0.1, 0.0)),
            ParticleVelocity(DVec2::new(1.0, 0.0)),
            ParticleMass(1.0),
        ))
        .id()
}

/// A dynamic 0.2 m square box of 1 kg at (0.25, 0), at rest.
fn one_kg_box(world: &mut World) -> Entity {
    world
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(0.2, 0.2),
            Mass(1.0),
            Position(Vec2::new(0.25, 0.0)),
        ))
        .id()
}

/// The particles' total momentum, kg·m/s.
fn particle_momentum(app: &App) -> DVec2 {
    let s = app.world().resource::<Solver>();
    s.v().iter().zip(s.mass()).map(|(v, m)| *v * *m).sum()
}

fn body_velocity(app: &App, body: Entity) -> DVec2 {
    app.world()
        .get::<LinearVelocity>(body)
        .unwrap()
        .0
        .as_dvec2()
}

/// Every integrator at a step it is made for (the explicit ones small, the large-step ones at
/// 1/120 s) and the frames that make 0.8 s of it.
const EACH_METHOD_FOR_0_8_S: [(Integrator, f64, usize); 9] = [
    (Integrator::SymplecticEuler, 1e-4, 8000),
    (Integrator::ExplicitEuler, 1e-5, 80000),
    (Integrator::VelocityVerlet, 1e-4, 8000),
    (Integrator::Rk4, 1e-4, 8000),
    (Integrator::Xpbd, 1.0 / 120.0, 96),
    (Integrator::ImplicitEuler, 1.0 / 120.0, 96),
    (Integrator::ProjectiveDynamics, 1.0 / 120.0, 96),
    (Integrator::Bdf2, 1.0 / 120.0, 96),
    (Integrator::Vbd, 1.0 / 120.0, 96),
];

/// A 1 kg soft ball, and a 1 kg particle, hit a 1 kg box head-on with gravity off: the
/// momentum is kept to 1e-5 under every integrator, each at a step it is made for (the
/// explicit ones small, the large-step ones at 1/120 s), by whichever place its contact acts
/// in: the contact pass, the velocity pass after a solve, XPBD's substeps, the contact forces
/// of the implicit solves, VBD's last sweep. Two limits, measured here: VBD's notes are exact
/// where its iterations converge (200 here; its default 10 left the pair's momentum 27 %
/// high), and BDF2's history carries part of a soft ball's contact into later steps, where
/// the box does not see it (the pair keeps 78 %, never more than it had).
#[test]
fn a_head_on_impact_keeps_the_momentum() {
    for (integrator, dt, frames) in EACH_METHOD_FOR_0_8_S {
        for ball in [true, false] {
            let mut app = coupled(integrator, dt, Vec2::ZERO);
            app.world_mut().resource_mut::<SimParams>().iterations.vbd = 200;
            let w = app.world_mut();
            if ball {
                soft_ball(w, DVec2::new(0.0, 0.0), 0.1, 1.0, DVec2::new(1.0, 0.0));
            } else {
                one_kg_particle(w);
            }
            let body = one_kg_box(w);
            run(&mut app, 2);
            let before = particle_momentum(&app) + body_velocity(&app, body);
            assert!((before.x - 1.0).abs() < 1e-9, "{before}");
            let mut touched = false;
            for _ in 0..frames {
                app.update();
                touched |= !app.world().resource::<Coupling>().impulses.is_empty();
            }
            assert!(touched, "{integrator}: the ball never reached the box");
            let after = particle_momentum(&app) + body_velocity(&app, body);
            let drift = (after - before).length() / before.length();
            let (box_v, ball_v) = (body_velocity(&app, body), particle_momentum(&app));
            println!(
                "{integrator}, ball {ball}: momentum drift {drift:.1e}, box {box_v}, ball {ball_v}"
            );
            if ball && integrator == Integrator::Bdf2 {
                assert!(
                    after.x < before.x && after.x > 0.7 * before.x,
                    "{integrator}: momentum {before} -> {after}"
                );
            } else {
                assert!(drift < 1e-5, "{integrator}: momentum {before} -> {after}");
            }
        }
    }
}

/// A ring of 12 particles of `mass` kg in all, 52 mm apart, filled with gas, moving at `v`,
/// with an edge's middle rightmost.
fn gas_ring(world: &mut World, centre: DVec2, mass: f64, v: DVec2) -> Vec<Entity> {
    let (n, radius) = (12, 0.1);
    let rim: Vec<Entity> = (0..n)
        .map(|k| {
            let angle = (k as f64 + 0.5) * std::f64::consts::TAU / n as f64;
            let at = centre + DVec2::from_angle(angle) * radius;
            let m = ParticleMass(mass / n as f64);
            world
                .spawn((Particle, ParticlePosition(at), ParticleVelocity(v), m))
                .id()
        })
        .collect();
    let side = 2.0 * radius * (std::f64::consts::PI / n as f64).sin();
    for k in 0..n {
        let spring = Spring::new(rim[k], rim[(k + 1) % n], side, 2e3);
        world.spawn((spring, Dashpot(2.0)));
    }
    world.spawn(hooke::sim::PressureBody {
        particles: rim.clone(),
        nrt: 5.0,
    });
    rim
}

/// A 1 kg gas ring thrown at a 1 kg box standing on its corner, which points between two of the
/// ring's particles, bodies colliding by their outlines: the corner pushes the ring's edge and
/// the edge the box, so the box never enters the ring and the momentum is kept to 1e-5 under
/// every integrator (VBD at 200 iterations, as in [`a_head_on_impact_keeps_the_momentum`]).
#[test]
fn a_box_corner_pushes_a_ring_by_its_outline() {
    for (integrator, dt, frames) in EACH_METHOD_FOR_0_8_S {
        let mut app = coupled(integrator, dt, Vec2::ZERO);
        let mut params = app.world_mut().resource_mut::<SimParams>();
        params.iterations.vbd = 200;
        if let Some(c) = params.contact.as_mut() {
            c.outlines = true;
        }
        let w = app.world_mut();
        gas_ring(w, DVec2::ZERO, 1.0, DVec2::new(1.0, 0.0));
        let (size, at) = (Vec2::splat(0.1), Vec2::new(0.25, 0.0));
        let body = dynamic_box(w, size, 1.0, at, 45f32.to_radians());
        run(&mut app, 2);
        let before = particle_momentum(&app) + body_velocity(&app, body);
        let (mut touched, mut inside) = (false, 0usize);
        for _ in 0..frames {
            app.update();
            touched |= !app.world().resource::<Coupling>().impulses.is_empty();
            // The box's left corner, within the ring's polygon?
            let at = app.world().get::<Position>(body).unwrap().0.as_dvec2();
            let turn = app.world().get::<Rotation>(body).unwrap().as_radians() as f64;
            let corner = at + DVec2::from_angle(turn).rotate(DVec2::new(-0.05, -0.05));
            let ring = app.world().resource::<Solver>().x();
            inside += common::inside(ring, corner) as usize;
        }
        assert!(touched, "{integrator}: the ring never reached the box");
        let after = particle_momentum(&app) + body_velocity(&app, body);
        let drift = (after - before).length() / before.length();
        let box_v = body_velocity(&app, body);
        println!("{integrator}: momentum drift {drift:.1e}, box {box_v}, {inside} frames inside");
        assert_eq!(inside, 0, "{integrator}: the box's corner entered the ring");
        assert!(
            box_v.x > 0.1,
            "{integrator}: the box was not pushed: {box_v}"
        );
        assert!(drift < 1e-5, "{integrator}: momentum {before} -> {after}");
    }
}

/// A particle hits a box off its centre: the box spins at (r × J)/I, J the impulse the particle
/// lost and r its arm from the box's centre of mass.
#[test]
fn an_off_centre_hit_spins_the_box() {
    let mut app = coupled(Integrator::SymplecticEuler, 1e-4, Vec2::ZERO);
    let w = app.world_mut();
    let v0 = DVec2::new(0.0, -2.0);
    let p = w
        .spawn((
            Particle,
            ParticlePosition(DVec2::new(0.15, 0.2)),
            ParticleVelocity(v0),
            ParticleMass(0.1),
        ))
        .id();
    let body = w
        .spawn((RigidBody::Dynamic, Collider::rectangle(0.4, 0.2), Mass(1.0)))
        .id();
    run(&mut app, 2);
    let inertia = app
        .world()
        .get::<ComputedAngularInertia>(body)
        .unwrap()
        .value() as f64;
    let mut hit = None;
    for _ in 0..2000 {
        let before = app.world().get::<ParticlePosition>(p).unwrap().0;
        app.update();
        if hit.is_none() && !app.world().resource::<Coupling>().impulses.is_empty() {
            hit = Some(before);
        }
    }
    let at = hit.expect("the particle hits the box");
    let v = app.world().get::<ParticleVelocity>(p).unwrap().0;
    let j = -(v - v0) * 0.1;
    // The arm to the contact point on the box's top face, from the centre of mass at rest.
    let r = DVec2::new(at.x, 0.1);
    let expected = r.perp_dot(j) / inertia;
    let spin = app.world().get::<AngularVelocity>(body).unwrap().0 as f64;
    println!("spin {spin} rad/s, expected {expected}, impulse {j}");
    assert!(j.y < -0.1, "the particle gave the box an impulse: {j}");
    assert!(
        ((spin - expected) / expected).abs() < 0.02,
        "spin {spin} against (r × J)/I = {expected}"
    );
}

/// A crate of mass M hangs still on a rope of n particles from a pin: spring j stretches by
/// (M + (n − j) m) g / k.
#[test]
fn a_crate_hangs_on_a_rope() {
    let (n, m, k, big_m, l) = (10usize, 0.02, 2e3, 1.0, 0.05);
    let mut app = coupled(
        Integrator::ImplicitEuler,
        1.0 / 120.0,
        Vec2::new(0.0, -9.81),
    );
    app.world_mut().resource_mut::<SimParams>().damping = 2.0;
    let w = app.world_mut();
    let crate_top = 1.0 - n as f64 * l;
    let body = w
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(0.1, 0.1),
            Mass(big_m as f32),
            LinearDamping(1.0),
            AngularDamping(1.0),
            Position(Vec2::new(0.5, crate_top as f32 - 0.05)),
        ))
        .id();
    let rope: Vec<Entity> = (0..=n)
        .map(|j| {
            let at = DVec2::new(0.5, 1.0 - j as f64 * l);
            let mut e = w.spawn((Particle, ParticlePosition(at), ParticleMass(m)));
            if j == 0 {
                e.insert(Pinned);
            }
            if j == n {
                e.insert(Attachment {
                    body,
                    anchor: Vec2::new(0.0, 0.05),
                });
            }
            e.id()
        })
        .collect();
    for j in 1..=n {
        w.spawn(Spring::new(rope[j - 1], rope[j], l, k));
    }
    run(&mut app, 1100);
    let before = app.world().get::<Position>(body).unwrap().0;
    run(&mut app, 100);
    let s = app.world().resource::<Solver>();
    let g = 9.81f32 as f64;
    for j in 1..=n {
        let stretch = (s.x()[j] - s.x()[j - 1]).length() - l;
        let expected = (big_m + (n - j) as f64 * m) * g / k;
        assert!(
            ((stretch - expected) / expected).abs() < 0.01,
            "spring {j}: stretch {stretch}, expected {expected}"
        );
    }
    // Still: avian's stored velocity at rest is not 0 (the pull comes as an impulse at the
    // step's start, gravity over its substeps), so its place is what is checked.
    let moved = app.world().get::<Position>(body).unwrap().0 - before;
    assert!(
        moved.length() < 1e-5,
        "the crate still moves: {moved} in 100 steps"
    );
}

/// A pinned strip of cloth, `columns` wide and two rows deep, its ends pinned, at height `y`.
fn trampoline(world: &mut World, columns: usize, y: f64, mass: f64, k: f64) -> Vec<Entity> {
    let (width, rows) = (1.0, 2);
    let dx = width / (columns - 1) as f64;
    let mut grid = vec![];
    for r in 0..rows {
        for c in 0..columns {
            let at = DVec2::new(c as f64 * dx, y - r as f64 * dx);
            let mut e = world.spawn((Particle, ParticlePosition(at), ParticleMass(mass)));
            if c == 0 || c == columns - 1 {
                e.insert(Pinned);
            }
            grid.push(e.id());
        }
    }
    let id = |r: usize, c: usize| grid[r * columns + c];
    for r in 0..rows {
        for c in 0..columns {
            if c + 1 < columns {
                world.spawn(Spring::new(id(r, c), id(r, c + 1), dx, k));
            }
            if r + 1 < rows {
                world.spawn(Spring::new(id(r, c), id(r + 1, c), dx, k));
                if c + 1 < columns {
                    let d = dx * std::f64::consts::SQRT_2;
                    world.spawn(Spring::new(id(r, c), id(r + 1, c + 1), d, k));
                    world.spawn(Spring::new(id(r + 1, c), id(r, c + 1), d, k));
                }
            }
        }
    }
    grid
}

/// A box dropped on a pinned cloth comes to rest on it, and the cloth carries its weight: the
/// contacts' impulses over a second sum to M g. Under XPBD at 1/60 s with the box damped
/// (avian's `LinearDamping` and `AngularDamping` of 2/s), and under VBD, which moves the body
/// inside its solve, at 1/30 s undamped: avian's substeps leave a resting body moving at
/// (n − 1)/(2n) g h, which its damping takes a share of each step, so that what holds a damped
/// box still is more than M g (1.0 % more at 1/30 s; 0.5 % at 1/60 s).
#[test]
fn a_trampoline_carries_a_box() {
    for (integrator, dt, damping) in [
        (Integrator::Xpbd, 1.0 / 60.0, 2.0),
        (Integrator::Vbd, 1.0 / 30.0, 0.0),
    ] {
        trampoline_carries_a_box(integrator, dt, damping);
    }
}

fn trampoline_carries_a_box(integrator: Integrator, dt: f64, damping: f32) {
    let mut app = coupled(integrator, dt, Vec2::new(0.0, -9.81));
    app.world_mut().resource_mut::<SimParams>().damping = 5.0;
    let w = app.world_mut();
    trampoline(w, 41, 0.5, 0.01, 1e4);
    let big_m = 0.5;
    let body = w
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(0.2, 0.1),
            Mass(big_m),
            LinearDamping(damping),
            AngularDamping(damping),
            Position(Vec2::new(0.5, 0.62)),
        ))
        .id();
    run(&mut app, (10.0 / dt).round() as usize);
    let mut total = Vec2::ZERO;
    for _ in 0..(1.0 / dt).round() as usize {
        app.update();
        for (e, j) in &app.world().resource::<Coupling>().impulses {
            if *e == body {
                total += *j;
            }
        }
    }
    let weight = big_m as f64 * 9.81f32 as f64;
    let carried = total.y as f64;
    println!("{integrator}: carried {carried} N·s over 1 s against M g = {weight}");
    assert!(
        ((carried - weight) / weight).abs() < 0.01,
        "{integrator}: carried {carried}, weight {weight}"
    );
    let y = app.world().get::<Position>(body).unwrap().0.y;
    assert!(y < 0.6 && y > 0.3, "the box rests on the cloth: y = {y}");
}

/// A mass ratio of 1000:1: a 10 kg box dropped on a strip of cloth of 10 g in all, at a
/// frame's step. Nothing goes non-finite and the box never passes through: every particle under
/// it stays below its bottom face (to the radius and a step of the box's travel, which the
/// particles meet a step late). Returns how far the worst particle got above the face, m, and
/// where the box ended.
fn heavy_box_on_light_cloth(integrator: Integrator) -> (f64, f32) {
    let dt = 1.0 / 60.0;
    let mut app = coupled(integrator, dt, Vec2::new(0.0, -9.81));
    app.world_mut().resource_mut::<SimParams>().damping = 5.0;
    let w = app.world_mut();
    let (columns, cloth) = (21, 0.010);
    trampoline(w, columns, 0.5, cloth / (2 * columns) as f64, 1e4);
    let body = w
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(0.2, 0.1),
            Mass(10.0),
            Position(Vec2::new(0.5, 0.6)),
        ))
        .id();
    let mut worst: f64 = f64::NEG_INFINITY;
    for _ in 0..300 {
        app.update();
        let s = app.world().resource::<Solver>();
        let at = app.world().get::<Position>(body).unwrap().0.as_dvec2();
        let bottom = at.y - 0.05;
        assert!(
            bottom.is_finite() && s.x().iter().all(|p| p.is_finite()),
            "{integrator}: not finite"
        );
        let lag = body_velocity(&app, body).length() * dt;
        for p in s.x() {
            if (p.x - at.x).abs() < 0.08 {
                worst = worst.max(p.y - (bottom + lag));
            }
        }
    }
    let y = app.world().get::<Position>(body).unwrap().0.y;
    println!(
        "{integrator}: a particle at most {worst:.4} m above the box's bottom; the box at y = {y}"
    );
    (worst, y)
}

/// VBD holds the 1000:1 box: its contact force is its block's Hessian times the push, which
/// carries the springs' stiffness, not only the particle's mass.
#[test]
fn a_heavy_box_on_a_light_cloth_stays_above_it() {
    let (worst, y) = heavy_box_on_light_cloth(Integrator::Vbd);
    assert!(
        worst < 0.005 + 1e-3 && y > 0.2,
        "a particle {worst} m inside the box, the box at y = {y}"
    );
}

/// The other large-step methods let the 1000:1 box through: their contact's push carries only
/// what the light particle's mass moves in a step (XPBD's m δ/hₛ; projective dynamics', implicit
/// Euler's and BDF2's learned force, at most 4 m δ/ĥ² an iteration), far less than the cloth's
/// springs would give.
#[test]
#[ignore = "not met: XPBD, projective dynamics, implicit Euler and BDF2 let it through (docs/library.md)"]
fn a_heavy_box_on_a_light_cloth_stays_above_it_under_every_method() {
    for integrator in [
        Integrator::Xpbd,
        Integrator::ProjectiveDynamics,
        Integrator::ImplicitEuler,
        Integrator::Bdf2,
    ] {
        let (worst, y) = heavy_box_on_light_cloth(integrator);
        assert!(
            worst < 0.005 + 1e-3 && y > 0.2,
            "{integrator}: a particle {worst} m inside the box, the box at y = {y}"
        );
    }
}

/// A static avian circle moves a falling cloth exactly as hooke's own circle of the same size
/// and place does, to avian's f32 pose.
#[test]
fn an_avian_circle_is_a_native_circle() {
    let build = |app: &mut App| {
        let w = app.world_mut();
        for r in 0..6 {
            for c in 0..6 {
                let at = DVec2::new(0.4 + 0.04 * c as f64, 0.5 - 0.04 * r as f64);
                w.spawn((Particle, ParticlePosition(at)));
            }
        }
    };
    let dt = 1.0 / 120.0;
    let mut avian = coupled(Integrator::Xpbd, dt, Vec2::new(0.0, -9.81));
    build(&mut avian);
    avian.world_mut().spawn((
        RigidBody::Static,
        Collider::circle(0.1),
        Position(Vec2::new(0.5, 0.2)),
    ));
    let mut native = hooke::headless_app();
    frame(&mut native, Integrator::Xpbd, dt);
    native.world_mut().resource_mut::<SimParams>().gravity = DVec2::new(0.0, -9.81);
    native
        .world_mut()
        .resource_mut::<hooke::sim::TickPlan>()
        .target_tick_seconds = dt;
    build(&mut native);
    native.world_mut().spawn((
        Obstacle(hooke::solver::Shape::Circle { radius: 0.1 }),
        ObstaclePose {
            center: DVec2::new(0.5, 0.2),
            angle: 0.0,
        },
    ));
    let (mut worst, mut touching): (f64, usize) = (0.0, 0);
    for _ in 0..120 {
        avian.update();
        native.update();
        let (a, b) = (
            avian.world().resource::<Solver>(),
            native.world().resource::<Solver>(),
        );
        for (p, q) in a.x().iter().zip(b.x()) {
            worst = worst.max((*p - *q).length());
        }
        let contacts = avian
            .world()
            .resource::<hooke::sim::Obstacles>()
            .contacts
            .surfaces;
        touching = touching.max(contacts);
    }
    println!("largest difference {worst:.1e} m, {touching} contacts");
    assert!(touching > 0, "the cloth reached the circle");
    assert!(worst < 1e-6, "avian's circle and hooke's part by {worst} m");
}

/// hooke's steps and avian's are the same count after any number of frames, and pausing hooke
/// pauses both.
#[test]
fn the_two_clocks_step_together() {
    let mut app = coupled(Integrator::Xpbd, 1.0 / 60.0, Vec2::new(0.0, -9.81));
    let w = app.world_mut();
    soft_ball(w, DVec2::new(0.5, 0.8), 0.05, 0.2, DVec2::ZERO);
    w.spawn((
        RigidBody::Dynamic,
        Collider::circle(0.05),
        Position(Vec2::new(0.5, 0.5)),
    ));
    let count = |app: &App| {
        (
            app.world().resource::<SimClock>().steps,
            // avian's clock advances by its step only when it steps.
            (app.world().resource::<Time<Physics>>().elapsed_secs_f64() * 60.0).round() as u64,
        )
    };
    run(&mut app, 37);
    let (hooke_steps, avian_steps) = count(&app);
    assert!(hooke_steps > 30, "{hooke_steps}");
    assert_eq!(hooke_steps, avian_steps);
    app.world_mut().resource_mut::<SimParams>().paused = true;
    run(&mut app, 10);
    assert_eq!(
        count(&app),
        (hooke_steps, avian_steps),
        "paused, neither steps"
    );
    app.world_mut().resource_mut::<SimParams>().paused = false;
    run(&mut app, 23);
    let (h, a) = count(&app);
    assert_eq!(h, a);
    assert!(h > hooke_steps + 15);
}

/// With restitution 0, a 1 kg particle and the 1 kg box it hits leave together at half its
/// speed.
#[test]
fn an_inelastic_impact_leaves_together() {
    let mut app = coupled(Integrator::SymplecticEuler, 1e-4, Vec2::ZERO);
    let w = app.world_mut();
    let p = one_kg_particle(w);
    let body = one_kg_box(w);
    run(&mut app, 3000);
    let v = app.world().get::<ParticleVelocity>(p).unwrap().0.x;
    let u = body_velocity(&app, body).x;
    assert!(
        (v - 0.5).abs() < 0.01 && (u - 0.5).abs() < 0.01,
        "particle {v} m/s, box {u} m/s"
    );
}

/// The shipped `crates` scene: its rigid bodies load as avian's, run coupled by the runner's
/// `advance` (a tick a step), fall into the net and rest in it, held at the net's stiffness,
/// and save back as they are.
#[test]
fn a_scene_with_bodies_runs_rests_and_saves_back() {
    use hooke::scene::{LoadedScene, load_into_world, snapshot, to_ron};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/crates.ron");
    let loaded = LoadedScene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut app = hooke::running_app(&loaded).unwrap();
    // The bodies' heights: the dynamic ones by entity, then the fixed one.
    let heights = |app: &mut App| -> Vec<f32> {
        let w = app.world_mut();
        let mut all: Vec<(bool, Entity, f32)> = w
            .query::<(Entity, &RigidBody, &Position)>()
            .iter(w)
            .map(|(e, kind, p)| (kind.is_static(), e, p.0.y))
            .collect();
        all.sort_by_key(|(fixed, e, _)| (*fixed, *e));
        all.into_iter().map(|(.., y)| y).collect()
    };
    let start = heights(&mut app);
    assert_eq!(start.len(), 4);
    let taken = hooke::sim::advance(app.world_mut(), 960);
    assert_eq!(taken, 960);
    let rest = heights(&mut app);
    // The three falling bodies came down into the net (its ends hang at 0.4 m) and rest there,
    // above the ground body's top (0.1 m); the ground body stays.
    for (k, (a, b)) in start.iter().zip(&rest).enumerate().take(3) {
        assert!(b < a && *b > 0.3, "body {k}: {a} -> {b}");
    }
    assert_eq!(rest[3], start[3]);
    // The net carries them at its stiffness: the panel shows no amber line (at one sweep a
    // substep, without the scene's tolerance, its springs carried 78 % of k's force).
    let solve = app.world().resource::<Solver>().solve_stats();
    let soft = hooke::readable::xpbd_softness(&solve);
    assert!(soft.is_none(), "{soft:?}");
    let before = rest;
    hooke::sim::advance(app.world_mut(), 240);
    let after = heights(&mut app);
    for (a, b) in before.iter().zip(&after) {
        assert!((a - b).abs() < 0.01, "still moving: {a} -> {b}");
    }
    // Saved and loaded back: the same bodies, where they were, moving as they moved.
    let saved = snapshot(app.world_mut());
    assert_eq!(saved.bodies.len(), 4);
    let text = to_ron(&saved).unwrap();
    let back = LoadedScene::parse(&text, std::path::Path::new("saved.ron")).unwrap();
    assert_eq!(back.scene.bodies, saved.bodies);
    let mut again = hooke::headless_app();
    load_into_world(again.world_mut(), &back);
    assert_eq!(heights(&mut again), after);
}

/// A dt that no clock holds (NaN, 0, 1e19 s over `MAX_DT`), written into a running world
/// with rigid bodies, pauses it with the field named and the bodies where they were, as a bad
/// dt does without them; avian's clock panicked at each before the check ran.
#[test]
fn a_step_no_clock_holds_pauses_with_its_name() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/crates.ron");
    let loaded = hooke::scene::LoadedScene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    for dt in [f64::NAN, 0.0, 1e19] {
        let mut app = hooke::running_app(&loaded).unwrap();
        hooke::sim::advance(app.world_mut(), 10);
        let w = app.world_mut();
        let bodies =
            |w: &mut World| -> Vec<Vec2> { w.query::<&Position>().iter(w).map(|p| p.0).collect() };
        let before = bodies(w);
        w.resource_mut::<SimParams>().dt = dt;
        assert_eq!(hooke::sim::advance(w, 10), 0, "dt {dt}");
        match *w.resource::<hooke::sim::SimStatus>() {
            hooke::sim::SimStatus::InvalidInput(p) => {
                assert_eq!(p.field, "SimParams.dt", "{p}");
            }
            other => panic!("dt {dt}: not paused on it: {other:?}"),
        }
        assert_eq!(bodies(w), before, "dt {dt}");
        // Mended, it runs on.
        w.resource_mut::<SimParams>().dt = loaded.scene.dt;
        w.resource_mut::<SimParams>().paused = false;
        assert_eq!(hooke::sim::advance(w, 10), 10, "dt {dt}: mended");
    }
}

/// A body's bad values and misspelled fields are named, with where they are.
#[test]
fn a_bad_body_is_named() {
    use hooke::scene::LoadedScene;
    let scene = |bodies: &str| {
        format!(
            "(gravity: (0.0, -9.8), damping: 0.0, ground: None, integrator: Xpbd, dt: 0.01, \
             bodies: [{bodies}])"
        )
    };
    let error = |bodies: &str| {
        LoadedScene::parse(&scene(bodies), std::path::Path::new("bad.ron"))
            .unwrap_err()
            .to_string()
    };
    let e = error("(shape: Circle(center: (0.5, 0.5), radius: 0.1), mass: -1.0)");
    assert!(
        e.contains("bodies[0].mass: must be finite and > 0, got -1"),
        "{e}"
    );
    let e = error(
        "(shape: Circle(center: (0.5, 0.5), radius: 0.1)), (shape: Box(center: (0.0, 0.0), half: (0.0, 0.1)))",
    );
    assert!(e.contains("bodies[1].shape"), "{e}");
    let e = error("(shape: Circle(center: (0.5, 0.5), radius: 0.1), mas: 2.0)");
    assert!(e.contains("mas") && e.contains("mass"), "{e}");
    let e = error(
        "(shape: Polygon(center: (0.5, 0.5), corners: [(0.0, 0.0), (0.1, 0.0), (0.05, 0.01), (0.05, 0.1)]))",
    );
    assert!(e.contains("bodies[0].shape") && e.contains("convex"), "{e}");
}

/// The shipped `crates` under `integrator` at `dt` for 2 s through `hooke run`'s runner: the
/// run's report and each dynamic body's centre (x, y).
fn crates_run(integrator: Integrator, dt: f64) -> (hooke::runner::RunReport, Vec<(f32, f32)>) {
    use hooke::runner::{Duration, Overrides, run};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/crates.ron");
    let loaded = hooke::scene::LoadedScene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let overrides = Overrides {
        integrator: Some(integrator),
        dt: Some(dt),
        ..Default::default()
    };
    let mut done = run(&loaded, &overrides, Duration::Time(2.0)).unwrap();
    let w = done.app.world_mut();
    let mut bodies: Vec<(Entity, f32, f32)> = w
        .query::<(Entity, &RigidBody, &Position)>()
        .iter(w)
        .filter(|(_, kind, _)| kind.is_dynamic())
        .map(|(e, _, p)| (e, p.0.x, p.0.y))
        .collect();
    bodies.sort_by_key(|b| b.0);
    (
        done.report,
        bodies.into_iter().map(|(_, x, y)| (x, y)).collect(),
    )
}

/// A run's total energy is the whole world's: the rigid bodies' too (kinetic, turning and in
/// gravity). At the start the `crates` hold 0.5 kg at 0.6 m, 0.4 kg at 0.7 m and 0.3 kg at
/// 0.6 m above the particles' energy: 7.448 J in g = 9.8. Counted without them, a crate thrown
/// out of its net took its energy out of the figures.
#[test]
fn a_runs_energy_counts_the_rigid_bodies() {
    use hooke::runner::{Duration, run};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/crates.ron");
    let loaded = hooke::scene::LoadedScene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let done = run(&loaded, &Default::default(), Duration::Steps(0)).unwrap();
    let particles = done.solver().energy(DVec2::new(0.0, -9.8)).total();
    let bodies = done.report.energy_start - particles;
    assert!((bodies - 7.448).abs() < 1e-4, "bodies' energy {bodies} J");
    assert_eq!(done.report.energy_end, done.report.energy_start);
}

/// The `crates` under each of `integrators` at `dt`: the crates land in the net and stay in it
/// (their centres between 0.3 and 0.5 m high, over the net's span), and the whole world's
/// energy, the crates' with the particles', never rises more than 5 % above its start (the
/// coupling is explicit: each engine meets the other's state of the step before).
fn crates_rest_in_the_net(integrators: &[Integrator], dt: f64) {
    for &integrator in integrators {
        let (report, bodies) = crates_run(integrator, dt);
        assert_eq!(bodies.len(), 3);
        for (k, &(x, y)) in bodies.iter().enumerate() {
            assert!(
                (0.1..0.9).contains(&x) && (0.3..0.5).contains(&y),
                "{integrator:?}: body {k} at ({x}, {y})"
            );
        }
        assert!(
            report.energy_max <= 1.05 * report.energy_start,
            "{integrator:?}: {} J from {} J",
            report.energy_max,
            report.energy_start
        );
    }
}

/// At the scene's own step, 1/240 s, under every large-step method.
#[test]
fn the_crates_rest_in_the_net_under_every_large_step_method() {
    use Integrator::*;
    crates_rest_in_the_net(
        &[ImplicitEuler, ProjectiveDynamics, Xpbd, Vbd, Bdf2],
        1.0 / 240.0,
    );
}

/// At a frame's step, 1/60 s, under XPBD (its substeps exchange the impulses in small steps),
/// implicit Euler (its line search sizes the contact forces by how the whole net answers
/// them; learned particle by particle they threw the ball out of the net and let a crate
/// through it) and VBD (the bodies among its unknowns).
#[test]
fn the_crates_rest_in_the_net_at_a_frames_step_under_xpbd_implicit_euler_and_vbd() {
    use Integrator::*;
    crates_rest_in_the_net(&[Xpbd, ImplicitEuler, Vbd], 1.0 / 60.0);
}

/// VBD moves the bodies inside its solve (`solver::contact::solved`), and holds the crates up
/// to 1/15 s, the largest step it was measured to (coupled from outside the solve, it threw
/// them out of the net past 1/240 s; XPBD loses them at 1/20 s).
#[test]
fn vbd_holds_the_crates_in_the_net_up_to_a_fifteenth_of_a_second() {
    for dt in [1.0 / 30.0, 1.0 / 15.0] {
        crates_rest_in_the_net(&[Integrator::Vbd], dt);
    }
}

/// At 1/60 s under the other large-step methods: projective dynamics and BDF2 throw crates
/// out of the net (docs/library.md, the explicit coupling).
#[test]
#[ignore = "not met: projective dynamics and BDF2 throw the crates out at 1/60 s (docs/library.md)"]
fn the_crates_rest_in_the_net_at_a_frames_step() {
    use Integrator::*;
    crates_rest_in_the_net(&[ProjectiveDynamics, Bdf2], 1.0 / 60.0);
}

/// Where a 0.5 kg box dropped on a net of 10 g particles (k = 2·10⁴ N/m, pinned at its ends)
/// rests after 10 s under VBD at `dt`: its height, m, and its turn, rad.
fn box_in_a_net_under_vbd(dt: f64) -> (f32, f32) {
    let mut app = coupled(Integrator::Vbd, dt, Vec2::new(0.0, -9.8));
    app.world_mut().resource_mut::<SimParams>().damping = 1.0;
    let w = app.world_mut();
    trampoline(w, 41, 0.5, 0.01, 2e4);
    let body = dynamic_box(w, Vec2::new(0.12, 0.08), 0.5, Vec2::new(0.5, 0.6), 0.0);
    run(&mut app, (10.0 / dt).round() as usize);
    let w = app.world();
    let (at, turn) = (
        w.get::<Position>(body).unwrap(),
        w.get::<Rotation>(body).unwrap(),
    );
    (at.0.y, turn.as_radians())
}

/// VBD at a frame's step rests a box in a net where it rests at a small step: within 1 cm and
/// 0.01 rad at 1/30 s of where it rests at 1/240 s (its 10 iterations a step reach the rest
/// over the steps: 1.1 cm above it after 4 s). The body starts each step's descent where
/// the step began and ends it where the particles were last kept out of it; started where its
/// engine alone would take it (a step of gravity into the net), it pushed the net a little
/// further down each step and rested 11 cm too low at 1/30 s, the net stretched to twice its
/// energy; with the contact pass meeting it at the velocity avian had rather than the solve's,
/// the pass's impulses turned it by ±1° a step.
#[test]
fn vbd_rests_a_box_in_a_net_at_a_frames_step_where_it_rests_at_a_small_one() {
    let (small, small_turn) = box_in_a_net_under_vbd(1.0 / 240.0);
    let (frame, frame_turn) = box_in_a_net_under_vbd(1.0 / 30.0);
    println!(
        "at 1/240 s: y {small} m, turn {small_turn}; at 1/30 s: y {frame} m, turn {frame_turn}"
    );
    assert!(
        (frame - small).abs() < 0.01,
        "{frame} m at 1/30 s, {small} m at 1/240 s"
    );
    assert!(frame_turn.abs() < 0.01, "turned {frame_turn} rad at 1/30 s");
}

/// Under VBD each body ends its step where the solve left it: where hooke moved its obstacle
/// by the end of the step (the solve's motion, after the contact pass) and where avian's own
/// step put it agree to 0.1 mm and 1e-4 rad, tick by tick, while a box with friction lands on
/// a trampoline at 1/30 s and comes to rest. Met by the contact pass meeting the body moving as
/// the solve moved it (`Workspace::solved_motion`); meeting it at avian's velocity, the pass's
/// own impulses moved it elsewhere.
#[test]
fn vbd_and_avian_agree_where_each_body_ends_its_step() {
    let dt = 1.0 / 30.0;
    let mut app = coupled(Integrator::Vbd, dt, Vec2::new(0.0, -9.8));
    {
        let mut p = app.world_mut().resource_mut::<SimParams>();
        p.damping = 1.0;
        p.contact = Some(ContactSettings {
            radius: 0.005,
            friction: 0.5,
            ..ContactSettings::default()
        });
    }
    let w = app.world_mut();
    trampoline(w, 41, 0.5, 0.01, 2e4);
    let body = dynamic_box(w, Vec2::new(0.12, 0.08), 0.5, Vec2::new(0.45, 0.6), 0.3);
    let (mut worst, mut worst_turn, mut touched) = (0.0f64, 0.0f64, 0);
    for _ in 0..90 {
        app.update();
        let w = app.world();
        let obstacles = w.resource::<hooke::sim::obstacles::Obstacles>();
        let Some(k) = obstacles.entities().iter().position(|e| *e == body) else {
            continue;
        };
        touched += 1;
        let solved = obstacles.placed()[k].pose;
        let at = w.get::<Position>(body).unwrap().0.as_dvec2();
        let turn = w.get::<Rotation>(body).unwrap().as_radians() as f64;
        worst = worst.max((solved.center - at).length());
        worst_turn = worst_turn.max((solved.angle - turn).abs());
    }
    println!("over {touched} ticks: {worst:.2e} m, {worst_turn:.2e} rad apart at most");
    assert!(touched > 30, "the box met the net in {touched} ticks");
    assert!(worst < 1e-4, "hooke and avian put the box {worst} m apart");
    assert!(
        worst_turn < 1e-4,
        "hooke and avian turned the box {worst_turn} rad apart"
    );
}
