//! How long a frame's ticks may run: each tick sized from dt to about
//! [`TickPlan::target_tick_seconds`] of simulated time ([`plan_tick`], before each frame's
//! fixed loop), cut to a share of the frame's wall-time allowance once steps are seen to be
//! slow, and the rest of a frame's simulated time dropped once the allowance is spent, so that
//! a slow scene slows down instead of freezing the window.

use super::inputs;
use super::params::{SimParams, TickPlan};
use bevy::prelude::*;
use bevy::time::Fixed;
use std::time::{Duration, Instant};

/// The wall-clock time fixed ticks may take in one frame. Past it the remaining simulated time
/// of the frame is dropped: the simulation slows down instead of the window freezing.
///
/// The allowance is at least `per_frame` and grows up to [`StepBudget::MAX_GROWTH`] times that
/// while the main thread would otherwise sit idle between frames (waiting for a slow renderer,
/// such as a software one): time the frame takes anyway goes to the simulation. When the
/// idle time goes, the allowance decays back to `per_frame`.
///
/// ```
/// # use hooke::sim::StepBudget;
/// # use std::time::Duration;
/// let mut app = hooke::headless_app();
/// app.world_mut().resource_mut::<StepBudget>().per_frame = Duration::from_millis(10);
/// ```
#[derive(Resource, Debug, Clone, Copy)]
pub struct StepBudget {
    /// The allowance a frame starts with.
    pub per_frame: Duration,
    /// The current allowance.
    pub allowance: Duration,
    frame_start: Option<Instant>,
    frame_end: Option<Instant>,
    /// Simulated seconds dropped so far because the budget ran out.
    pub dropped_seconds: f64,
    /// The wall time a step has taken lately (a moving average over the ticks), s.
    step_seconds: Option<f64>,
}

impl StepBudget {
    /// How far the allowance may grow, as a multiple of `per_frame`.
    pub const MAX_GROWTH: u32 = 4;

    /// The share of the allowance one tick may take. The budget is checked between ticks, so
    /// a tick of a method that is slow at this dt (projective dynamics at 1e-4 s: 83 steps of
    /// 2–3 ms under a software renderer) would hold a frame for its whole length, and the app
    /// drew 3–5 frames a second; a tick is cut to fit instead (at least one step).
    pub const TICK_SHARE: f64 = 0.5;

    /// The wall time a step has taken lately, s (`None` before the first tick).
    pub fn step_seconds(&self) -> Option<f64> {
        self.step_seconds
    }

    /// Notes that `steps` steps took `wall`.
    pub(crate) fn note_steps(&mut self, wall: Duration, steps: u64) {
        if steps == 0 {
            return;
        }
        let per_step = wall.as_secs_f64() / steps as f64;
        self.step_seconds = Some(match self.step_seconds {
            Some(s) => 0.7 * s + 0.3 * per_step,
            None => per_step,
        });
    }

    /// How many steps of a tick fit its share of the allowance, from the recent step time.
    fn steps_that_fit(&self) -> Option<u32> {
        let cost = self.step_seconds.filter(|c| *c > 0.0)?;
        let fit = self.allowance.as_secs_f64() * Self::TICK_SHARE / cost;
        Some(fit.clamp(1.0, u32::MAX as f64) as u32)
    }

    /// Follows the idle time between the last frame's end and this frame's start:
    /// a = 0.9 a + 0.8 idle, within [per_frame, MAX_GROWTH · per_frame]. When the renderer sets
    /// the pace (frame time R, other main-thread work o) this settles at a ≈ 0.9 (R − o); when
    /// the simulation does, idle is ~0 and a decays.
    fn adapt(&mut self, now: Instant) {
        let idle = self
            .frame_end
            .map_or(Duration::ZERO, |end| now.saturating_duration_since(end));
        let next = self.allowance.mul_f64(0.9) + idle.mul_f64(0.8);
        self.allowance = next.clamp(self.per_frame, self.per_frame * Self::MAX_GROWTH);
    }
}

impl Default for StepBudget {
    fn default() -> Self {
        let per_frame = Duration::from_millis(25);
        StepBudget {
            per_frame,
            allowance: per_frame,
            frame_start: None,
            frame_end: None,
            dropped_seconds: 0.0,
            step_seconds: None,
        }
    }
}

/// Sizes the fixed tick from dt, before the fixed loop of each frame.
pub(crate) fn plan_tick(
    params: Res<SimParams>,
    mut plan: ResMut<TickPlan>,
    mut time: ResMut<Time<Fixed>>,
    mut budget: ResMut<StepBudget>,
) {
    let now = Instant::now();
    budget.adapt(now);
    budget.frame_start = Some(now);
    // A bad dt (written by user code) is reported by the input check; the tick keeps its
    // size until it is mended.
    if inputs::check_params(&params).is_some() || inputs::check_tick_plan(&plan).is_some() {
        return;
    }
    let steps = (plan.target_tick_seconds / params.dt)
        .round()
        .clamp(1.0, 1e6) as u32;
    let steps = budget.steps_that_fit().map_or(steps, |fit| steps.min(fit));
    if plan.steps_per_tick != steps {
        plan.steps_per_tick = steps;
    }
    let Ok(tick) = Duration::try_from_secs_f64(params.dt * steps as f64) else {
        return;
    };
    if time.timestep() != tick && tick > Duration::ZERO {
        time.set_timestep(tick);
    }
}

/// Drops the rest of the frame's simulated time once the frame's budget is spent.
pub(crate) fn enforce_step_budget(mut budget: ResMut<StepBudget>, mut time: ResMut<Time<Fixed>>) {
    let Some(start) = budget.frame_start else {
        return;
    };
    if start.elapsed() > budget.allowance {
        let overstep = time.overstep();
        if overstep > Duration::ZERO {
            budget.dropped_seconds += overstep.as_secs_f64();
            time.discard_overstep(overstep);
        }
    }
}

/// Notes when the frame's work ended, for [`StepBudget::adapt`].
pub(crate) fn mark_frame_end(mut budget: ResMut<StepBudget>) {
    budget.frame_end = Some(Instant::now());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames paced by a slow renderer (120 ms, 10 ms of other work) let the simulation use
    /// most of the frame; frames paced by the simulation itself bring the allowance back down.
    #[test]
    fn the_step_allowance_follows_idle_time() {
        let mut budget = StepBudget::default();
        let mut now = Instant::now();
        let run_frame = |budget: &mut StepBudget, now: &mut Instant, frame: Duration| {
            budget.adapt(*now);
            let busy = (budget.allowance + Duration::from_millis(10)).min(frame);
            budget.frame_end = Some(*now + busy);
            *now += frame.max(busy);
        };
        for _ in 0..100 {
            run_frame(&mut budget, &mut now, Duration::from_millis(120));
        }
        let ms = budget.allowance.as_secs_f64() * 1e3;
        assert!(
            (80.0..=100.0).contains(&ms),
            "render-bound allowance {ms} ms"
        );
        for _ in 0..100 {
            run_frame(&mut budget, &mut now, Duration::ZERO);
        }
        assert_eq!(budget.allowance, budget.per_frame);
    }

    /// A tick is cut to its share of the frame's allowance once steps are seen to be slow, and
    /// grows back to its simulated length when they are fast again; never below one step.
    #[test]
    fn a_slow_step_shortens_the_tick() {
        let mut app = crate::headless_app();
        app.world_mut().resource_mut::<SimParams>().paused = true;
        // The steps of the next tick, and how many fit the allowance the frame had (which
        // follows the idle time between frames, so it is read back, not assumed).
        let per_tick = |app: &mut App, step: Option<f64>| {
            app.world_mut().resource_mut::<StepBudget>().step_seconds = step;
            app.update();
            let allowance = app.world().resource::<StepBudget>().allowance.as_secs_f64();
            let fit = step.map(|s| (allowance * StepBudget::TICK_SHARE / s).floor() as u32);
            (app.world().resource::<TickPlan>().steps_per_tick, fit)
        };
        let dt = app.world().resource::<SimParams>().dt;
        let full = (TickPlan::default().target_tick_seconds / dt).round() as u32;
        assert_eq!(per_tick(&mut app, None).0, full);
        // 2.5 ms a step: half of a 25–100 ms allowance holds 5 to 20 steps of the 83.
        let (steps, fit) = per_tick(&mut app, Some(2.5e-3));
        assert!(steps < full);
        assert_eq!(Some(steps), fit);
        assert_eq!(per_tick(&mut app, Some(10.0)).0, 1);
        assert_eq!(per_tick(&mut app, Some(1e-7)).0, full);
    }

    /// The step time follows the ticks: a moving average of their wall time per step.
    #[test]
    fn the_step_time_follows_the_ticks() {
        let mut budget = StepBudget::default();
        budget.note_steps(Duration::from_millis(10), 0);
        assert_eq!(budget.step_seconds(), None);
        budget.note_steps(Duration::from_millis(10), 10);
        assert_eq!(budget.step_seconds(), Some(1e-3));
        for _ in 0..50 {
            budget.note_steps(Duration::from_millis(10), 100);
        }
        assert!((budget.step_seconds().unwrap() - 1e-4).abs() < 1e-9);
    }
}
