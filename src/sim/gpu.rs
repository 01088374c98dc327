//! The world's step on the graphics card (the `gpu` feature): what of a scene the card runs,
//! and stepping the world's packed state there ([`advance_on_gpu`]).
//!
//! The card runs symplectic and explicit Euler with gravity, external forces, damping, the
//! ground, pins, dashpots, tearing, and the obstacles and the ground's contact with friction
//! and restitution ([`crate::solver::gpu`]). A scene that uses anything else stays on the CPU,
//! and [`unsupported`] says what keeps it there, in words a user reads.

use super::obstacles::Obstacles;
use super::params::{SimClock, SimParams, SimStatus};
use super::solver::Solver;
use super::watch::EnergyPeak;
use crate::solver::gpu::{ExplicitMethod, ExplicitSettings, Gpu, GpuStep, Precision, TearSettings};
use crate::solver::method::Integrator;
use bevy::ecs::world::World;

/// The most steps recorded into one submit by [`advance_on_gpu`]; the state is read back (and
/// the energy peak taken) after each.
pub const STEPS_PER_READ: u64 = 1000;

/// What in the world's scene the card does not run, as a sentence; `None` when it runs all of
/// it. Read after the state is packed ([`super::pack`]).
pub fn unsupported(world: &World) -> Option<String> {
    let params = world.resource::<SimParams>();
    let method = match params.integrator {
        Integrator::SymplecticEuler | Integrator::ExplicitEuler => None,
        other => Some(format!(
            "the GPU runs symplectic and explicit Euler, not {other}"
        )),
    };
    let mut what = vec![];
    if let Some(c) = params.contact {
        if c.particles && c.radius > 0.0 {
            what.push("contact between particles".to_string());
        }
        if c.outlines && c.radius > 0.0 {
            what.push("contact by outlines".to_string());
        }
    }
    if let Some(m) = GpuStep::unsupported(&world.resource::<Solver>().state) {
        what.push(m);
    }
    let materials = (!what.is_empty())
        .then(|| format!("the GPU does not run {} yet", crate::readable::list(&what)));
    match (method, materials) {
        (None, None) => None,
        (Some(a), None) | (None, Some(a)) => Some(a),
        (Some(a), Some(b)) => Some(format!("{a}, and {b}")),
    }
}

/// The card's step settings from the world's parameters; tearing looks every
/// `steps_per_tick` steps, at the end of each of the CPU's ticks.
pub fn settings(params: &SimParams, steps_per_tick: u64) -> ExplicitSettings {
    ExplicitSettings {
        method: match params.integrator {
            Integrator::ExplicitEuler => ExplicitMethod::ExplicitEuler,
            _ => ExplicitMethod::SymplecticEuler,
        },
        dt: params.dt,
        gravity: params.gravity,
        damping: params.damping,
        ground: params.ground,
        contact: params.contact,
        tear: params.tear.map(|strain| TearSettings {
            strain,
            every: steps_per_tick.min(u32::MAX as u64) as u32,
        }),
    }
}

/// The steps a fixed tick runs at the world's dt ([`super::advance`]'s rule).
fn steps_per_tick(world: &World) -> u64 {
    let dt = world.resource::<SimParams>().dt;
    let target = world
        .resource::<super::params::TickPlan>()
        .target_tick_seconds;
    ((target / dt).round() as u64).clamp(1, 10_000)
}

/// Steps the world's packed state `steps` times on `gpu` in `precision`, in submits of up to
/// [`STEPS_PER_READ`] steps, reading it back after each: the clock advances, an
/// [`EnergyPeak`] present takes the energy after each submit (not after every step, as on the
/// CPU), and a non-finite state stops the run as a blow-up does on the CPU (at the end of the
/// submit it was found in). Returns the steps taken, or why the card could not run the
/// scene (nothing is stepped then).
pub fn advance_on_gpu(
    world: &mut World,
    gpu: &Gpu,
    precision: Precision,
    steps: u64,
) -> Result<u64, String> {
    if let Some(why) = unsupported(world) {
        return Err(why);
    }
    let params = world.resource::<SimParams>().clone();
    // The obstacles as the tick gathers them from their entities (and writes back after).
    world
        .run_system_cached(super::obstacles::gather_obstacles)
        .map_err(|e| e.to_string())?;
    let mut card = {
        let solver = world.resource::<Solver>();
        let obstacles = world.resource::<Obstacles>().placed();
        let settings = settings(&params, steps_per_tick(world));
        GpuStep::new(gpu, &solver.state, &settings, obstacles, precision)
            .map_err(|e| e.to_string())?
    };
    let mut taken = 0;
    let mut torn = vec![];
    while taken < steps {
        let n = (steps - taken).min(STEPS_PER_READ);
        card.place(world.resource::<Obstacles>().placed());
        card.run(n as u32);
        if taken + n == steps {
            // The CPU tears at the end of every tick, its run's last (shorter) one too.
            card.tear_now();
        }
        {
            let mut solver = world.resource_mut::<Solver>();
            card.read_into(&mut solver.state)
                .map_err(|e| e.to_string())?;
            // A spring the card broke carries nothing from here on (its entity goes at the
            // end of the run, and the next tick repacks without it).
            for i in card.torn_springs().map_err(|e| e.to_string())? {
                solver.state.springs[i].k = 0.0;
                torn.push(i);
            }
        }
        let contacts = card.contacts().map_err(|e| e.to_string())?;
        {
            // The obstacles move on the CPU too, in f64, as the step moves them
            // (`Placed::advance` after each step's contact pass).
            let mut o = world.resource_mut::<Obstacles>();
            for p in &mut o.placed {
                if p.pose.velocity != bevy::math::DVec2::ZERO || p.pose.angular_velocity != 0.0 {
                    for _ in 0..n {
                        p.advance(params.dt);
                    }
                }
            }
            o.contacts = crate::solver::Contacts {
                surfaces: contacts,
                ..Default::default()
            };
        }
        taken += n;
        let mut clock = world.resource_mut::<SimClock>();
        clock.steps += n;
        clock.time += n as f64 * params.dt;
        let clock = *clock;
        let solver = world.resource::<Solver>();
        let energy = solver.energy(params.gravity).total();
        let finite = !solver.non_finite;
        if let Some(mut peak) = world.get_resource_mut::<EnergyPeak>() {
            peak.max = Some(peak.max.map_or(energy, |m| m.max(energy)));
        }
        if !finite {
            *world.resource_mut::<SimStatus>() = SimStatus::BlewUp {
                step: clock.steps,
                time: clock.time,
            };
            world.resource_mut::<SimParams>().paused = true;
            break;
        }
    }
    world
        .run_system_cached(super::obstacles::write_back_obstacles)
        .map_err(|e| e.to_string())?;
    // The entities take the card's state, as the tick's write-back gives them the CPU's: the
    // next repack (the torn springs' removal is one) builds from them.
    if !world.resource::<Solver>().non_finite {
        world
            .run_system_cached(super::sync::sync_from_solver)
            .map_err(|e| e.to_string())?;
    }
    if !torn.is_empty() {
        let entities: Vec<_> = {
            let solver = world.resource::<Solver>();
            torn.iter()
                .filter_map(|&i| solver.spring_entity_in(world, i))
                .collect()
        };
        world.resource_mut::<super::params::Tearing>().pending = entities;
        world
            .run_system_cached(super::tear::remove_torn_springs)
            .map_err(|e| e.to_string())?;
        // Repacked now, as the next tick would, so that the state reads without them.
        super::pack(world)?;
    }
    Ok(taken)
}
