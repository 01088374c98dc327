//! Helpers shared by the headless tests.
#![allow(dead_code)]

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::scene::{Generator, LoadedScene, ParticleDef, Pin, Scene, SpringDef, load_into_world};
use hooke::sim::{self, ContactSettings, Integrator, Solver};

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

/// A shipped or shown scene, loaded; `None` where this build has no rigid bodies and the
/// scene has some: such a build refuses it, naming the feature it lacks, which is checked here
/// (`cargo test --no-default-features` runs the rest).
pub fn unless_it_needs_avian(
    loaded: Result<LoadedScene, hooke::scene::SceneError>,
    name: &str,
) -> Option<LoadedScene> {
    match loaded {
        Err(e) if !cfg!(feature = "avian") && e.to_string().contains("`avian` feature") => None,
        loaded => Some(loaded.unwrap_or_else(|e| panic!("{name}: {e}"))),
    }
}

pub fn step(app: &mut App, steps: u64) {
    let taken = sim::advance(app.world_mut(), steps);
    assert_eq!(taken, steps, "the simulation stopped early");
}

pub fn solver(app: &App) -> &Solver {
    app.world().resource::<Solver>()
}

/// Steps `app` `steps` times, and fails if a step ends with more energy than the start (to
/// round-off, 1e-9 of it), naming `what` ran.
pub fn never_gains_energy(app: &mut App, what: impl std::fmt::Display, steps: u64) {
    let g = app.world().resource::<sim::SimParams>().gravity;
    let start = solver(app).energy(g).total();
    for n in 1..=steps {
        step(app, 1);
        let energy = solver(app).energy(g).total();
        assert!(
            energy <= start + 1e-9 * start.abs(),
            "{what}, dt {}: step {n} has {energy} J, more than the start's {start} J",
            app.world().resource::<sim::SimParams>().dt
        );
    }
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

/// Contact settings with particle pairs on.
pub fn pairs_on(radius: f64, friction: f64) -> Option<ContactSettings> {
    Some(ContactSettings {
        radius,
        friction,
        restitution: 0.0,
        particles: true,
        outlines: false,
    })
}

/// The pairs that springs join, each as (lower index, higher).
fn joined(solver: &Solver) -> std::collections::HashSet<(u32, u32)> {
    let springs = solver.state().springs().iter();
    springs.map(|s| (s.a.min(s.b), s.a.max(s.b))).collect()
}

/// The closest pair of particles that no spring joins, and its distance.
pub fn closest_unjoined(solver: &Solver) -> (f64, usize, usize) {
    let (x, joined) = (solver.x(), joined(solver));
    let mut best = (f64::INFINITY, 0, 0);
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let d = (x[i] - x[j]).length();
            if d < best.0 && !joined.contains(&(i as u32, j as u32)) {
                best = (d, i, j);
            }
        }
    }
    best
}

/// The pairs of particles that no spring joins closer than `within`: how many touch, read off
/// the state (not off a pass's count, which depends on where the method resolved them).
pub fn touching_unjoined(solver: &Solver, within: f64) -> usize {
    let (x, joined) = (solver.x(), joined(solver));
    let mut count = 0;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            if (x[i] - x[j]).length() < within && !joined.contains(&(i as u32, j as u32)) {
                count += 1;
            }
        }
    }
    count
}

/// A strip of cloth (2 × 96 particles, 0.9 m) standing on its foot just above the ground,
/// leaning a little so that it folds onto itself, with particle pairs on at a radius of 0.45
/// of its spacing; and that radius.
pub fn folding_strip(integrator: Integrator, dt: f64) -> (Scene, f64) {
    let (length, cols) = (0.9, 96);
    let d = length / (cols - 1) as f64;
    let r = 0.45 * d;
    let mut scene = bare_scene(integrator, dt);
    scene.gravity = (0.0, -9.8);
    scene.ground = Some(0.0);
    scene.damping = 1.0;
    scene.generate = vec![Generator::Grid {
        cols: 2,
        rows: cols,
        min: (0.5, r + 0.01),
        max: (0.5 + d, r + 0.01 + length),
        mass: 0.01,
        stiffness: 1e4,
        shear: true,
        pin: Pin::None,
        vel: (0.3, 0.0),
        damping: None,
        plastic: None,
    }];
    scene.contact = pairs_on(r, 0.3);
    (scene, r)
}

/// A soft box: a `n`×`n` grid with shear springs, `size` wide, its lower left corner at `at`.
pub fn soft_box(n: usize, size: f64, at: (f64, f64), k: f64) -> Generator {
    Generator::Grid {
        cols: n,
        rows: n,
        min: at,
        max: (at.0 + size, at.1 + size),
        // 0.25 kg a particle: heavier boxes of this stiffness are jelly (1 kg: the lower one
        // squashed by 37 % under the upper, which slid off it).
        mass: 0.25,
        stiffness: k,
        shear: true,
        pin: Pin::None,
        vel: (0.0, 0.0),
        damping: None,
        plastic: None,
    }
}

/// [`stacked_soft_boxes`]' boxes: particles a side, width, and the contact radius.
pub const STACKED_BOXES: (usize, f64, f64) = (6, 0.1, 0.009);

/// Two soft boxes ([`soft_box`], k = 1e4) on the ground, the upper dropped from 0.05 m above
/// the lower, with the app's damping (so that "at rest" asks the same of every method) and
/// particle pairs at the boxes' radius with friction 0.5.
pub fn stacked_soft_boxes(integrator: Integrator, dt: f64) -> Scene {
    let (n, size, r) = STACKED_BOXES;
    let mut scene = bare_scene(integrator, dt);
    scene.gravity = (0.0, -9.8);
    scene.ground = Some(0.0);
    scene.damping = 10.0;
    scene.generate = vec![
        soft_box(n, size, (0.30, r), 1e4),
        soft_box(n, size, (0.30, 0.15 + r), 1e4),
    ];
    scene.contact = pairs_on(r, 0.5);
    scene
}

/// Whether `p` lies inside the closed polygon `ring` (crossing number).
pub fn inside(ring: &[DVec2], p: DVec2) -> bool {
    let mut odd = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            odd = !odd;
        }
    }
    odd
}

/// The area where the gas's pressure balances the springs' tension, for a regular N-gon with
/// springs of rest length L₀ (the side at radius 0.1). With side s, area A = N s²/(4 tan(π/N))
/// and the energy N k (s − L₀)²/2 − nRT ln A is stationary where N k (s − L₀) = 2 nRT/s:
/// s = (L₀ + √(L₀² + 8 nRT/(N k)))/2.
pub fn balanced_area(segments: usize, k: f64, nrt: f64) -> f64 {
    use std::f64::consts::PI;
    let n = segments as f64;
    let l0 = 2.0 * 0.1 * (PI / n).sin();
    let s = 0.5 * (l0 + (l0 * l0 + 8.0 * nrt / (n * k)).sqrt());
    n * s * s / (4.0 * (PI / n).tan())
}

/// The area of the solver's first gas body.
pub fn ring_area(solver: &Solver) -> f64 {
    solver.materials().gas()[0].signed_area(solver.x()).abs()
}

/// How many of the signed areas in `start` have another sign in `end`: cells or triangles
/// turned inside out.
pub fn inverted(start: &[f64], end: &[f64]) -> usize {
    start
        .iter()
        .zip(end)
        .filter(|(a, b)| a.signum() != b.signum())
        .count()
}

/// The particles' kinetic energy, J.
pub fn kinetic(s: &Solver) -> f64 {
    (s.v().iter().zip(s.mass()))
        .map(|(v, m)| 0.5 * m * v.length_squared())
        .sum()
}

/// The plank of [`landing_on_a_plank`]: its level, m, and the contact radius r, m.
pub const PLANK: (f64, f64) = (0.5, 0.01);

/// A 10 g particle resting on a level plank of no thickness ([`PLANK`]: y = 0.5, r = 1 cm, pairs
/// on), and a 10 kg one 3 mm off its centre falling onto it at `speed`, placed so that a free
/// fall would end its first step `above` over the light one's centre; `None` where it would
/// start within 2r of the light one (the scene's check refuses such a start).
pub fn landing_on_a_plank(
    integrator: Integrator,
    dt: f64,
    speed: f64,
    above: f64,
) -> Option<Scene> {
    let (level, r) = PLANK;
    let start = level + r + above + speed * dt + 9.8 * dt * dt;
    if start - (level + r) < 2.05 * r {
        return None;
    }
    let mut scene = bare_scene(integrator, dt);
    scene.gravity = (0.0, -9.8);
    let mut light = particle(0.5, level + r, false);
    light.mass = 0.01;
    let mut heavy = particle(0.503, start, false);
    heavy.mass = 10.0;
    heavy.vel = (0.0, -speed);
    scene.particles = vec![light, heavy];
    scene.obstacles = vec![hooke::scene::ObstacleDef::Segment {
        a: (0.0, level),
        b: (1.0, level),
        thickness: 0.0,
    }];
    scene.contact = pairs_on(r, 0.5);
    Some(scene)
}

/// The plank of [`landing_on_a_plank`] made a slab r thick, its top at the plank's level: a
/// closed shape thinner than the pair solve's push of up to 3r.
pub fn plank_as_slab(scene: &mut Scene) {
    let (level, r) = PLANK;
    scene.obstacles = vec![hooke::scene::ObstacleDef::Box {
        center: (0.5, level - 0.5 * r),
        half: (0.5, 0.5 * r),
        angle: 0.0,
    }];
}
