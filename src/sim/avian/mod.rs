//! hooke in an avian2d world (feature `avian`): avian's colliders act on the particles as
//! obstacles, its dynamic bodies take back the impulse of every particle contact, and
//! [`Attachment`]s tie particles to points of bodies, two ways.
//!
//! # One clock
//!
//! hooke's step is avian's step: each fixed tick runs one hooke step of
//! [`SimParams::dt`](crate::sim::SimParams::dt) in `FixedUpdate` and then one avian step of the
//! same length in `FixedPostUpdate` (avian's default schedule), so after N ticks both have taken
//! N steps. The plugin sets the tick to dt ([`TickPlan::target_tick_seconds`]), pauses avian's
//! time whenever hooke is paused or stopped, and copies avian's [`Gravity`] into hooke's
//! gravity: avian's is the one source.
//!
//! # What crosses each tick, in order ([`AvianSystems`])
//!
//! 1. `FixedUpdate`, before [`PhysicsSystems::Prepare`]: [`AvianSystems::Follow`]. Each
//!    attached particle is put at its body's point, with that point's velocity, held
//!    kinematic for the step.
//! 2. In [`PhysicsSystems::Prepare`], after hooke's own obstacles are gathered:
//!    [`AvianSystems::Colliders`]. Every collider whose shapes' bounds meet the particles'
//!    bounds, grown by a step's travel, is added to the tick's obstacles at its body's pose and
//!    velocity, with the body's mass for the contacts' share ([`crate::solver::Inertia`]).
//! 3. hooke's step ([`PhysicsSystems::Step`]) collides the particles with them under the
//!    chosen integrator, and notes the impulse each contact gives
//!    ([`crate::solver::contact::reaction`]).
//! 4. After [`PhysicsSystems::Writeback`]: [`AvianSystems::Push`]. Each dynamic body takes
//!    minus the impulses its colliders gave, at their contact points (linear and angular), and
//!    each attachment's pull, through avian's [`Forces`]. Nothing writes avian's positions.
//! 5. avian steps in `FixedPostUpdate`, with the impulses in its bodies' velocities.
//!
//! `docs/library.md` has the whole account: what is supported under which integrator, and what
//! the feature costs to build.

mod colliders;
mod exchange;

pub use colliders::{ShapeProblem, obstacle_shapes};
pub use exchange::Attachment;

use super::params::{SimParams, SimStatus, TickPlan};
use super::sets::PhysicsSystems;
use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;

/// The coupling's sets in `FixedUpdate`, in the order of the module docs.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AvianSystems {
    /// Attached particles follow their bodies' points (before hooke's
    /// [`PhysicsSystems::Prepare`]).
    Follow,
    /// avian's colliders near the particles become this tick's obstacles (in
    /// [`PhysicsSystems::Prepare`]).
    Colliders,
    /// The dynamic bodies take the contacts' impulses and the attachments' pulls (after
    /// [`PhysicsSystems::Writeback`]).
    Push,
}

/// Couples hooke ([`crate::SimPlugin`]) with avian2d (`PhysicsPlugins`), which the app adds
/// itself, in avian's default schedule (`FixedPostUpdate`).
///
/// ```
/// use avian2d::prelude::*;
/// let mut app = hooke::headless_app();
/// app.add_plugins((
///     PhysicsPlugins::default(),
///     hooke::sim::avian::HookeAvianPlugin,
/// ));
/// // A dynamic box for the particles to push.
/// app.world_mut().spawn((RigidBody::Dynamic, Collider::rectangle(0.2, 0.2)));
/// ```
pub struct HookeAvianPlugin;

impl Plugin for HookeAvianPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Coupling>()
            .configure_sets(
                FixedUpdate,
                (
                    AvianSystems::Follow.before(PhysicsSystems::Prepare),
                    AvianSystems::Colliders.in_set(PhysicsSystems::Prepare),
                    AvianSystems::Push.after(PhysicsSystems::Writeback),
                ),
            )
            .add_systems(
                RunFixedMainLoop,
                one_clock
                    .in_set(bevy::app::RunFixedMainLoopSystems::BeforeFixedMainLoop)
                    .before(super::budget::plan_tick),
            )
            .add_systems(
                FixedUpdate,
                (
                    (one_gravity, exchange::follow).in_set(AvianSystems::Follow),
                    colliders::gather
                        .in_set(AvianSystems::Colliders)
                        .after(super::obstacles::gather_obstacles),
                    exchange::push.in_set(AvianSystems::Push),
                ),
            )
            .add_systems(
                FixedPostUpdate,
                note_bodies_energy.after(avian2d::schedule::PhysicsSystems::Last),
            );
    }
}

/// What the coupling found and did on the last tick, for a status line or a test.
#[derive(Resource, Debug, Default, Clone)]
pub struct Coupling {
    /// avian's colliders that acted on the particles as obstacles.
    pub colliders: usize,
    /// The dynamic bodies in the world (the ones the particles push back) after the last tick.
    pub dynamic: usize,
    /// Their energy after the last tick, J ([`bodies_energy`]).
    pub energy: f64,
    /// Colliders whose shape hooke cannot take (a height field, a triangle mesh), each named
    /// once with why; they do not touch the particles.
    pub skipped: Vec<(Entity, ShapeProblem)>,
    /// The sum of the impulses the particles gave each dynamic body on the last tick, N·s.
    pub impulses: Vec<(Entity, Vec2)>,
    /// hooke's own tick length while bodies set it to dt, to give back when none is left.
    own_tick: Option<f64>,
}

/// A rigid body's motion as hooke reads it: its centre of mass in the world, and its
/// velocities, the same at every point of it as v + ω × (p − c).
#[derive(Debug, Clone, Copy)]
struct Motion {
    com: DVec2,
    linear: DVec2,
    angular: f64,
}

/// What hooke reads of a rigid body's motion: where it is, how it is turned, its velocities
/// and its centre of mass.
type BodyMotion<'a> = (
    &'a Position,
    &'a Rotation,
    Option<&'a LinearVelocity>,
    Option<&'a AngularVelocity>,
    Option<&'a ComputedCenterOfMass>,
);

/// What hooke reads of a rigid body, for the colliders' gather and the bodies' energy: its
/// kind and motion; its mass, moment of inertia and gravity scale; its damping; and the mass
/// and shape it was given (which stand for the first two before avian's first step computes
/// them).
type BodyRead<'a> = (
    &'a RigidBody,
    BodyMotion<'a>,
    (
        Option<&'a ComputedMass>,
        Option<&'a ComputedAngularInertia>,
        Option<&'a GravityScale>,
    ),
    (Option<&'a LinearDamping>, Option<&'a AngularDamping>),
    (Option<&'a Mass>, Option<&'a Collider>),
);

impl Motion {
    /// The motion of a body from avian's components (a missing velocity is none; a missing
    /// centre of mass is the body's origin).
    fn of((at, turn, v, w, com): BodyMotion) -> Motion {
        Motion {
            com: centre_of_mass(at, turn, com),
            linear: v.map_or(DVec2::ZERO, |v| v.0.as_dvec2()),
            angular: w.map_or(0.0, |w| w.0 as f64),
        }
    }

    /// The velocity of the body's material at the world point `p`.
    fn velocity_at(&self, p: DVec2) -> DVec2 {
        self.linear + self.angular * (p - self.com).perp()
    }
}

/// A body's centre of mass in the world.
fn centre_of_mass(at: &Position, turn: &Rotation, com: Option<&ComputedCenterOfMass>) -> DVec2 {
    (at.0 + *turn * com.map_or(Vec2::ZERO, |c| c.0)).as_dvec2()
}

/// One clock: a tick is one step of hooke's dt, avian's time runs only while hooke steps.
/// Without a rigid body (an app that has the plugin but whose scene has none) nothing is
/// coupled: hooke's tick is its own again and avian's time stands still (and the colliders'
/// gather leaves the steps noting no contact for anyone).
fn one_clock(
    params: Res<SimParams>,
    status: Res<SimStatus>,
    bodies: Query<(), With<RigidBody>>,
    mut coupling: ResMut<Coupling>,
    mut plan: ResMut<TickPlan>,
    mut physics: ResMut<Time<Physics>>,
) {
    let coupled = !bodies.is_empty();
    if coupled {
        if coupling.own_tick.is_none() {
            coupling.own_tick = Some(plan.target_tick_seconds);
        }
        if params.dt.is_finite() && params.dt > 0.0 && plan.target_tick_seconds != params.dt {
            plan.target_tick_seconds = params.dt;
        }
    } else if let Some(own) = coupling.own_tick.take() {
        plan.target_tick_seconds = own;
    }
    let running = coupled && !params.paused && *status == SimStatus::Running;
    if running && physics.is_paused() {
        physics.unpause();
    } else if !running && !physics.is_paused() {
        physics.pause();
    }
}

/// Readies the clocks for one tick run by hand ([`crate::sim::advance`]): the fixed clock
/// moved on by `dt` and made the generic `Time`, as Bevy's fixed loop does, so that avian's
/// step in the tick is dt long. Returns the clock to put back after the tick.
pub(crate) fn enter_tick(world: &mut World, dt: f64) -> Time {
    let before = *world.resource::<Time>();
    // `advance` stops at a dt no clock holds before it comes here.
    let step = std::time::Duration::try_from_secs_f64(dt).unwrap_or_default();
    let mut fixed = world.resource_mut::<Time<Fixed>>();
    fixed.set_timestep(step);
    fixed.advance_by(step);
    let generic = fixed.as_generic();
    *world.resource_mut::<Time>() = generic;
    if world.resource::<Time<Physics>>().is_paused() {
        world.resource_mut::<Time<Physics>>().unpause();
    }
    before
}

/// Whether rigid bodies are coupled in this world: the plugin is in and some body exists.
pub(crate) fn coupled(world: &World) -> bool {
    world.contains_resource::<Coupling>() && has_bodies(world)
}

/// A dynamic body's energy in gravity `g`, J: its kinetic energy, ½M|v|² + ½Iω², and its
/// potential, −M g·c (c its centre of mass; zero at the origin, as the particles' is). `None`
/// for a body that does not move by its own dynamics (static or kinematic).
fn body_energy(
    (kind, motion, (mass, inertia, scale), _, (given, shape)): BodyRead,
    g: DVec2,
) -> Option<f64> {
    if !kind.is_dynamic() {
        return None;
    }
    let mut m = mass.map_or(0.0, |m| m.value() as f64);
    let mut i = inertia.map_or(0.0, |i| i.value() as f64);
    if m == 0.0 {
        // Before avian's first step has computed them: the mass the body was given and its
        // shape's inertia at that mass.
        m = given.map_or(0.0, |g| g.0 as f64);
        if let Some(unit) = shape.map(|c| c.mass_properties(1.0))
            && unit.mass > 0.0
        {
            i = unit.angular_inertia as f64 * m / unit.mass as f64;
        }
    }
    let motion = Motion::of(motion);
    let fall = g * scale.map_or(1.0, |s| s.0 as f64);
    Some(
        0.5 * m * motion.linear.length_squared() + 0.5 * i * motion.angular * motion.angular
            - m * fall.dot(motion.com),
    )
}

/// The dynamic rigid bodies' energy, J: each body's kinetic energy, ½M|v|² + ½Iω², and its
/// potential in avian's gravity, −M g·c (c its centre of mass; zero at the origin, as the
/// particles' is). With it a run's total energy is the whole world's: the particles' alone hid
/// a crate thrown out of its net, which took its energy with it.
pub fn bodies_energy(world: &mut World) -> f64 {
    let g = world
        .get_resource::<Gravity>()
        .map_or(DVec2::ZERO, |g| g.0.as_dvec2());
    let mut bodies = world.query::<BodyRead>();
    bodies.iter(world).filter_map(|b| body_energy(b, g)).sum()
}

/// After avian's step: the dynamic bodies counted and their energy taken, for the panel and
/// into the run's peak (with the particles' of the same tick) where a run keeps one.
fn note_bodies_energy(
    bodies: Query<BodyRead>,
    gravity: Option<Res<Gravity>>,
    mut coupling: ResMut<Coupling>,
    peak: Option<ResMut<super::watch::EnergyPeak>>,
) {
    let g = gravity.map_or(DVec2::ZERO, |g| g.0.as_dvec2());
    let (mut dynamic, mut e) = (0, 0.0);
    for b in &bodies {
        if let Some(energy) = body_energy(b, g) {
            dynamic += 1;
            e += energy;
        }
    }
    if (coupling.dynamic, coupling.energy) != (dynamic, e) {
        (coupling.dynamic, coupling.energy) = (dynamic, e);
    }
    if dynamic > 0
        && let Some(mut peak) = peak
    {
        peak.note_bodies(e);
    }
}

/// Whether the world has a rigid body.
pub(crate) fn has_bodies(world: &World) -> bool {
    world
        .try_query_filtered::<(), With<RigidBody>>()
        .is_some_and(|mut q| q.iter(world).next().is_some())
}

/// One gravity: avian's, copied into hooke's parameters when it differs.
fn one_gravity(gravity: Res<Gravity>, mut params: ResMut<SimParams>) {
    let g = gravity.0.as_dvec2();
    if params.gravity != g {
        params.gravity = g;
    }
}
