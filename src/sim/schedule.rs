//! When the simulation runs: the fixed-tick sets, the per-step schedule and its ordered sets.
//!
//! At the assignment's dt = 1e-4 s the simulation needs 10 000 steps per simulated second, far
//! more than frames. So, as avian runs its substeps, one fixed tick ([`PhysicsSystems::Step`])
//! runs the [`PhysicsStep`] schedule [`TickPlan::steps_per_tick`] times in a tight loop with a
//! single-threaded executor; the ECS sync happens once per tick, not per step.

use super::advance::{check_tick, sync_tick};
use super::budget::{enforce_step_budget, mark_frame_end, plan_tick};
use super::inputs;
use super::params::*;
use super::solver::Solver;
use super::sync::sync_from_solver;
use super::tear;
use crate::solver::step;
use bevy::app::{RunFixedMainLoop, RunFixedMainLoopSystems};
use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, SingleThreadedExecutor};
use bevy::prelude::*;
use std::time::Instant;

pub use super::advance::{advance, check, pack, steps_per_tick};
pub use super::budget::StepBudget;
#[allow(deprecated)]
pub use super::sets::{PhysicsSet, StepSet};
pub use super::sets::{PhysicsStep, PhysicsSystems, StepSystems};

/// Whether the particle passes after the forces run fused, as one sweep over the particles
/// (the default), or as separate systems, one per set.
///
/// Fused, [`StepSystems::Advance`] runs one loop that does for each particle what the
/// separate passes do, in their order: the Euler methods' kick (their `Integrate`), damping,
/// ground contact and the position update. It is assembled from what is on: without damping
/// it does no damping work, without a ground no contact test (each combination is its own
/// loop). The result is the separate passes' bit for bit (a test checks every integrator);
/// the arrays are read and written once a step instead of once per pass.
///
/// The sets stay in their order either way. A system that must see the state *between* the
/// passes (after the kick and before damping, say) turns fusion off:
///
/// ```
/// # use hooke::sim::ParticleSweep;
/// let mut app = hooke::headless_app();
/// app.insert_resource(ParticleSweep { fused: false });
/// ```
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParticleSweep {
    /// One fused sweep (true), or one system per pass.
    pub fused: bool,
}

impl Default for ParticleSweep {
    fn default() -> Self {
        ParticleSweep { fused: true }
    }
}

/// The headless simulation: components, solver, fixed-tick systems. No window, no rendering.
pub struct SimPlugin;

impl Plugin for SimPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SimParams>()
            .init_resource::<SimClock>()
            .init_resource::<SimStatus>()
            .init_resource::<PassCounts>()
            .init_resource::<Tearing>()
            .init_resource::<Solver>()
            .init_resource::<super::pull::Attraction>()
            .init_resource::<TickPlan>()
            .init_resource::<ParticleSweep>()
            .init_resource::<StepBudget>()
            .init_resource::<CgSettings>()
            .init_resource::<SolverThreads>()
            .init_resource::<super::obstacles::Obstacles>()
            .init_resource::<super::components::Serials>();

        app.configure_sets(
            FixedUpdate,
            (
                PhysicsSystems::Prepare,
                PhysicsSystems::Step,
                PhysicsSystems::Writeback,
                PhysicsSystems::Tear,
            )
                .chain(),
        )
        .add_systems(
            FixedUpdate,
            (
                (
                    check_tick,
                    // The solver synced first: an adapter's obstacles gathered after hooke's
                    // (`sim::avian`) read the particles' bounds from it.
                    (sync_tick, super::obstacles::gather_obstacles)
                        .chain()
                        .run_if(inputs::inputs_valid),
                )
                    .chain()
                    .in_set(PhysicsSystems::Prepare),
                run_steps
                    .in_set(PhysicsSystems::Step)
                    .run_if(simulation_running)
                    .run_if(not(on_card)),
                // Only when the solver changed since: a paused tick writes nothing back (14 ms a
                // tick on the 2000² cloth).
                sync_from_solver
                    .in_set(PhysicsSystems::Writeback)
                    .run_if(inputs::inputs_valid)
                    .run_if(resource_changed::<Solver>),
                super::sync::write_back_rest_lengths
                    .in_set(PhysicsSystems::Writeback)
                    .run_if(inputs::inputs_valid)
                    .run_if(scene_has_plastic_springs),
                super::obstacles::write_back_obstacles
                    .in_set(PhysicsSystems::Writeback)
                    .run_if(inputs::inputs_valid)
                    .run_if(resource_changed::<super::obstacles::Obstacles>),
                (
                    tear::find_torn_springs
                        .run_if(tear::tearing_enabled)
                        .run_if(not(card_tears)),
                    tear::remove_torn_springs.run_if(tear::tears_pending),
                )
                    .chain()
                    .in_set(PhysicsSystems::Tear),
                enforce_step_budget.after(PhysicsSystems::Writeback),
                super::watch::watch_energy
                    .after(PhysicsSystems::Writeback)
                    .run_if(resource_exists::<super::watch::EnergyWatch>),
            ),
        )
        .add_systems(
            RunFixedMainLoop,
            plan_tick.in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop),
        )
        .add_systems(Last, mark_frame_end);
        #[cfg(feature = "gpu")]
        app.init_resource::<super::gpu::CardStep>().add_systems(
            FixedUpdate,
            (
                super::gpu::receive_from_card
                    .in_set(PhysicsSystems::Prepare)
                    .after(check_tick)
                    .before(sync_tick),
                tear::remove_springs_torn_on_card
                    .in_set(PhysicsSystems::Prepare)
                    .after(super::gpu::receive_from_card)
                    .before(sync_tick)
                    .run_if(tear::tears_pending),
                super::gpu::decide_device
                    .in_set(PhysicsSystems::Prepare)
                    .after(sync_tick)
                    .after(super::obstacles::gather_obstacles)
                    .run_if(inputs::inputs_valid),
                super::gpu::run_steps_on_card
                    .in_set(PhysicsSystems::Step)
                    .run_if(simulation_running)
                    .run_if(super::gpu::on_card),
            ),
        );
        // The card decides once an adapter's colliders have joined the tick's obstacles.
        #[cfg(all(feature = "gpu", feature = "avian"))]
        app.configure_sets(
            FixedUpdate,
            super::avian::AvianSystems::Colliders.before(super::gpu::decide_device),
        );

        app.init_schedule(PhysicsStep);
        app.edit_schedule(PhysicsStep, |schedule| {
            schedule
                .set_executor(SingleThreadedExecutor::new())
                .set_build_settings(ScheduleBuildSettings {
                    ambiguity_detection: LogLevel::Error,
                    ..default()
                })
                .configure_sets(
                    (
                        StepSystems::Actuate,
                        StepSystems::Forces,
                        StepSystems::Integrate,
                        StepSystems::Damping,
                        StepSystems::Ground,
                        StepSystems::Advance,
                        StepSystems::Collide,
                        StepSystems::Yield,
                    )
                        .chain(),
                )
                .add_systems((
                    (
                        // The pull toward a point first: it sets external forces.
                        super::pull::pull,
                        // Body and spring forces in one parallel region, or the body forces
                        // alone when no spring force is read.
                        forces.run_if(scene_has_springs.and_then(integrator_reads_spring_forces)),
                        apply_gravity.run_if(not(
                            scene_has_springs.and_then(integrator_reads_spring_forces)
                        )),
                    )
                        .chain()
                        .in_set(StepSystems::Forces),
                    // The Euler methods' kick is part of the fused sweep when that runs.
                    integrate
                        .run_if(not(euler_method.and_then(sweep_fused)))
                        .in_set(StepSystems::Integrate),
                    damp_velocity
                        .run_if(damping_enabled.and_then(not(sweep_fused)))
                        .in_set(StepSystems::Damping),
                    ground_contact
                        .run_if(ground_enabled.and_then(not(sweep_fused)))
                        .in_set(StepSystems::Ground),
                    (
                        advance_positions.run_if(not(sweep_fused)),
                        particle_sweep.run_if(sweep_fused),
                    )
                        .chain()
                        .in_set(StepSystems::Advance),
                    collide.run_if(contact_enabled).in_set(StepSystems::Collide),
                    (
                        move_obstacles.run_if(obstacles_move),
                        actuate.run_if(scene_has_muscles),
                    )
                        .chain()
                        .in_set(StepSystems::Actuate),
                    yield_springs
                        .run_if(scene_has_plastic_springs)
                        .in_set(StepSystems::Yield),
                    super::watch::track_energy_peak
                        .run_if(resource_exists::<super::watch::EnergyPeak>)
                        .after(StepSystems::Yield),
                ));
        });
    }
}

// ---- run conditions: a pass whose feature the scene does not use does not run ----

/// Run condition: not paused and healthy.
pub fn simulation_running(params: Res<SimParams>, status: Res<SimStatus>) -> bool {
    !params.paused && *status == SimStatus::Running
}

/// Run condition: the scene has springs (or gas bodies, whose forces the force pass adds).
pub fn scene_has_springs(solver: Res<Solver>) -> bool {
    !solver.springs.is_empty() || !solver.materials().gas().is_empty()
}

/// Run condition: some spring is a muscle.
pub fn scene_has_muscles(solver: Res<Solver>) -> bool {
    !solver.materials().muscles().is_empty()
}

/// Run condition: some spring is plastic.
pub fn scene_has_plastic_springs(solver: Res<Solver>) -> bool {
    !solver.materials().plastic().is_empty()
}

/// Run condition: the integrator reads the spring forces at the start of the step (projective
/// dynamics and XPBD read only the body forces, so the force pass's spring sweep does not run).
pub fn integrator_reads_spring_forces(params: Res<SimParams>) -> bool {
    params.integrator.reads_spring_forces()
}

/// Only the selected integrator's system runs.
pub fn integrator_is(which: Integrator) -> impl Fn(Res<SimParams>) -> bool + Clone {
    move |params: Res<SimParams>| params.integrator == which
}

/// Run condition: the integrator is explicit or symplectic Euler, whose update is the kick.
pub fn euler_method(params: Res<SimParams>) -> bool {
    step::motion(params.integrator).kicks()
}

/// Run condition: the particle passes run as one fused sweep ([`ParticleSweep`]).
pub fn sweep_fused(sweep: Res<ParticleSweep>) -> bool {
    sweep.fused
}

/// Run condition: damping is on (μ ≠ 0) and the damping pass applies it (BDF2 takes it
/// inside its solve).
pub fn damping_enabled(params: Res<SimParams>) -> bool {
    pass_damping(&params) != 0.0
}

/// The μ the damping pass (or the fused sweep) applies: 0 for the methods that take the drag
/// inside their solve ([`Integrator::drags_in_solve`]).
pub fn pass_damping(params: &SimParams) -> f64 {
    if params.solve_drag() != 0.0 {
        0.0
    } else {
        params.damping
    }
}

/// Run condition: the scene has a ground that the ground pass clamps (with contact set, the
/// contact pass handles the ground instead, with the particles' radius and friction).
pub fn ground_enabled(params: Res<SimParams>) -> bool {
    clamped_ground(&params).is_some()
}

/// Run condition: the contact pass has something to do: obstacles, or contact with a ground.
pub fn contact_enabled(
    params: Res<SimParams>,
    obstacles: Res<super::obstacles::Obstacles>,
) -> bool {
    contact_needed(&params, &obstacles)
}

fn contact_needed(params: &SimParams, obstacles: &super::obstacles::Obstacles) -> bool {
    surroundings(params, obstacles).active()
}

/// What the contact pass works against this step.
fn surroundings<'a>(
    params: &SimParams,
    obstacles: &'a super::obstacles::Obstacles,
) -> crate::solver::Surroundings<'a> {
    crate::solver::Surroundings {
        obstacles: &obstacles.placed,
        ground: params.ground,
        settings: params.contact,
        reactions: obstacles.feel.then_some(&obstacles.reactions),
    }
}

/// The ground the step's own clamp handles (the ground pass, the fused sweep, XPBD's substeps):
/// none when contact is set, since the contact pass then does.
pub fn clamped_ground(params: &SimParams) -> Option<f64> {
    params.ground.filter(|_| params.contact.is_none())
}

// ---- the passes: each system runs one of the core's passes ([`crate::solver::step`]) ----

fn apply_gravity(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    step::body_forces(&mut solver.state, params.gravity, &threads);
    n.gravity += 1;
}

fn forces(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    let s = &mut *solver;
    step::forces(&mut s.state, &mut s.work, params.gravity, &threads);
    n.gravity += 1;
    n.springs += 1;
    n.materials += s.state.materials().exerts_forces() as u64;
}

/// The muscles' rest lengths for the step about to start.
fn actuate(mut solver: ResMut<Solver>, clock: Res<SimClock>, mut n: ResMut<PassCounts>) {
    step::actuate(&mut solver.state, clock.time);
    n.actuate += 1;
}

/// Plastic springs yield.
fn yield_springs(mut solver: ResMut<Solver>, params: Res<SimParams>, mut n: ResMut<PassCounts>) {
    step::yield_springs(&mut solver.state, params.dt);
    n.yield_springs += 1;
}

/// The integrator's update, for whichever integrator the run condition selected.
fn integrate(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    mut obstacles: ResMut<super::obstacles::Obstacles>,
    settings: Res<CgSettings>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    let method = step::Method {
        integrator: params.integrator,
        dt: params.dt,
        gravity: params.gravity,
        ground: clamped_ground(&params),
        iterations: params.iterations,
        cg: settings.0,
        pair_radius: params
            .contact
            .filter(|c| c.particles && c.radius > 0.0)
            .map(|c| c.radius),
        drag: params.solve_drag(),
    };
    let s = &mut *solver;
    if !method.integrator.reads_spring_forces() {
        // Projective dynamics and XPBD take the materials' forces inside their solves.
        n.materials += s.state.materials().exerts_forces() as u64;
    }
    let around = surroundings(&params, &obstacles);
    if let Err(e) = step::integrate(&mut s.state, &mut s.work, &method, Some(&around), &threads) {
        // Only when memory runs out: with m > 0 and k >= 0 (checked) projective dynamics'
        // M + h²L is positive definite. The step is refused like a blow-up, which pauses with
        // the last good state.
        tracing::error!("hooke: {e}");
        s.state.non_finite = true;
    }
    if !s.work.solved_motion().is_empty() {
        // The bodies the solve moved among its unknowns: the contact pass meets them moving
        // as the solve moved them, and they move after it to where the solve left them.
        obstacles
            .bypass_change_detection()
            .move_as_solved(s.work.solved_motion());
    }
    n.integrate += 1;
}

fn damp_velocity(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    step::damp(&mut solver.state, params.damping, params.dt, &threads);
    n.damping += 1;
}

fn ground_contact(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    let Some(ground) = clamped_ground(&params) else {
        return;
    };
    let (integrator, dt) = (params.integrator, params.dt);
    step::ground(&mut solver.state, integrator, dt, ground, &threads);
    n.ground += 1;
}

fn advance_positions(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    step::advance(&mut solver.state, params.integrator, params.dt, &threads);
    n.advance += 1;
}

/// The fused particle sweep ([`ParticleSweep`]): the Euler kick, damping, ground and the
/// position update in one pass, with only the parts the scene uses.
fn particle_sweep(
    mut solver: ResMut<Solver>,
    params: Res<SimParams>,
    obstacles: Res<super::obstacles::Obstacles>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    let (integrator, dt) = (params.integrator, params.dt);
    if integrator == Integrator::ExplicitEuler && contact_needed(&params, &obstacles) {
        // The contact pass needs the velocity the step moves with (the separate kick keeps it).
        step::keep_start_velocity(&mut solver.state);
    }
    let around = surroundings(&params, &obstacles);
    let s = &mut *solver;
    step::ready_outlines(&s.state, &mut s.work, dt, &around);
    let (mu, ground) = (pass_damping(&params), clamped_ground(&params));
    let sweep = step::sweep(&mut solver.state, integrator, dt, mu, ground, &threads);
    n.integrate += sweep.motion.kicks() as u64;
    n.damping += sweep.decay.is_some() as u64;
    n.ground += sweep.ground.is_some() as u64;
    n.advance += 1;
    n.sweeps += 1;
}

/// The contact pass, then the obstacles that stood where the step began (those whose bodies
/// feel the particles) move by their velocities.
fn collide(
    mut solver: ResMut<Solver>,
    mut obstacles: ResMut<super::obstacles::Obstacles>,
    params: Res<SimParams>,
    threads: Res<SolverThreads>,
    mut n: ResMut<PassCounts>,
) {
    let around = surroundings(&params, &obstacles);
    let (integrator, dt, g) = (params.integrator, params.dt, params.gravity);
    let s = &mut *solver;
    let contacts = step::collide(
        &mut s.state,
        &mut s.work,
        integrator,
        dt,
        g,
        &around,
        &threads,
    );
    let o = obstacles.bypass_change_detection();
    o.contacts = contacts;
    if o.feel {
        // The bodies' masses take their part of the step's contacts (the particles'
        // velocities give some back), then the notes are summed for the adapter.
        o.reactions
            .close_step(o.placed.len(), &mut s.state.v, &s.state.inv_mass);
    }
    // Those that stood where the step began move now.
    if o.advance(dt, false) {
        obstacles.set_changed();
    }
    n.contact += 1;
}

/// The obstacles that the step moves by their velocities move to where the step ends, first:
/// its contact sees them there, each particle's path read in its frame
/// ([`crate::solver::contact::pass`]; XPBD's substeps each see them where the substep ends).
/// (Not a body that feels the particles: those move after the contact, [`collide`].)
fn move_obstacles(mut obstacles: ResMut<super::obstacles::Obstacles>, params: Res<SimParams>) {
    if obstacles.bypass_change_detection().advance(params.dt, true) {
        obstacles.set_changed();
    }
}

/// Run condition: an obstacle that the step moves moves.
fn obstacles_move(obstacles: Res<super::obstacles::Obstacles>) -> bool {
    obstacles.any_moves_first()
}

/// Whether this tick's steps go to the graphics card (never without the `gpu` feature).
fn on_card(#[cfg(feature = "gpu")] card: Option<Res<super::gpu::CardStep>>) -> bool {
    #[cfg(feature = "gpu")]
    return super::gpu::on_card(card);
    #[cfg(not(feature = "gpu"))]
    false
}

/// Whether the card tears this tick's springs (its state read on demand), so that the CPU
/// does not look at a state that lags it.
fn card_tears(#[cfg(feature = "gpu")] card: Option<Res<super::gpu::CardStep>>) -> bool {
    #[cfg(feature = "gpu")]
    return card.is_some_and(|c| c.active() && c.on_demand);
    #[cfg(not(feature = "gpu"))]
    false
}

/// Runs this tick's steps; stops at the first step that produced a non-finite value.
fn run_steps(world: &mut World) {
    let steps = world.resource::<TickPlan>().steps_per_tick;
    let threads = world.resource::<SolverThreads>().clone();
    let springs = world.resource::<Solver>().spring_count();
    let (start, before) = (Instant::now(), world.resource::<SimClock>().steps);
    threads.run(springs, || {
        world.schedule_scope(PhysicsStep, |world, schedule| {
            for _ in 0..steps {
                schedule.run(world);
                let dt = world.resource::<SimParams>().dt;
                let mut clock = world.resource_mut::<SimClock>();
                clock.steps += 1;
                clock.time += dt;
                let clock = *clock;
                if world.resource::<Solver>().non_finite {
                    *world.resource_mut::<SimStatus>() = SimStatus::BlewUp {
                        step: clock.steps,
                        time: clock.time,
                    };
                    world.resource_mut::<SimParams>().paused = true;
                    break;
                }
            }
        })
    });
    let taken = world.resource::<SimClock>().steps - before;
    let mut budget = world.resource_mut::<StepBudget>();
    budget.note_steps(start.elapsed(), taken);
}
