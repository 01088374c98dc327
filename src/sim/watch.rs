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
//! its fastest mode. While the user holds a particle or applies an external force, work is
//! being done on the system, so every tick counts as an edit.
//!
//! By the time the energy passes that bound, the last few ticks are already a tangle (cloth32
//! under explicit Euler at μ = 0, k = 4e5: 1.7e6 J one tick before the stop, 4.8e3 J at rest).
//! So the watch keeps the state at the last edit and, since then, one every
//! [`KEEP_EVERY`] ticks (the last [`KEPT`]), each with its energy. [`restore_last_good_state`]
//! goes back to the newest one whose energy stayed within [`NEAR`] of the reference,
//! `E ≤ E_ref + NEAR · (|E_ref| + 1 J)`: a healthy run with damping and ground never gains
//! energy, and the symplectic methods' bounded energy error stays below 5 % at the step sizes
//! the stability panel calls safe, while an instability grows exponentially and is past that
//! within a few of its periods. When none is that near, the state at the edit is used.

use super::components::{Particle, Position, Velocity};
use super::params::{SimClock, SimParams, SimStatus, SolverThreads};
use super::solver::Solver;
use bevy::math::DVec2;
use bevy::prelude::*;
use std::collections::VecDeque;

/// Relative energy rise past which the watch stops the simulation.
pub const GROWTH: f64 = 10.0;
/// Relative energy rise within which a kept state counts as good.
pub const NEAR: f64 = 0.05;
/// Ticks between kept states (0.1 s of simulated time at the app's tick of 1/120 s).
pub const KEEP_EVERY: u64 = 12;
/// How many interval states are kept.
pub const KEPT: usize = 8;

/// Present = the largest total energy at the end of any step is kept (`hooke run` reports it
/// as `energy_max`, so that an energy gain shows without a plot). Costs an energy evaluation a
/// step, a pass over the particles and the springs on the solver's threads
/// ([`crate::solver::State::energy_on`]): on the 256² cloth about half a step's time (0.28 ms
/// against 0.55 ms on two threads of an Intel Xeon, 2026-12-05). Its time is kept apart, so
/// that a run's throughput is the step's own.
///
/// ```
/// # use hooke::sim::watch::EnergyPeak;
/// let mut app = hooke::headless_app();
/// app.init_resource::<EnergyPeak>();
/// ```
#[derive(Resource, Debug, Default, Clone, Copy)]
pub struct EnergyPeak {
    /// The largest total energy at the end of a step so far, J (`None` before the first): the
    /// particles' and the rigid bodies' ([`Self::bodies`]).
    pub max: Option<f64>,
    /// Wall time spent evaluating it, s.
    pub seconds: f64,
    /// The particles' total energy at the end of the last step, J.
    pub particles: f64,
    /// The rigid bodies' energy at the end of the last tick, J (zero without any: with the
    /// `avian` feature, the coupling notes it after avian's step), counted in the total.
    pub bodies: f64,
}

impl EnergyPeak {
    /// Takes the particles' total energy `e` at the end of a step (with the bodies' last) into
    /// the peak, and answers whether it could: an energy that is not finite is no figure to
    /// keep, and the state it came from has blown up even where that state is still finite
    /// (speeds past 1e154 m/s), so its callers, on the CPU and on the card, refuse the step as
    /// they refuse a NaN.
    pub fn note(&mut self, e: f64) -> bool {
        self.particles = e;
        let total = e + self.bodies;
        if total.is_finite() {
            self.max = Some(self.max.map_or(total, |m| m.max(total)));
        }
        e.is_finite()
    }

    /// Takes the rigid bodies' energy `e` at the end of a tick, with the particles' of the same
    /// tick, into the peak.
    pub fn note_bodies(&mut self, e: f64) {
        self.bodies = e;
        let total = self.particles + e;
        if total.is_finite() {
            self.max = Some(self.max.map_or(total, |m| m.max(total)));
        }
    }
}

/// After every step, with [`EnergyPeak`] present: its total energy against the peak.
///
/// An energy that is not finite, from a state that still is (speeds past 1e154 m/s: rope
/// under explicit Euler at 1/60 s), is a blow-up as surely as a NaN, and the step is refused
/// like one: without this, such a run ended "finite" with positions of 1e151 m.
pub(crate) fn track_energy_peak(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut peak: ResMut<EnergyPeak>,
) {
    let clock = std::time::Instant::now();
    let e = solver.energy_now(params.gravity, &threads).total();
    if !peak.note(e) {
        solver.non_finite = true;
    }
    peak.seconds += clock.elapsed().as_secs_f64();
}

/// Present = the watch is on (the app turns it on; headless runs report energies instead).
///
/// ```
/// # use hooke::sim::watch::EnergyWatch;
/// let mut app = hooke::headless_app();
/// app.init_resource::<EnergyWatch>(); // stop runs whose energy grows, keep states to go back to
/// ```
#[derive(Resource, Debug, Default, Clone)]
pub struct EnergyWatch {
    /// Energy at the last edit, and the solver shape it was taken for.
    reference: Option<(f64, usize, usize)>,
    /// The state at the last edit.
    pub at_edit: Option<GoodState>,
    /// States kept since the last edit, oldest first.
    pub recent: VecDeque<GoodState>,
    ticks: u64,
}

/// A state to go back to: positions and velocities by particle entity.
#[derive(Debug, Clone)]
pub struct GoodState {
    /// Particle entities, in the solver's order.
    pub entities: Vec<Entity>,
    /// Their positions, m.
    pub x: Vec<DVec2>,
    /// Their velocities, m/s.
    pub v: Vec<DVec2>,
    /// The clock then.
    pub clock: SimClock,
    /// The total energy then, J.
    pub energy: f64,
}

impl GoodState {
    /// Copies the solver's state into `reuse`'s buffers, or new ones.
    fn capture(solver: &Solver, clock: SimClock, energy: f64, reuse: Option<GoodState>) -> Self {
        let mut s = reuse.unwrap_or(GoodState {
            entities: vec![],
            x: vec![],
            v: vec![],
            clock,
            energy,
        });
        s.entities.clone_from(&solver.entities);
        s.x.clone_from(&solver.x);
        s.v.clone_from(&solver.v);
        (s.clock, s.energy) = (clock, energy);
        s
    }
}

impl EnergyWatch {
    /// The energy past which the watch stops a run from the reference `reference`.
    pub fn bound(reference: f64) -> f64 {
        reference + GROWTH * (reference.abs() + 1.0)
    }

    /// The energy below which a kept state counts as good.
    pub fn near(reference: f64) -> f64 {
        reference + NEAR * (reference.abs() + 1.0)
    }

    /// The state [`restore_last_good_state`] would go back to.
    pub fn best(&self) -> Option<&GoodState> {
        let (reference, ..) = self.reference?;
        let near = Self::near(reference);
        self.recent
            .iter()
            .rev()
            .find(|s| s.energy <= near)
            .or(self.at_edit.as_ref())
    }
}

/// Runs after each tick's writeback (when the watch is on).
pub fn watch_energy(
    mut watch: ResMut<EnergyWatch>,
    solver: Res<Solver>,
    mut params: ResMut<SimParams>,
    clock: Res<SimClock>,
    mut status: ResMut<SimStatus>,
    threads: Res<SolverThreads>,
) {
    let shape = (solver.particle_count(), solver.spring_count());
    let energy = solver.energy_now(params.gravity, &threads).total();
    let interacting = solver.kinematic > 0 || solver.external_active;
    let edited = params.is_changed()
        || interacting
        || watch.reference.is_none_or(|(_, n, s)| (n, s) != shape);
    if edited || *status != SimStatus::Running {
        if *status == SimStatus::Running && energy.is_finite() && !solver.non_finite {
            watch.reference = Some((energy, shape.0, shape.1));
            let reuse = watch.at_edit.take();
            watch.at_edit = Some(GoodState::capture(&solver, *clock, energy, reuse));
            watch.recent.clear();
            watch.ticks = 0;
        }
        return;
    }
    let Some((reference, ..)) = watch.reference.filter(|_| !params.paused) else {
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
    watch.ticks += 1;
    if watch.ticks.is_multiple_of(KEEP_EVERY) && energy.is_finite() && !solver.non_finite {
        let reuse = (watch.recent.len() >= KEPT)
            .then(|| watch.recent.pop_front())
            .flatten();
        let kept = GoodState::capture(&solver, *clock, energy, reuse);
        watch.recent.push_back(kept);
    }
}

/// Puts the best kept state (see the module docs) back into the particles, clears the blow-up
/// and stays paused. Returns false when there is no state to go back to.
pub fn restore_last_good_state(world: &mut World) -> bool {
    let Some(good) = world
        .get_resource::<EnergyWatch>()
        .and_then(|w| w.best().cloned())
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
        w.recent.clear();
    }
    true
}
