//! Blow-up detection beyond non-finite values, and the last good state to go back to.
//!
//! Without external work the total energy of a mass-spring system with damping and ground
//! contact never rises. So, once per fixed tick, the watch compares the energy with the energy
//! at the last *edit* (a scene load, a parameter change, a particle or spring added or
//! changed, a restore), E_ref, and pauses the simulation with [`SimStatus::EnergyGrew`] when
//!
//! `E > E_ref + GROWTH · (|E_ref| + 1 J)`, with `GROWTH = 10`:
//!
//! a rise that no stable run produces, yet one an unstable run passes within a few periods of
//! its fastest mode. While the state is healthy, the end of every tick is kept as the last good
//! state; [`restore_last_good_state`] writes it back.

use super::components::{Particle, Position, Velocity};
use super::params::{SimClock, SimParams, SimStatus};
use super::solver::Solver;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Relative energy rise past which the watch stops the simulation.
pub const GROWTH: f64 = 10.0;

/// Present = the watch is on (the app turns it on; headless runs report energies instead).
#[derive(Resource, Debug, Default, Clone)]
pub struct EnergyWatch {
    /// Energy at the last edit, and the solver shape it was taken for.
    reference: Option<(f64, usize, usize)>,
    pub last_good: Option<GoodState>,
}

#[derive(Debug, Clone)]
pub struct GoodState {
    pub entities: Vec<Entity>,
    pub x: Vec<DVec2>,
    pub v: Vec<DVec2>,
    pub clock: SimClock,
}

impl EnergyWatch {
    pub fn bound(reference: f64) -> f64 {
        reference + GROWTH * (reference.abs() + 1.0)
    }
}

/// Runs after each tick's writeback (when the watch is on).
pub fn watch_energy(
    mut watch: ResMut<EnergyWatch>,
    solver: Res<Solver>,
    mut params: ResMut<SimParams>,
    clock: Res<SimClock>,
    mut status: ResMut<SimStatus>,
) {
    let shape = (solver.particle_count(), solver.spring_count());
    let energy = solver.energy(params.gravity).total();
    let edited = params.is_changed() || watch.reference.is_none_or(|(_, n, s)| (n, s) != shape);
    if edited || *status != SimStatus::Running {
        if *status == SimStatus::Running && energy.is_finite() {
            watch.reference = Some((energy, shape.0, shape.1));
        }
        return;
    }
    let Some((reference, ..)) = watch.reference else {
        return;
    };
    let bound = EnergyWatch::bound(reference);
    if energy > bound {
        *status = SimStatus::EnergyGrew {
            step: clock.steps,
            time: clock.time,
            energy,
            bound,
        };
        params.paused = true;
        return;
    }
    if energy.is_finite() && !solver.non_finite {
        // Every tick: reuse the previous copy's memory rather than allocating anew.
        let good = watch.last_good.get_or_insert_with(|| GoodState {
            entities: vec![],
            x: vec![],
            v: vec![],
            clock: *clock,
        });
        good.entities.clone_from(&solver.entities);
        good.x.clone_from(&solver.x);
        good.v.clone_from(&solver.v);
        good.clock = *clock;
    }
}

/// Puts the last good state back into the particles, clears the blow-up and stays paused.
/// Returns false when there is no good state to go back to.
pub fn restore_last_good_state(world: &mut World) -> bool {
    let Some(good) = world
        .get_resource::<EnergyWatch>()
        .and_then(|w| w.last_good.clone())
    else {
        return false;
    };
    for (i, &e) in good.entities.iter().enumerate() {
        if let Ok(mut entity) = world.get_entity_mut(e)
            && entity.contains::<Particle>()
        {
            entity.insert((Position(good.x[i]), Velocity(good.v[i])));
        }
    }
    *world.resource_mut::<SimClock>() = good.clock;
    *world.resource_mut::<SimStatus>() = SimStatus::Running;
    world.resource_mut::<SimParams>().paused = true;
    world.resource_mut::<Solver>().non_finite = false;
    if let Some(mut w) = world.get_resource_mut::<EnergyWatch>() {
        w.reference = None;
    }
    true
}
