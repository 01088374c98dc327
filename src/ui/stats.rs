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

/// The share of the app's time the stability estimate may take: one estimate is 60 Lanczos
/// products with the stiffness, milliseconds on a cloth of 16 k springs but over a second on one
/// of 4 M, where re-estimating every second (as the small scenes do) took a sixth of the CPU and
/// held every frame.
const ESTIMATE_SHARE: f64 = 0.05;

/// When the stability estimate was last made, for which shape, how long it took, and whether
/// the parameters changed since.
#[derive(Debug, Clone, Copy)]
pub struct LastEstimate {
    at: Instant,
    shape: (usize, usize),
    cost: f64,
    changed: bool,
}

impl LastEstimate {
    /// Whether to estimate again: every second, or less often where an estimate is dear (at
    /// most [`ESTIMATE_SHARE`] of the time), and sooner after a change of the parameters or the
    /// scene's shape (at once on small scenes; after four times the estimate's cost on big
    /// ones, so that dragging a slider over a huge cloth does not estimate every frame).
    fn due(&self, shape: (usize, usize), now: Instant) -> bool {
        let since = now.duration_since(self.at).as_secs_f64();
        let periodic = since > (self.cost / ESTIMATE_SHARE).max(1.0);
        let changed = self.changed || self.shape != shape;
        periodic || (changed && since > 4.0 * self.cost)
    }
}

/// Re-estimates the stability limit when the parameters or the scene's shape change, and
/// periodically (the linearisation follows the state), within [`ESTIMATE_SHARE`] of the time
/// on big scenes ([`LastEstimate::due`]).
pub fn estimate_stability(
    params: Res<SimParams>,
    solver: Res<Solver>,
    mut estimate: ResMut<Stability>,
    mut last: Local<Option<LastEstimate>>,
) {
    let shape = (solver.particle_count(), solver.spring_count());
    let now = Instant::now();
    let due = match &mut *last {
        None => true,
        Some(l) => {
            // Remembered until the estimate is made, which on a big scene can be frames later.
            l.changed |= params.is_changed();
            l.due(shape, now)
        }
    };
    if due {
        estimate.set_if_neq(Stability(stability::estimate(&solver, &params)));
        *last = Some(LastEstimate {
            at: now,
            shape,
            cost: now.elapsed().as_secs_f64(),
            changed: false,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_dear_estimate_is_made_less_often() {
        let at = Instant::now();
        let after = |s: f64| at + Duration::from_secs_f64(s);
        let cheap = LastEstimate {
            at,
            shape: (0, 0),
            cost: 0.002,
            changed: false,
        };
        let same = (0, 0);
        assert!(!cheap.due(same, after(0.5)) && cheap.due(same, after(1.01)));
        let changed = LastEstimate {
            changed: true,
            ..cheap
        };
        assert!(changed.due(same, after(0.01)), "a change on a small scene");
        assert!(
            cheap.due((1, 0), after(0.01)),
            "a new shape on a small scene"
        );
        let dear = LastEstimate { cost: 1.0, ..cheap };
        assert!(!dear.due(same, after(19.0)) && dear.due(same, after(20.5)));
        let dear_changed = LastEstimate {
            changed: true,
            ..dear
        };
        assert!(!dear_changed.due(same, after(3.0)) && dear_changed.due(same, after(4.5)));
    }
}
