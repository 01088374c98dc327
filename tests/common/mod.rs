//! Helpers shared by the headless tests.
#![allow(dead_code)]

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::scene::{LoadedScene, ParticleDef, Scene, SpringDef, load_into_world};
use hooke::sim::{self, Integrator, Solver};

/// A scene with no gravity, damping or ground: pure springs.
pub fn bare_scene(integrator: Integrator, dt: f64) -> Scene {
    Scene {
        gravity: (0.0, 0.0),
        damping: 0.0,
        ground: None,
        integrator,
        dt,
        ..Default::default()
    }
}

pub fn particle(x: f64, y: f64, pinned: bool) -> ParticleDef {
    ParticleDef {
        pos: (x, y),
        vel: (0.0, 0.0),
        mass: 1.0,
        pinned,
    }
}

pub fn spring(a: usize, b: usize, stiffness: f64, rest: f64) -> SpringDef {
    SpringDef::new(a, b, rest, stiffness)
}

/// A small 2D network under gravity: a pinned particle and three free ones of different
/// masses, six springs, released from a perturbed shape.
pub fn network(integrator: Integrator, dt: f64) -> Scene {
    let mut scene = bare_scene(integrator, dt);
    scene.gravity = (0.0, -9.8);
    let mut p = vec![
        particle(0.5, 0.9, true),
        particle(0.4, 0.7, false),
        particle(0.62, 0.72, false),
        particle(0.5, 0.5, false),
    ];
    p[2].mass = 2.0;
    p[3].mass = 0.5;
    scene.particles = p;
    scene.springs = [(0, 1), (0, 2), (1, 2), (1, 3), (2, 3), (0, 3)]
        .iter()
        .map(|&(a, b)| spring(a, b, 200.0, 0.2))
        .collect();
    scene
}

/// A headless app (MinimalPlugins + SimPlugin) with the scene loaded and running.
pub fn app_with(scene: Scene) -> App {
    let loaded = LoadedScene::from_scene(scene, None).expect("test scene is valid");
    let mut app = hooke::headless_app();
    load_into_world(app.world_mut(), &loaded);
    app.world_mut().resource_mut::<sim::SimParams>().paused = false;
    sim::pack(app.world_mut()).unwrap();
    app
}

pub fn step(app: &mut App, steps: u64) {
    let taken = sim::advance(app.world_mut(), steps);
    assert_eq!(taken, steps, "the simulation stopped early");
}

pub fn solver(app: &App) -> &Solver {
    app.world().resource::<Solver>()
}

pub fn pos(app: &App, i: usize) -> DVec2 {
    solver(app).x()[i]
}

pub fn vel(app: &App, i: usize) -> DVec2 {
    solver(app).v()[i]
}

/// The workspace's `shared/` folder (beside the project root), if present.
pub fn shared_dir() -> Option<std::path::PathBuf> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    p.is_dir().then_some(p)
}

/// Sets the iterative methods' counts.
pub fn set_iterations(app: &mut App, iterations: sim::Iterations) {
    app.world_mut().resource_mut::<sim::SimParams>().iterations = iterations;
}

/// The largest distance between two sets of points, m.
pub fn max_difference(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}
