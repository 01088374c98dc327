//! When the simulation runs: the fixed-tick sets, the per-step schedule and its ordered sets.
//!
//! At the assignment's dt = 1e-4 s the simulation needs 10 000 steps per simulated second, far
//! more than frames. So, as avian runs its substeps, one fixed tick ([`PhysicsSystems::Step`])
//! runs the [`PhysicsStep`] schedule [`TickPlan::steps_per_tick`] times in a tight loop with a
//! single-threaded executor; the ECS sync happens once per tick, not per step.

use super::inputs;
use super::params::*;
use super::solver::Solver;
use super::sync::{sync_from_solver, sync_into_solver};
use super::tear;
use crate::solver::step;
use bevy::app::{FixedMain, RunFixedMainLoop, RunFixedMainLoopSystems};
use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};
use bevy::prelude::*;
use bevy::time::Fixed;
use std::time::{Duration, Instant};

/// The sets of a fixed tick, in `FixedUpdate`, in this order. A user system joins the tick by
/// going into one of them, or between two (`.after(PhysicsSystems::Writeback)`):
///
/// ```
/// # use bevy::prelude::*;
/// # use hooke::sim::{PhysicsSystems, Solver, advance};
/// #[derive(Resource, Default)]
/// struct Lowest(f64);
///
/// // Reads the state of the tick just taken.
/// fn lowest_point(solver: Res<Solver>, mut lowest: ResMut<Lowest>) {
///     lowest.0 = solver.x().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
/// }
///
/// let rope = hooke::scene::presets::resolve("rope").unwrap();
/// let mut app = hooke::running_app(&rope).unwrap();
/// app.init_resource::<Lowest>();
/// app.add_systems(FixedUpdate, lowest_point.after(PhysicsSystems::Writeback));
/// advance(app.world_mut(), 1000);
/// assert!(app.world().resource::<Lowest>().0 > 0.0); // above the ground
/// ```
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PhysicsSystems {
    /// 1. Check what users wrote ([`super::inputs`]) and bring ECS edits into the solver:
    ///    write [`super::ExternalForce`], positions and the like before it.
    Prepare,
    /// 2. Run this tick's steps (the [`PhysicsStep`] schedule, [`TickPlan::steps_per_tick`]
    ///    times).
    Step,
    /// 3. Write results back into the components.
    Writeback,
    /// 4. Break overstretched springs ([`super::tear`]; only while tearing is on).
    Tear,
}

/// The old name of [`PhysicsSystems`] (Bevy names system sets `...Systems` since 0.17).
#[deprecated(since = "0.1.0", note = "renamed to `PhysicsSystems`")]
pub type PhysicsSet = PhysicsSystems;

/// One step of size dt. Its sets ([`StepSystems`]) run in order, with a single-threaded
/// executor, and the schedule is built with ambiguity detection at the error level: a system
/// added to it without an order against the systems it conflicts with fails at build time
/// instead of racing silently.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct PhysicsStep;

/// The passes of one step, in [`PhysicsStep`], in this order (`docs/integrators.md`):
///
/// ```
/// # use bevy::prelude::*;
/// # use hooke::sim::{PhysicsStep, Solver, StepSystems, advance};
/// #[derive(Resource, Default)]
/// struct LargestForce(f64);
///
/// // Sees every step's forces before the integrator uses them.
/// fn largest_force(solver: Res<Solver>, mut largest: ResMut<LargestForce>) {
///     let now = solver.f().iter().map(|f| f.length()).fold(0.0, f64::max);
///     largest.0 = largest.0.max(now);
/// }
///
/// let rope = hooke::scene::presets::resolve("rope").unwrap();
/// let mut app = hooke::running_app(&rope).unwrap();
/// app.init_resource::<LargestForce>();
/// app.add_systems(
///     PhysicsStep,
///     largest_force.after(StepSystems::Forces).before(StepSystems::Integrate),
/// );
/// advance(app.world_mut(), 100);
/// assert!(app.world().resource::<LargestForce>().0 > 0.0);
/// ```
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepSystems {
    /// 0. Only with muscles: each muscle's rest length for the step's start time. Runs first,
    ///    before the forces.
    Actuate,
    /// 1. f = m g + f_ext + Σ spring forces at the start-of-step positions.
    Forces,
    /// 2. The integrator's velocity update (and what it needs for the position update).
    Integrate,
    /// 3. v *= exp(-μ dt).
    Damping,
    /// 4. Ground contact on the start-of-step position (implicit Euler and projective
    ///    dynamics: on the end-of-step position, see [`crate::solver::Contact`]).
    Ground,
    /// 5. The position update, x += dt u, with u the integrator's drift velocity; checks
    ///    finiteness.
    Advance,
    /// 6. Contact between particles when [`SimParams::contact`] asks for it
    ///    ([`crate::solver::contact::pairs`]), then with the obstacles, and with the ground when contact
    ///    is set ([`crate::solver::contact`]); then the obstacles move by their velocities.
    ///    Runs only when the scene has obstacles, contact with a ground, or particle pairs.
    Collide,
    /// 7. Only with plastic springs: each strained past its yield moves its rest length toward
    ///    its length ([`crate::sim::Plastic`]).
    Yield,
}

/// The old name of [`StepSystems`].
#[deprecated(since = "0.1.0", note = "renamed to `StepSystems`")]
pub type StepSet = StepSystems;

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
                    actuate
                        .run_if(scene_has_muscles)
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
    obstacles: Res<super::obstacles::Obstacles>,
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

/// The contact pass, then the obstacles move by their velocities.
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
    if o.advance(dt) {
        obstacles.set_changed();
    }
    n.contact += 1;
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
fn enforce_step_budget(mut budget: ResMut<StepBudget>, mut time: ResMut<Time<Fixed>>) {
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
fn mark_frame_end(mut budget: ResMut<StepBudget>) {
    budget.frame_end = Some(Instant::now());
}

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
/// Fails only when the world lacks the [`SimPlugin`] resources.
pub fn pack(world: &mut World) -> Result<(), String> {
    world
        .run_system_cached(sync_into_solver)
        .map_err(|e| format!("cannot pack the solver: {e}"))
}

/// Checks the inputs now, without stepping (the check the first tick would run: every particle
/// and spring of a newly loaded scene), so that a run can time its steps apart from it: on the
/// 2000² cloth (16 M springs) this first check takes about 0.23 s, against 0.03 s a step.
/// The tick runs the same cached system instance, so that it then sees only
/// what changed since. Fails only when the world lacks the [`SimPlugin`] resources.
pub fn check(world: &mut World) -> Result<(), String> {
    world
        .run_system_cached(inputs::check_inputs)
        .map_err(|e| format!("cannot check the inputs: {e}"))
}

/// The tick's input check: [`check`]'s cached system instance.
fn check_tick(world: &mut World) {
    if let Err(e) = check(world) {
        // Only when the world lacks the plugin's resources, which the plugin inserts.
        tracing::error!("hooke: {e}");
    }
}

/// The tick's sync: the same cached system instance as [`pack`]'s, so that the change
/// detection of the two is one. A tick after `pack` sees only what changed since it, instead
/// of every particle and spring as new (which repacked a big scene a second time).
fn sync_tick(world: &mut World) {
    if let Err(e) = pack(world) {
        // Only when the world lacks the plugin's resources, which the plugin inserts.
        tracing::error!("hooke: {e}");
    }
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
