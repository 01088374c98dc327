//! Live figures for the panel: steps per second and real-time factor, measured over the last
//! half second of wall time.

use crate::sim::{SimClock, SimParams, Solver, Stability, stability};
use bevy::prelude::*;
use std::time::Instant;

#[derive(Resource, Debug, Clone)]
pub struct LiveStats {
    pub steps_per_second: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    pub fps: f64,
    window_start: Instant,
    steps_at_start: u64,
    time_at_start: f64,
    frames: u32,
}

impl Default for LiveStats {
    fn default() -> Self {
        LiveStats {
            steps_per_second: 0.0,
            real_time_factor: 0.0,
            fps: 0.0,
            window_start: Instant::now(),
            steps_at_start: 0,
            time_at_start: 0.0,
            frames: 0,
        }
    }
}

pub fn measure(clock: Res<SimClock>, mut stats: ResMut<LiveStats>) {
    stats.frames += 1;
    let wall = stats.window_start.elapsed().as_secs_f64();
    if wall < 0.5 {
        return;
    }
    // A reset rewinds the clock: start a new window from it.
    let steps = clock.steps.saturating_sub(stats.steps_at_start);
    let sim = (clock.time - stats.time_at_start).max(0.0);
    stats.steps_per_second = steps as f64 / wall;
    stats.real_time_factor = sim / wall;
    stats.fps = stats.frames as f64 / wall;
    stats.window_start = Instant::now();
    stats.steps_at_start = clock.steps;
    stats.time_at_start = clock.time;
    stats.frames = 0;
}

/// Re-estimates the stability limit when the parameters or the scene's shape change, and
/// periodically (the linearisation follows the state): every second, and every second per
/// 50,000 springs on big scenes, where one estimate (60 Lanczos products) costs milliseconds.
pub fn estimate_stability(
    params: Res<SimParams>,
    solver: Res<Solver>,
    mut estimate: ResMut<Stability>,
    mut last: Local<Option<(Instant, usize, usize)>>,
) {
    let shape = (solver.particle_count(), solver.spring_count());
    let due = match *last {
        None => true,
        Some((t, n, s)) => {
            params.is_changed() || (n, s) != shape || t.elapsed().as_secs_f64() > 1.0
        }
    };
    if due {
        estimate.set_if_neq(Stability(stability::estimate(&solver, &params)));
        *last = Some((Instant::now(), shape.0, shape.1));
    }
}
