//! Ticks run by hand, for headless use (the CLI, the reports, tests): [`advance`] runs the
//! app's fixed-tick systems tick by tick without a frame loop; [`pack`] and [`check`] run a
//! tick's sync and input check alone, as the tick does, through the same cached systems.

use super::inputs;
use super::params::{SimClock, SimParams, TickPlan};
use super::sync::sync_into_solver;
use bevy::app::FixedMain;
use bevy::prelude::*;

/// The steps in one of [`advance`]'s ticks: with rigid bodies coupled, one (a tick is one step
/// of both engines); otherwise [`TickPlan::target_tick_seconds`] of simulated time. Two runs
/// of `advance` in whole ticks end where one run of their sum does, bit for bit.
pub fn steps_per_tick(world: &World) -> u64 {
    #[cfg(feature = "avian")]
    if super::avian::coupled(world) {
        return 1;
    }
    let dt = world.resource::<SimParams>().dt;
    world.resource::<TickPlan>().steps_at(dt)
}

/// Runs `steps` steps of the simulation directly, through the same fixed-tick systems the app
/// runs (sync, step sets, writeback, and the energy watch when present), in ticks of the app's
/// size ([`TickPlan::target_tick_seconds`] of simulated time), for headless use: the CLI,
/// benchmarks, tests. Returns the number of steps taken: fewer when paused or when a step blew up.
pub fn advance(world: &mut World, steps: u64) -> u64 {
    let start = world.resource::<SimClock>().steps;
    #[cfg(feature = "avian")]
    let (coupled, dt) = (
        super::avian::coupled(world),
        world.resource::<SimParams>().dt,
    );
    let per_tick = steps_per_tick(world);
    // A dt that avian's clock cannot hold (NaN, not above 0, over `MAX_DT`) is the input
    // check's to name before the clock takes it: the tick would check it only after.
    #[cfg(feature = "avian")]
    if coupled && super::params::dt_problem(dt).is_some() {
        check_tick(world);
        return 0;
    }
    let mut remaining = steps;
    while remaining > 0 {
        let n = remaining.min(per_tick);
        world.resource_mut::<TickPlan>().steps_per_tick = n as u32;
        #[cfg(feature = "avian")]
        if coupled {
            let before = super::avian::enter_tick(world, dt);
            world.run_schedule(FixedMain);
            *world.resource_mut::<Time>() = before;
            let taken = world.resource::<SimClock>().steps - start;
            if taken < steps - remaining + n {
                break;
            }
            remaining -= n;
            continue;
        }
        world.run_schedule(FixedMain);
        let taken = world.resource::<SimClock>().steps - start;
        if taken < steps - remaining + n {
            break;
        }
        remaining -= n;
    }
    world.resource::<SimClock>().steps - start
}

/// Brings the world's particles and springs into the solver now, without stepping (the same
/// sync the first tick would run), so that its state can be read before the first step.
/// Fails only when the world lacks the [`SimPlugin`](super::SimPlugin) resources.
pub fn pack(world: &mut World) -> Result<(), String> {
    world
        .run_system_cached(sync_into_solver)
        .map_err(|e| format!("cannot pack the solver: {e}"))
}

/// Checks the inputs now, without stepping (the check the first tick would run: every particle
/// and spring of a newly loaded scene), so that a run can time its steps apart from it: on the
/// 2000² cloth (16 M springs) this first check takes about 0.23 s, against 0.03 s a step.
/// The tick runs the same cached system instance, so that it then sees only what changed
/// since. Fails only when the world lacks the [`SimPlugin`](super::SimPlugin) resources.
pub fn check(world: &mut World) -> Result<(), String> {
    world
        .run_system_cached(inputs::check_inputs)
        .map_err(|e| format!("cannot check the inputs: {e}"))
}

/// The tick's input check: [`check`]'s cached system instance.
pub(crate) fn check_tick(world: &mut World) {
    if let Err(e) = check(world) {
        // Only when the world lacks the plugin's resources, which the plugin inserts.
        tracing::error!("hooke: {e}");
    }
}

/// The tick's sync: the same cached system instance as [`pack`]'s, so that the change
/// detection of the two is one. A tick after `pack` sees only what changed since it, instead
/// of every particle and spring as new (which repacked a big scene a second time).
pub(crate) fn sync_tick(world: &mut World) {
    if let Err(e) = pack(world) {
        // Only when the world lacks the plugin's resources, which the plugin inserts.
        tracing::error!("hooke: {e}");
    }
}
