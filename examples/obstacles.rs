//! A kinematic obstacle moved by a system of your own: a cloth strip lies on a platform, and a
//! system sets the platform's velocity, which carries the strip along by friction.
//!
//! `cargo run --example obstacles`

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::scene::{Generator, LoadedScene, Pin, Scene, load_into_world};
use hooke::sim::{
    ContactSettings, Integrator, Obstacle, ObstaclePose, ObstacleVelocity, PhysicsSystems,
    SimClock, SimParams, Solver, advance,
};
use hooke::solver::Shape;

/// The platform: a box obstacle.
#[derive(Component)]
struct Platform;

/// Moves the platform right at 0.2 m/s for the first second, then stops it. Runs before the
/// tick's steps, so that they see the new velocity.
fn drive(clock: Res<SimClock>, mut platforms: Query<&mut ObstacleVelocity, With<Platform>>) {
    for mut v in &mut platforms {
        v.linear = if clock.time < 1.0 {
            DVec2::new(0.2, 0.0)
        } else {
            DVec2::ZERO
        };
    }
}

fn main() {
    // A strip of cloth just above where the platform's top will be, with friction 0.8.
    let scene = Scene {
        gravity: (0.0, -9.8),
        damping: 5.0,
        ground: None,
        integrator: Integrator::SymplecticEuler,
        dt: 1e-4,
        generate: vec![Generator::Grid {
            cols: 24,
            rows: 2,
            min: (0.2, 0.305),
            max: (0.5, 0.32),
            mass: 0.02,
            stiffness: 1e4,
            shear: true,
            pin: Pin::None,
            vel: (0.0, 0.0),
            damping: None,
            plastic: None,
        }],
        contact: Some(ContactSettings {
            radius: 0.005,
            friction: 0.8,
            restitution: 0.0,
            particles: false,
            outlines: false,
        }),
        ..Default::default()
    };
    let loaded = LoadedScene::from_scene(scene, None).expect("a valid scene");

    let mut app = hooke::headless_app();
    app.add_systems(FixedUpdate, drive.before(PhysicsSystems::Prepare));
    let world = app.world_mut();
    load_into_world(world, &loaded);
    world.resource_mut::<SimParams>().paused = false;
    // The platform, its top at y = 0.3: an entity like any other.
    world.spawn((
        Platform,
        Obstacle(Shape::Box {
            half: DVec2::new(0.3, 0.05),
        }),
        ObstaclePose {
            center: DVec2::new(0.35, 0.25),
            angle: 0.0,
        },
    ));

    // Pack the entities into the solver now, to read the state before the first step.
    hooke::sim::pack(world).expect("a SimPlugin world");
    let mean_x = |world: &World| {
        let x = world.resource::<Solver>().x();
        x.iter().map(|p| p.x).sum::<f64>() / x.len() as f64
    };
    for tenth in 0..=15 {
        if tenth > 0 {
            advance(app.world_mut(), 1_000);
        }
        let world = app.world_mut();
        let platform = world
            .query_filtered::<&ObstaclePose, With<Platform>>()
            .single(world)
            .expect("one platform");
        println!(
            "t = {:.1} s: platform at x = {:.4} m, the strip's centre at x = {:.4} m",
            tenth as f64 / 10.0,
            platform.center.x,
            mean_x(world)
        );
    }
}
