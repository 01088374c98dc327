//! Runs a scene through the ECS systems and records the state at checkpoints, timing only
//! the stepping.

use crate::scene::{LoadedScene, Scene};
use crate::sim::{self, SimStatus, Solver};
use bevy::math::DVec2;
use std::time::Instant;

/// Positions at evenly spaced checkpoints, the stepping's wall time, and whether every step
/// stayed finite.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Positions of every particle at each checkpoint.
    pub checkpoints: Vec<Vec<DVec2>>,
    /// Wall time of the stepping, s.
    pub wall_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// Whether every step stayed finite.
    pub finite: bool,
    /// What the iterative methods did.
    pub stats: crate::sim::SolveStats,
}

/// A run's start: the scene loaded and running, its steps, and an empty trajectory; an error
/// when dt does not divide `t_end` into a multiple of `checkpoints` steps.
fn start(
    scene: &Scene,
    t_end: f64,
    checkpoints: u64,
) -> Result<(bevy::app::App, u64, Trajectory), String> {
    let steps = (t_end / scene.dt).round() as u64;
    if steps == 0 || !steps.is_multiple_of(checkpoints) {
        return Err(format!(
            "dt = {} does not divide T = {t_end} into a multiple of {checkpoints} steps",
            scene.dt
        ));
    }
    let loaded = LoadedScene::from_scene(scene.clone(), None).map_err(|e| e.to_string())?;
    let app = crate::running_app(&loaded)?;
    let out = Trajectory {
        checkpoints: vec![],
        wall_s: 0.0,
        steps: 0,
        finite: true,
        stats: Default::default(),
    };
    Ok((app, steps, out))
}

/// Runs `scene` to time `t_end` in steps of the scene's dt, recording `checkpoints` states.
pub fn run(scene: &Scene, t_end: f64, checkpoints: u64) -> Result<Trajectory, String> {
    let (mut app, steps, mut out) = start(scene, t_end, checkpoints)?;
    let world = app.world_mut();
    for _ in 0..checkpoints {
        let start = Instant::now();
        let taken = sim::advance(world, steps / checkpoints);
        out.wall_s += start.elapsed().as_secs_f64();
        out.steps += taken;
        out.checkpoints.push(world.resource::<Solver>().x.clone());
        if *world.resource::<SimStatus>() != SimStatus::Running {
            out.finite = false;
            break;
        }
    }
    out.stats = world.resource::<Solver>().solve_stats();
    Ok(out)
}

/// [`run`] on the graphics card in `precision`: the state uploaded once, each checkpoint's
/// steps one submit, the positions read back at each checkpoint (the wall time includes the
/// read, which waits for the card). Fails when the card does not run the scene.
#[cfg(feature = "gpu")]
pub fn run_on_card(
    scene: &Scene,
    t_end: f64,
    checkpoints: u64,
    gpu: &crate::solver::gpu::Gpu,
    precision: crate::solver::gpu::Precision,
) -> Result<Trajectory, String> {
    let (mut app, steps, mut out) = start(scene, t_end, checkpoints)?;
    let world = app.world_mut();
    let mut card = sim::gpu::card_for(world, gpu, precision)?;
    let mut solver = world.resource_mut::<Solver>();
    for _ in 0..checkpoints {
        let start = Instant::now();
        card.run((steps / checkpoints) as u32);
        card.read_into(&mut solver).map_err(|e| e.to_string())?;
        out.wall_s += start.elapsed().as_secs_f64();
        out.steps += steps / checkpoints;
        out.checkpoints.push(solver.x.clone());
        if !solver.state_is_finite() {
            out.finite = false;
            break;
        }
    }
    Ok(out)
}

/// The largest distance of any particle from its reference position over all checkpoints;
/// infinite if the run blew up.
pub fn max_position_error(run: &Trajectory, reference: &[Vec<DVec2>]) -> f64 {
    if !run.finite || run.checkpoints.len() != reference.len() {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for (a, b) in run.checkpoints.iter().zip(reference) {
        for (p, q) in a.iter().zip(b) {
            worst = worst.max(p.distance(*q));
        }
    }
    if worst.is_finite() {
        worst
    } else {
        f64::INFINITY
    }
}
